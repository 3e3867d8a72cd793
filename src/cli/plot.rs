//! `cablecell plot fusion RECORDING`

use std::path::{Path, PathBuf};

use cablecell::plot::fusion::FusionFigure;
use cablecell::plot::{PlotError, save};
use cablecell::recording::schema::{CableShapesMessage, RunMessage};
use cablecell::recording::{Recording, Topic};

use super::Status;

/// The figures `plot` draws.
#[derive(Debug, clap::Subcommand)]
pub enum PlotCommand {
    /// The paper's Fig. 12: at one grasp, the vision shape, the pad's
    /// linear and quadratic fits, their fusion and (simulated cells) the
    /// true cable, in the pad's plane.
    Fusion {
        /// The recording (MCAP) of a run.
        recording: PathBuf,
        /// The figure to write, .png or .svg (default: beside the
        /// recording, RECORDING-fusion-K.png).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Which grasp: 0 the trial grasp, k the k-th regrasp.
        #[arg(long, default_value_t = 0)]
        grasp: u32,
    },
}

pub fn plot(command: &PlotCommand) -> Status {
    match command {
        PlotCommand::Fusion {
            recording,
            out,
            grasp,
        } => fusion(recording, out.as_deref(), *grasp),
    }
}

fn fusion(path: &Path, out: Option<&Path>, attempt: u32) -> Status {
    let recording = match Recording::read(path) {
        Ok(recording) => recording,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    let (runs, grasps) = match (
        recording.decode::<RunMessage>(Topic::Run),
        recording.decode::<CableShapesMessage>(Topic::CableShapes),
    ) {
        (Ok(runs), Ok(grasps)) => (runs, grasps),
        (runs, grasps) => {
            for error in [runs.err(), grasps.err()].into_iter().flatten() {
                eprintln!("error: {error}");
            }
            return Status::BadInput;
        }
    };
    let Some(message) = grasps.iter().find(|m| m.attempt == attempt) else {
        let recorded: Vec<String> = grasps.iter().map(|m| m.attempt.to_string()).collect();
        eprintln!(
            "error: {}: no shapes of grasp {attempt} (recorded: {})",
            path.display(),
            if recorded.is_empty() {
                "none".to_owned()
            } else {
                recorded.join(", ")
            }
        );
        return Status::BadInput;
    };
    let name = match attempt {
        0 => "trial grasp".to_owned(),
        k => format!("regrasp {k}"),
    };
    let run = runs
        .first()
        .map(|run| format!(", {} seed {}", run.task, run.seed))
        .unwrap_or_default();
    let title = format!("Vision and touch fused at the {name}{run}");
    let out = out.map_or_else(|| default_out(path, attempt), Path::to_owned);
    match FusionFigure::new(&message.shapes, title).and_then(|figure| save(&figure, &out)) {
        Ok(()) => {
            eprintln!("wrote {}", out.display());
            Status::Success
        }
        Err(error @ (PlotError::Format { .. } | PlotError::Empty(_))) => {
            eprintln!("error: {error}");
            Status::BadInput
        }
        Err(error) => {
            eprintln!("error: {error}");
            Status::OutputFailed
        }
    }
}

/// RECORDING-fusion-K.png beside the recording.
fn default_out(recording: &Path, attempt: u32) -> PathBuf {
    let stem = recording
        .file_stem()
        .map_or_else(|| "recording".into(), |s| s.to_string_lossy().into_owned());
    recording.with_file_name(format!("{stem}-fusion-{attempt}.png"))
}
