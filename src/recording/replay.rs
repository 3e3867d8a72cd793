//! A recorded run read back: its timeline, and its grasps fitted again
//! from the recorded frames, with the recorded estimator or another one,
//! so that estimators can be compared on the same inputs.

use super::RecordingError;
use super::read::Recording;
use super::schema::{RunMessage, TactileFitMessage, TactileRawMessage, Topic, TransitionMessage};
use crate::geometry::{LineInSensor, PoseError};
use crate::perception::tactile::{BiasEstimator, Estimator, FitError, RawFrame};

/// What a recording says happened.
#[derive(Debug, Clone)]
pub struct Replay {
    /// The run as it started.
    pub run: RunMessage,
    /// The run's description each time its plan changed (the REPL's `set`).
    pub changes: Vec<RunMessage>,
    pub transitions: Vec<TransitionMessage>,
    pub fits: Vec<TactileFitMessage>,
    raw: Vec<TactileRawMessage>,
}

/// One recorded grasp fitted again.
#[derive(Debug, Clone)]
pub struct Refit {
    pub attempt: u32,
    pub estimator: Estimator,
    /// The new estimate, or why there is none.
    pub line: Result<LineInSensor, FitError>,
    /// The recorded estimate.
    pub recorded: Option<LineInSensor>,
    /// Where the cable really lay (simulated cells).
    pub truth: Option<LineInSensor>,
    /// Frames averaged.
    pub frames: usize,
}

impl Refit {
    /// The new estimate against the truth.
    pub fn error(&self) -> Option<PoseError> {
        Some(self.line.as_ref().ok()?.error_to(&self.truth?))
    }

    /// The recorded estimate against the truth.
    pub fn recorded_error(&self) -> Option<PoseError> {
        Some(self.recorded?.error_to(&self.truth?))
    }
}

impl Replay {
    pub fn of(recording: &Recording) -> Result<Self, RecordingError> {
        let mut runs = recording.decode::<RunMessage>(Topic::Run)?.into_iter();
        let run = runs.next().ok_or_else(|| RecordingError::NotARun {
            path: recording.path.clone(),
        })?;
        Ok(Self {
            run,
            changes: runs.collect(),
            transitions: recording.decode(Topic::State)?,
            fits: recording.decode(Topic::TactileFit)?,
            raw: recording.decode(Topic::TactileRaw)?,
        })
    }

    /// Each recorded grasp fitted again with `estimator`, from the
    /// recorded raw frames: the bias from the first `bias_frames` frames
    /// (`prepare`'s), then the mean Δv of the frames read for that grasp.
    /// Empty if the recording holds no complete bias; a grasp whose frames
    /// are missing is left out.
    pub fn refit(&self, estimator: Estimator) -> Vec<Refit> {
        let mut bias = BiasEstimator::new(self.run.bias_frames);
        let Some(bias) = self
            .raw
            .iter()
            .filter(|m| m.state == "prepare")
            .find_map(|m| bias.push(&m.counts))
        else {
            return Vec::new();
        };
        let mut after = None;
        self.fits
            .iter()
            .filter_map(|fit| {
                let judged = fit.timestamp;
                let frames: Vec<RawFrame> = self
                    .raw
                    .iter()
                    .filter(|m| matches!(m.state.as_str(), "evaluate" | "verify"))
                    .filter(|m| Some(m.timestamp) > after && m.timestamp <= judged)
                    .map(|m| m.counts)
                    .collect();
                after = Some(judged);
                let map = bias.remove_mean(&frames)?;
                // The plan in force when the grasp was judged.
                let plan = std::iter::once(&self.run)
                    .chain(&self.changes)
                    .rfind(|run| run.timestamp <= judged)
                    .unwrap_or(&self.run);
                let config = plan.fit_config();
                let truth = fit.truth();
                Some(Refit {
                    attempt: fit.attempt,
                    estimator,
                    line: estimator
                        .estimate(&map, &config, truth)
                        .map(|estimate| estimate.line()),
                    recorded: fit
                        .n_mm
                        .zip(fit.alpha_rad)
                        .map(|(n_mm, alpha_rad)| LineInSensor::new(alpha_rad, n_mm)),
                    truth,
                    frames: frames.len(),
                })
            })
            .collect()
    }
}
