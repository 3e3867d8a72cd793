//! `cablecell run TASK`

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{SystemTime, UNIX_EPOCH};

use cablecell::cell::load_cell;
use cablecell::orchestrator::Runner;
use cablecell::orchestrator::breakpoint::Breakpoints;
use cablecell::orchestrator::driver::{Driver, Mode, Stop};
use cablecell::perception::shape::Distances;
use cablecell::record::{DetectedCable, RunOutcome, RunRecord};
use cablecell::record::{GraspRecord, RunReport, ShapeErrors, TransitionRecord};
use cablecell::recording::{LiveServer, RecordingTarget};
use cablecell::task::{load_task, load_task_on_cell};

use super::Status;
use super::output::outln;

/// Where a run is recorded: `--record PATH`, else a new file under
/// `runs/`, or nowhere with `--no-record`.
#[derive(Debug, Clone, clap::Args)]
pub struct RecordArgs {
    /// Record the run to this MCAP file (default: runs/TASK-seedN-TIME.mcap).
    #[arg(long, value_name = "PATH")]
    pub record: Option<PathBuf>,
    /// Write no recording.
    #[arg(long, conflicts_with = "record")]
    pub no_record: bool,
    /// Serve the run live to Foxglove (its WebSocket protocol) on ADDR
    /// (default 127.0.0.1:8765); `run` paces a simulated cell to the wall
    /// clock, the REPL by `--pace`.
    #[arg(
        long,
        value_name = "ADDR",
        num_args = 0..=1,
        default_missing_value = cablecell::recording::live::DEFAULT_ADDR
    )]
    pub live: Option<SocketAddr>,
}

impl RecordArgs {
    /// The file to record a run of `task` with `seed` to, if any.
    pub fn path(&self, task: &str, seed: u64) -> Option<PathBuf> {
        if self.no_record {
            return None;
        }
        Some(self.record.clone().unwrap_or_else(|| {
            let ms = SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0, |d| d.as_millis());
            PathBuf::from("runs").join(format!("{task}-seed{seed}-{ms}.mcap"))
        }))
    }

    /// Starts the live view's server if `--live` asks for one, and says
    /// where a viewer connects.
    pub fn live_server(&self) -> Result<Option<Arc<LiveServer>>, String> {
        let Some(addr) = self.live else {
            return Ok(None);
        };
        let server = LiveServer::start(addr).map_err(|error| error.to_string())?;
        eprintln!(
            "live view on ws://{} (Foxglove: Open connection, Foxglove WebSocket)",
            server.addr()
        );
        Ok(Some(Arc::new(server)))
    }
}

/// Starts recording `runner` to `path` and `live`; a failure is reported
/// and the run goes on unrecorded.
pub(super) fn start_recording(
    runner: &mut Runner,
    path: Option<&Path>,
    live: Option<&Arc<LiveServer>>,
) {
    if path.is_none() && live.is_none() {
        return;
    }
    let target = RecordingTarget {
        file: path,
        live: live.cloned(),
        metadata: Default::default(),
    };
    if let Err(error) = runner.start_recording(target, true) {
        eprintln!("warning: {error}; the run goes on unrecorded");
    }
}

/// Finishes `runner`'s recording and says where it is.
pub(super) fn finish_recording(runner: &mut Runner) {
    match runner.finish_recording() {
        Ok(Some(path)) => eprintln!("recorded to {}", path.display()),
        Ok(None) => {}
        Err(error) => eprintln!("warning: {error}"),
    }
}

pub fn run(
    task_path: &Path,
    cell_path: &Path,
    seed: Option<u64>,
    json: bool,
    record: &RecordArgs,
) -> Status {
    // Both files' errors at once; the task is checked against the cell
    // when the cell loads.
    let (task, cell) = match load_cell(cell_path) {
        Ok(cell) => match load_task_on_cell(task_path, cell_path, &cell) {
            Ok(task) => (task, cell),
            Err(error) => {
                eprintln!("error: {error}");
                return Status::BadInput;
            }
        },
        Err(error) => {
            for error in [load_task(task_path).err(), Some(error)]
                .into_iter()
                .flatten()
            {
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
    let live = match record.live_server() {
        Ok(live) => live,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    let path = record.path(&task.task.name, seed);
    start_recording(&mut runner, path.as_deref(), live.as_ref());
    if live.is_some() {
        runner = run_paced(runner, json);
    } else if json {
        if let Err(error) = runner.run_to_end() {
            eprintln!("warning: {error}; the run went on unrecorded");
        }
    } else {
        outln!(
            "task {} on {} (seed {seed})",
            task.task.name,
            cell.cell.name
        );
        let (target, tolerance) = (task.target, task.tolerance);
        outln!(
            "target n* = {:+.3} mm, α* = {:+.4} rad; tolerance ±{} mm, ±{} rad",
            target.n_mm,
            target.alpha_rad,
            tolerance.n_mm,
            tolerance.alpha_rad
        );
        let mut commentary = Commentary::default();
        loop {
            match runner.step() {
                Ok(true) => commentary.print_new(runner.record()),
                Ok(false) => break,
                Err(error) => eprintln!("warning: {error}; the run goes on unrecorded"),
            }
        }
    }
    finish_recording(&mut runner);
    let record = runner.into_record();
    if json {
        let printed = super::json::print(RunReport::new(&record));
        if printed != Status::Success {
            return printed;
        }
    } else {
        print_outcome(&record);
    }
    outcome_status(&record)
}

/// Runs to the end at the wall clock's pace (a simulated cell is as fast
/// as the computer otherwise: too fast to watch), printing the commentary
/// unless the report is JSON.
fn run_paced(runner: Runner, json: bool) -> Runner {
    let mut driver = Driver::new(runner, Breakpoints::default(), Some(1.0));
    let mut commentary = Commentary::default();
    let no_pause = AtomicBool::new(false);
    loop {
        let stop = driver.advance(Mode::Continue, &no_pause, |runner| {
            if !json {
                commentary.print_new(runner.record());
            }
        });
        match stop {
            Ok(Stop::Finished { .. }) => break,
            Ok(_) => {}
            Err(error) => eprintln!("warning: {error}; the run goes on unrecorded"),
        }
    }
    driver.into_parts().0
}

/// The exit status of a run's outcome.
pub(super) fn outcome_status(record: &RunRecord) -> Status {
    match record.outcome {
        Some(RunOutcome::Success { .. }) => Status::Success,
        Some(RunOutcome::Failed { .. }) => Status::TaskFailed,
        Some(RunOutcome::Fault { .. }) | None => Status::DeviceFault,
    }
}

/// Prints what a run added to its record since the last call: a search
/// by touch and its misses, grasps, then transitions with the time spent
/// in the state left.
#[derive(Debug, Default)]
pub(super) struct Commentary {
    transitions: usize,
    grasps: usize,
    /// `Some(misses printed)` once the search by touch is announced.
    misses: Option<usize>,
}

impl Commentary {
    pub(super) fn print_new(&mut self, record: &RunRecord) {
        if let Some(touch_only) = &record.touch_only {
            let printed = self.misses.unwrap_or_else(|| {
                outln!(
                    "vision not used ({}): searching by touch from the prior",
                    touch_only.why
                );
                0
            });
            for miss in &touch_only.misses[printed..] {
                print_grasp("search miss", miss);
            }
            self.misses = Some(touch_only.misses.len());
        }
        for grasp in &record.grasps[self.grasps..] {
            print_grasp(&attempt_name(grasp.attempt), grasp);
        }
        self.grasps = record.grasps.len();
        for (i, t) in record.transitions.iter().enumerate().skip(self.transitions) {
            print_transition(record, i, t);
        }
        self.transitions = record.transitions.len();
    }
}

/// Transition `i` of `record`, with the time spent in the state it left.
pub(super) fn print_transition(record: &RunRecord, i: usize, t: &TransitionRecord) {
    let entered_s = i.checked_sub(1).map_or(0.0, |p| record.transitions[p].t_s);
    print_timeline_line(t.t_s, t.from, t.to, entered_s);
}

/// A transition at `t_s` from the state entered at `entered_s`.
pub(super) fn print_timeline_line(t_s: f64, from: &str, to: &str, entered_s: f64) {
    outln!(
        "{t_s:9.3} s  {from:>11} → {to:<11}  ({from} took {:.3} s)",
        t_s - entered_s
    );
}

/// The trial grasp (0) or regrasp k.
pub(super) fn attempt_name(attempt: u32) -> String {
    match attempt {
        0 => "trial grasp".into(),
        k => format!("regrasp {k}"),
    }
}

fn print_grasp(name: &str, grasp: &GraspRecord) {
    match (&grasp.fit, &grasp.estimated_error) {
        (Some(fit), Some(error)) => outln!(
            "{name:>13}  estimate n {:+7.3} mm  α {:+.4} rad   error n {:+7.3} mm  α {:+.4} rad",
            fit.line().n_mm,
            fit.line().alpha_rad,
            error.n_mm,
            error.alpha_rad
        ),
        _ => outln!(
            "{name:>13}  no estimate (peak Δv {:.3} V)",
            grasp.map.peak_dv_v()
        ),
    }
    if let Some(truth) = &grasp.truth {
        outln!(
            "{:>13}  true     n {:+7.3} mm  α {:+.4} rad   error n {:+7.3} mm  α {:+.4} rad",
            "",
            truth.line.n_mm,
            truth.line.alpha_rad,
            truth.error.n_mm,
            truth.error.alpha_rad
        );
    }
    if let Some(errors) = grasp.shapes.as_ref().and_then(|shapes| shapes.errors) {
        print_shape_errors(&errors);
    }
}

/// Each shape's mean distance to the true cable, on the pad | beyond.
fn print_shape_errors(errors: &ShapeErrors) {
    let shapes = [
        ("vision", errors.vision),
        ("linear", errors.tactile_linear),
        ("quadratic", errors.tactile_quadratic),
        ("ridge", errors.tactile_ridge),
        ("fused", errors.fused),
    ];
    let mm = |d: Option<Distances>| d.map_or("–".to_owned(), |d| format!("{:.2}", d.mean_mm));
    let each: Vec<String> = shapes
        .iter()
        .filter_map(|&(name, e)| Some(format!("{name} {} | {}", mm(e?.grasped), mm(e?.beyond))))
        .collect();
    outln!(
        "{:>13}  shape off the true cable, on the pad | {:.0} mm beyond: {} mm",
        "",
        errors.beyond_mm,
        each.join(", ")
    );
}

pub(super) fn print_outcome(record: &RunRecord) {
    let tolerance = &record.tolerance;
    if let Some(touch_only) = &record.touch_only {
        outln!(
            "touch only ({}): {} search move(s)",
            touch_only.why,
            touch_only.search_moves
        );
    }
    match &record.outcome {
        Some(RunOutcome::Success { regrasps }) => outln!(
            "success: within tolerance (|n| ≤ {} mm, |α| ≤ {} rad) after {regrasps} regrasp(s)",
            tolerance.n_mm,
            tolerance.alpha_rad
        ),
        Some(RunOutcome::Failed { reason }) => outln!("task failed: {reason}"),
        Some(RunOutcome::Fault {
            state,
            device,
            error,
        }) => {
            let device = device.map(|d| format!(" ({d})")).unwrap_or_default();
            outln!("device fault in {state}{device}: {error}; the cell was made safe");
            for problem in &record.safe_stop_problems {
                outln!("  could not make safe: {problem}");
            }
        }
        None => outln!("the run stopped before it ended"),
    }
    if let Some(why) = chosen_cable(&record.detected) {
        outln!("{why}");
    }
    for skip in &record.skipped {
        outln!("skipped: {}: {}", skip.what, skip.why);
    }
}

/// Which detected cable the task grasped, and why.
fn chosen_cable(detected: &[DetectedCable]) -> Option<String> {
    let best = detected.first()?;
    Some(match detected.get(1) {
        None => format!(
            "grasped the one cable detected (confidence {:.2})",
            best.confidence
        ),
        Some(next) => format!(
            "grasped the most confident of {} cables detected ({:.2}; the next {:.2})",
            detected.len(),
            best.confidence,
            next.confidence
        ),
    })
}
