//! `cablecell plot FIGURE`: the figures of `cablecell::plot` drawn from a
//! recording (`tactile`, `regrasp`, `fusion`), a tactile map file
//! (`tactile`) or a campaign's output folder (`campaign`, in its own file).

mod campaign;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use cablecell::perception::tactile::{FitConfig, TactileMap};
use cablecell::plot::fusion::FusionFigure;
use cablecell::plot::regrasp::{GraspLines, RegraspFigure, grasp_name};
use cablecell::plot::tactile::TactileFigure;
use cablecell::plot::{Figure, PlotError, save};
use cablecell::recording::schema::{CableShapesMessage, RunMessage, TactileFitMessage};
use cablecell::recording::{Recording, Topic};
use serde::de::DeserializeOwned;

use super::Status;

/// The figures `plot` draws.
#[derive(Debug, clap::Subcommand)]
pub enum PlotCommand {
    /// The paper's Fig. 7: a grasp's tactile map, each taxel a circle whose
    /// radius follows its Δv, the centroids, the linear and quadratic fits,
    /// and (simulated cells) the true cable, in the sensor frame.
    Tactile {
        /// A recording (.mcap) of a run, or a tactile map file as
        /// `tactile-fit` reads it.
        input: PathBuf,
        /// Which grasp of a recording: 0 the trial grasp (the default), k
        /// the k-th regrasp.
        #[arg(long)]
        grasp: Option<u32>,
        /// The figure to write, .png or .svg (default: beside the input,
        /// INPUT-tactile-K.png, or MAP-tactile.png).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// The paper's Fig. 11: the cable on the pad at the trial grasp and
    /// after each regrasp (the pad's fits and, simulated cells, the
    /// truth), with the target pose and its tolerance.
    Regrasp {
        /// The recording (MCAP) of a run.
        recording: PathBuf,
        /// The figure to write, .png or .svg (default: beside the
        /// recording, RECORDING-regrasp.png).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// A campaign's grasps: per policy, |n| and |α| at the trial grasp and
    /// after each regrasp as box plots with every trial, the paper's
    /// means, the success rate with its 95 % interval, regrasps per trial.
    Campaign {
        /// The campaign's output folder (holding its trials.jsonl).
        folder: PathBuf,
        /// The figure to write, .png or .svg (default: FOLDER/campaign.png).
        #[arg(long)]
        out: Option<PathBuf>,
    },
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
    let drawn = match command {
        PlotCommand::Tactile { input, grasp, out } => tactile(input, *grasp, out.as_deref()),
        PlotCommand::Regrasp { recording, out } => regrasp(recording, out.as_deref()),
        PlotCommand::Campaign { folder, out } => campaign::campaign(folder, out.as_deref()),
        PlotCommand::Fusion {
            recording,
            out,
            grasp,
        } => fusion(recording, out.as_deref(), *grasp),
    };
    match drawn {
        Ok(out) => {
            eprintln!("wrote {}", out.display());
            Status::Success
        }
        Err(Failure::BadInput(message)) => {
            eprintln!("error: {message}");
            Status::BadInput
        }
        Err(Failure::Output(error)) => {
            eprintln!("error: {error}");
            Status::OutputFailed
        }
    }
}

/// Why no figure was written.
enum Failure {
    /// The input (or the output's format) is at fault: the message names
    /// the file and what is wrong.
    BadInput(String),
    /// The figure could not be drawn or written.
    Output(PlotError),
}

impl From<PlotError> for Failure {
    fn from(error: PlotError) -> Self {
        match error {
            PlotError::Format { .. } | PlotError::Empty(_) | PlotError::Config { .. } => {
                Failure::BadInput(error.to_string())
            }
            error => Failure::Output(error),
        }
    }
}

/// Saves `figure` to `out`, returning where it went.
fn write(figure: &impl Figure, out: PathBuf) -> Result<PathBuf, Failure> {
    save(figure, &out)?;
    Ok(out)
}

/// A run's recording: its `/run` message and the messages of `topic`.
fn read_recording<T: DeserializeOwned>(
    path: &Path,
    topic: Topic,
) -> Result<(RunMessage, Vec<T>), Failure> {
    let bad = |error: &dyn std::fmt::Display| Failure::BadInput(error.to_string());
    let recording = Recording::read(path).map_err(|e| bad(&e))?;
    let run = recording
        .decode::<RunMessage>(Topic::Run)
        .map_err(|e| bad(&e))?
        .into_iter()
        .next()
        .ok_or_else(|| {
            Failure::BadInput(format!(
                "{}: no /run message: not a cablecell run recording",
                path.display()
            ))
        })?;
    let messages = recording.decode::<T>(topic).map_err(|e| bad(&e))?;
    Ok((run, messages))
}

/// Each grasp's tactile fit, in order of attempts. A search by touch
/// records its misses before the grasp that felt the cable, under the same
/// attempt: the last message of an attempt is its grasp.
fn grasp_fits(messages: Vec<TactileFitMessage>) -> Vec<TactileFitMessage> {
    let by_attempt: BTreeMap<u32, TactileFitMessage> =
        messages.into_iter().map(|m| (m.attempt, m)).collect();
    by_attempt.into_values().collect()
}

/// "recorded: 0, 1" or "recorded: none", for a grasp asked for in vain.
fn recorded_attempts(attempts: impl Iterator<Item = u32>) -> String {
    let recorded: Vec<String> = attempts.map(|a| a.to_string()).collect();
    if recorded.is_empty() {
        "recorded: none".to_owned()
    } else {
        format!("recorded: {}", recorded.join(", "))
    }
}

/// ", regrasp seed 3": the run a figure comes from.
fn run_text(run: &RunMessage) -> String {
    format!(", {} seed {}", run.task, run.seed)
}

/// INPUT-SUFFIX.png beside `input`.
fn beside(input: &Path, suffix: &str) -> PathBuf {
    let stem = input
        .file_stem()
        .map_or_else(|| "figure".into(), |s| s.to_string_lossy().into_owned());
    input.with_file_name(format!("{stem}-{suffix}.png"))
}

fn is_recording(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
}

fn tactile(input: &Path, grasp: Option<u32>, out: Option<&Path>) -> Result<PathBuf, Failure> {
    let (figure, default_out) = if is_recording(input) {
        let attempt = grasp.unwrap_or(0);
        let (run, messages) = read_recording::<TactileFitMessage>(input, Topic::TactileFit)?;
        let fits = grasp_fits(messages);
        let Some(fit) = fits.iter().find(|m| m.attempt == attempt) else {
            return Err(Failure::BadInput(format!(
                "{}: no tactile map of grasp {attempt} ({})",
                input.display(),
                recorded_attempts(fits.iter().map(|m| m.attempt))
            )));
        };
        let map = TactileMap::from_row_major(&fit.map_dv_v)
            .map_err(|e| Failure::BadInput(format!("{}: {e}", input.display())))?;
        let config = run.fit_config();
        let truth = fit.truth();
        let title = format!(
            "Tactile map at the {}{}",
            grasp_name(attempt),
            run_text(&run)
        );
        (
            TactileFigure::new(map, &config, truth, title)?,
            beside(input, &format!("tactile-{attempt}")),
        )
    } else {
        if let Some(attempt) = grasp {
            return Err(Failure::BadInput(format!(
                "{}: a map file holds one map: --grasp {attempt} needs a recording (.mcap)",
                input.display()
            )));
        }
        let text = std::fs::read_to_string(input)
            .map_err(|e| Failure::BadInput(format!("{}: cannot read: {e}", input.display())))?;
        let map = TactileMap::parse(&text)
            .map_err(|e| Failure::BadInput(format!("{}: {e}", input.display())))?;
        let name = input
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        (
            TactileFigure::new(
                map,
                &FitConfig::default(),
                None,
                format!("Tactile map {name}"),
            )?,
            beside(input, "tactile"),
        )
    };
    write(&figure, out.map_or(default_out, Path::to_owned))
}

fn regrasp(path: &Path, out: Option<&Path>) -> Result<PathBuf, Failure> {
    let (run, messages) = read_recording::<TactileFitMessage>(path, Topic::TactileFit)?;
    let grasps: Vec<GraspLines> = grasp_fits(messages)
        .iter()
        .map(|m| GraspLines {
            attempt: m.attempt,
            estimate: m.estimate(),
            truth: m.truth(),
        })
        .collect();
    let title = format!("The cable on the pad, grasp by grasp{}", run_text(&run));
    let figure = RegraspFigure::new(grasps, run.target, run.tolerance, run.pitch_mm, title)
        .map_err(|e| Failure::BadInput(format!("{}: {e}", path.display())))?;
    write(
        &figure,
        out.map_or_else(|| beside(path, "regrasp"), Path::to_owned),
    )
}

fn fusion(path: &Path, out: Option<&Path>, attempt: u32) -> Result<PathBuf, Failure> {
    let (run, grasps) = read_recording::<CableShapesMessage>(path, Topic::CableShapes)?;
    let Some(message) = grasps.iter().find(|m| m.attempt == attempt) else {
        return Err(Failure::BadInput(format!(
            "{}: no shapes of grasp {attempt} ({})",
            path.display(),
            recorded_attempts(grasps.iter().map(|m| m.attempt))
        )));
    };
    let title = format!(
        "Vision and touch fused at the {}{}",
        grasp_name(attempt),
        run_text(&run)
    );
    let figure = FusionFigure::new(&message.shapes, title)?;
    write(
        &figure,
        out.map_or_else(
            || beside(path, &format!("fusion-{attempt}")),
            Path::to_owned,
        ),
    )
}
