//! What the REPL shows of a run: its state and the next command, the arm's
//! pose, the latest tactile map with its fit.

use crate::cli::output::outln;
use std::path::Path;

use cablecell::orchestrator::{Command, Runner};
use cablecell::perception::tactile::{Estimate, TAXEL_COLS, TAXEL_ROWS};
use cablecell::plot::save;
use cablecell::plot::tactile::TactileFigure;
use cablecell::record::{GraspRecord, RunRecord};

use super::super::run::{attempt_name, print_outcome, print_transition};
use super::map::draw_map;
use super::session::Loaded;

/// In a final state with nothing left to carry out.
pub(super) fn run_over(runner: &Runner) -> bool {
    runner.state().is_final() && runner.pending_command().is_none()
}

pub(super) fn next_command(runner: &Runner) -> String {
    runner
        .pending_command()
        .map(|command| format!("; next: {}", command_name(command)))
        .unwrap_or_default()
}

fn command_name(command: &Command) -> &'static str {
    match command {
        Command::Prepare { .. } => "prepare (reference and open the gripper, read the bias frames)",
        Command::Detect => "detect the cable",
        Command::MoveTo { .. } => "move to the standoff pose",
        Command::Grasp { .. } => "descend and grasp",
        Command::ReadTactile { .. } => "read the tactile frames",
        Command::Regrasp { .. } => "release, move by T_corr, grasp again",
        Command::Probe { .. } => "release, move to the search's next pose, grasp",
        Command::SafeStop { .. } => "safe stop (stop the arm, open the jaws)",
    }
}

pub(super) fn show_state(loaded: &Loaded) {
    let runner = loaded.driver.runner();
    let record = runner.record();
    outln!(
        "state {} at {:.3} s{}",
        runner.state().name(),
        runner.now_s(),
        next_command(runner)
    );
    let first = record.transitions.len().saturating_sub(8);
    if first > 0 {
        outln!("  ({first} earlier transitions)");
    }
    for (i, t) in record.transitions.iter().enumerate().skip(first) {
        print_transition(record, i, t);
    }
    if let Some(entered) = record.transitions.last() {
        outln!(
            "  in {} for {:.3} s",
            entered.to,
            runner.now_s() - entered.t_s
        );
    }
    if record.outcome.is_some() {
        print_outcome(record);
    }
}

pub(super) fn show_pose(loaded: &mut Loaded) -> Result<(), String> {
    let base_from_tcp = loaded
        .driver
        .base_from_tcp()
        .map_err(|e| format!("the arm did not answer: {e}"))?;
    outln!("arm TCP in base now:      {}", pose_text(&base_from_tcp));
    if let Some((name, grasp)) = latest_grasp(loaded.driver.runner().record()) {
        outln!(
            "at the latest grasp ({name}): {}",
            pose_text(&grasp.base_from_tcp)
        );
    }
    Ok(())
}

fn pose_text(pose: &nalgebra::Isometry3<f64>) -> String {
    let t = pose.translation.vector;
    let (roll, pitch, yaw) = pose.rotation.euler_angles();
    format!(
        "x {:+9.3} y {:+9.3} z {:+9.3} mm  roll {:+8.3} pitch {:+8.3} yaw {:+8.3} deg",
        t.x,
        t.y,
        t.z,
        roll.to_degrees(),
        pitch.to_degrees(),
        yaw.to_degrees()
    )
}

/// The latest grasp whose pad was read, with its name.
fn latest_grasp(record: &RunRecord) -> Option<(String, &GraspRecord)> {
    let grasp = record.latest_grasp()?;
    // A search's misses all come before the trial grasp.
    let name = if record.grasps.is_empty() {
        "search miss".to_owned()
    } else {
        attempt_name(grasp.attempt)
    };
    Some((name, grasp))
}

/// The latest tactile map with its fit, as text; with `file`, also drawn
/// there as the paper's Fig. 7 (`cablecell plot tactile`'s figure).
pub(super) fn show_tactile(loaded: &Loaded, file: Option<&Path>) -> Result<(), String> {
    let record = loaded.driver.runner().record();
    let (name, grasp) = latest_grasp(record)
        .ok_or("no tactile map yet: the first one is read after the trial grasp")?;
    let fit_config = loaded.driver.runner().plan().fit;
    let pitch_mm = fit_config.pitch_mm;
    let line = grasp.fit.as_ref().map(Estimate::line);
    let centroids: Vec<(f64, f64)> = match &grasp.fit {
        Some(Estimate::Centroids(fit)) => fit.centroids.iter().map(|c| (c.x_mm, c.y_mm)).collect(),
        _ => Vec::new(),
    };
    outln!(
        "{name} at {:.3} s: mean Δv, peak {:.3} V (shading ∝ Δv; o centroid, * fitted line)",
        grasp.t_s,
        grasp.map.peak_dv_v()
    );
    for row in draw_map(&grasp.map, pitch_mm, line, &centroids) {
        outln!("  |{row}|");
    }
    outln!("Δv (mV), rows c1j (top, +y) to c5j, columns ci1 (left) to ci5 (+x):");
    for row in 0..TAXEL_ROWS {
        let values: Vec<String> = (0..TAXEL_COLS)
            .map(|col| format!("{:7.1}", grasp.map.dv_v[row][col] * 1000.0))
            .collect();
        outln!("  {}", values.join(""));
    }
    match (&grasp.fit, line) {
        (Some(fit), Some(line)) => {
            let name = match fit {
                Estimate::Centroids(_) => "centroids",
                Estimate::Ridge(_) => "ridge",
                Estimate::Oracle { .. } => "oracle",
            };
            outln!(
                "fitted line ({name}): n {:+.3} mm, α {:+.4} rad",
                line.n_mm,
                line.alpha_rad
            );
        }
        _ => outln!("no fitted line: the fit failed"),
    }
    if let Some(truth) = &grasp.truth {
        outln!(
            "true line:            n {:+.3} mm, α {:+.4} rad",
            truth.line.n_mm,
            truth.line.alpha_rad
        );
    }
    if let Some(file) = file {
        let title = format!(
            "Tactile map at the {name}, {} seed {}",
            record.task, record.seed
        );
        let truth = grasp.truth.as_ref().map(|t| t.line);
        TactileFigure::new(grasp.map, &fit_config, truth, title)
            .and_then(|figure| save(&figure, file))
            .map_err(|e| e.to_string())?;
        outln!("drew the map in {}", file.display());
    }
    Ok(())
}
