//! `cablecell run TASK`

use std::path::Path;

use cablecell::orchestrator::record::{GraspRecord, RunReport};
use cablecell::orchestrator::{RunOutcome, RunRecord, Runner};
use cablecell::task::{load_cell, load_task};

use super::Status;

pub fn run(task_path: &Path, cell_path: &Path, seed: Option<u64>, json: bool) -> Status {
    let (task, cell) = match (load_task(task_path), load_cell(cell_path)) {
        (Ok(task), Ok(cell)) => (task, cell),
        (task, cell) => {
            for error in [task.err(), cell.err()].into_iter().flatten() {
                eprintln!("error: {error}");
            }
            return Status::BadInput;
        }
    };
    let seed = seed.or(task.task.seed).unwrap_or_else(rand::random);
    let mut runner = match Runner::for_task(&task, &cell, seed) {
        Ok(runner) => runner,
        Err(error) => {
            eprintln!("error: {}: {error}; nothing was moved", cell_path.display());
            return Status::DeviceFault;
        }
    };
    if json {
        runner.run_to_end();
    } else {
        println!(
            "task {} on {} (seed {seed})",
            task.task.name, cell.cell.name
        );
        let (target, tolerance) = (task.target, task.tolerance);
        println!(
            "target n* = {:+.3} mm, α* = {:+.4} rad; tolerance ±{} mm, ±{} rad",
            target.n_mm, target.alpha_rad, tolerance.n_mm, tolerance.alpha_rad
        );
        let (mut transitions, mut grasps) = (0, 0);
        while runner.step() {
            let record = runner.record();
            record.grasps[grasps..].iter().for_each(print_grasp);
            grasps = record.grasps.len();
            for (i, t) in record.transitions.iter().enumerate().skip(transitions) {
                let entered_s = i.checked_sub(1).map_or(0.0, |p| record.transitions[p].t_s);
                println!(
                    "{:9.3} s  {:>11} → {:<11}  ({} took {:.3} s)",
                    t.t_s,
                    t.from,
                    t.to,
                    t.from,
                    t.t_s - entered_s
                );
            }
            transitions = record.transitions.len();
        }
    }
    let record = runner.into_record();
    if json {
        match serde_json::to_string_pretty(&RunReport::new(&record)) {
            Ok(text) => println!("{text}"),
            Err(error) => eprintln!("error: cannot write the report as JSON: {error}"),
        }
    } else {
        print_outcome(&record);
    }
    match record.outcome {
        Some(RunOutcome::Success { .. }) => Status::Success,
        Some(RunOutcome::Failed { .. }) => Status::TaskFailed,
        Some(RunOutcome::Fault { .. }) | None => Status::DeviceFault,
    }
}

fn print_grasp(grasp: &GraspRecord) {
    let name = match grasp.attempt {
        0 => "trial grasp".to_owned(),
        k => format!("regrasp {k}"),
    };
    match (&grasp.fit, &grasp.estimated_error) {
        (Some(fit), Some(error)) => println!(
            "{name:>13}  estimate n {:+7.3} mm  α {:+.4} rad   error n {:+7.3} mm  α {:+.4} rad",
            fit.line().offset_mm,
            fit.line().alpha_rad,
            error.n_mm,
            error.alpha_rad
        ),
        _ => println!(
            "{name:>13}  no estimate (peak Δv {:.3} V)",
            grasp.map.peak_dv_v()
        ),
    }
    if let Some(truth) = &grasp.truth {
        println!(
            "{:>13}  true     n {:+7.3} mm  α {:+.4} rad   error n {:+7.3} mm  α {:+.4} rad",
            "", truth.line.offset_mm, truth.line.alpha_rad, truth.error.n_mm, truth.error.alpha_rad
        );
    }
}

fn print_outcome(record: &RunRecord) {
    let tolerance = &record.tolerance;
    match &record.outcome {
        Some(RunOutcome::Success { regrasps }) => println!(
            "success: within tolerance (|n| ≤ {} mm, |α| ≤ {} rad) after {regrasps} regrasp(s)",
            tolerance.n_mm, tolerance.alpha_rad
        ),
        Some(RunOutcome::Failed { reason }) => println!("task failed: {reason}"),
        Some(RunOutcome::Fault {
            state,
            device,
            error,
        }) => {
            let device = device.map(|d| format!(" ({d})")).unwrap_or_default();
            println!("device fault in {state}{device}: {error}; the cell was made safe");
            for problem in &record.safe_stop_problems {
                println!("  could not make safe: {problem}");
            }
        }
        None => println!("the run stopped before it ended"),
    }
}
