//! `cablecell replay FILE`

use std::path::Path;

use cablecell::geometry::LineInSensor;
use cablecell::perception::tactile::Estimator;
use cablecell::recording::replay::{Refit, Replay};
use cablecell::recording::{Recording, Topic};

use super::Status;

pub fn replay(path: &Path, estimators: &[Estimator]) -> Status {
    let recording = match Recording::read(path) {
        Ok(recording) => recording,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    if let Some(why) = &recording.truncated {
        println!(
            "truncated recording ({why}): showing the {} messages before the cut",
            recording.messages.len()
        );
    }
    let replay = match Replay::of(&recording) {
        Ok(replay) => replay,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    let run = &replay.run;
    println!(
        "task {} on {} (seed {}), estimator {}; {} messages",
        run.task,
        run.cell,
        run.seed,
        estimator_name(run.estimator),
        recording.messages.len()
    );
    let counts: Vec<String> = Topic::ALL
        .iter()
        .map(|topic| format!("{} {}", topic.name(), recording.count(*topic)))
        .collect();
    println!("channels: {}", counts.join(", "));
    println!("timeline:");
    let mut entered_s = 0.0;
    for t in &replay.transitions {
        println!(
            "{:9.3} s  {:>11} → {:<11}  ({} took {:.3} s)",
            t.t_s,
            t.from,
            t.to,
            t.from,
            t.t_s - entered_s
        );
        entered_s = t.t_s;
    }
    for estimator in estimators {
        let refits = replay.refit(*estimator);
        println!(
            "{} again on the recorded frames ({} grasps):",
            estimator_name(*estimator),
            refits.len()
        );
        refits.iter().for_each(print_refit);
    }
    Status::Success
}

fn print_refit(refit: &Refit) {
    let name = match refit.attempt {
        0 => "trial grasp".to_owned(),
        k => format!("regrasp {k}"),
    };
    let line_text =
        |line: &LineInSensor| format!("n {:+7.3} mm  α {:+.4} rad", line.offset_mm, line.alpha_rad);
    match &refit.line {
        Ok(line) => print!("{name:>13}  now      {}", line_text(line)),
        Err(error) => print!("{name:>13}  now      no estimate: {error}"),
    }
    match refit.error() {
        Some(e) => println!(
            "   vs truth n {:+7.3} mm  α {:+.4} rad",
            e.n_mm, e.alpha_rad
        ),
        None => println!(),
    }
    if let Some(recorded) = &refit.recorded {
        print!("{:>13}  recorded {}", "", line_text(recorded));
        match refit.recorded_error() {
            Some(e) => println!(
                "   vs truth n {:+7.3} mm  α {:+.4} rad",
                e.n_mm, e.alpha_rad
            ),
            None => println!(),
        }
    }
}

fn estimator_name(estimator: Estimator) -> &'static str {
    match estimator {
        Estimator::Centroids => "centroids",
        Estimator::Ridge => "ridge",
        Estimator::Oracle => "oracle",
    }
}
