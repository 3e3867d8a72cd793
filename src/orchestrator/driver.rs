//! Stepping, breakpoints and pausing around a run, for the REPL. The
//! machine knows nothing of them: the driver feeds it through the
//! [`Runner`] one event at a time and looks at the record in between.
//!
//! The driver stops only between two commands. Every command is carried
//! out to its end by the executor (a move until the arm arrives, a grasp
//! until the jaws hold the cable or close empty, a regrasp through its
//! release and new grasp), so a stop never leaves the gripper half closed
//! on nothing or the arm between two poses: between commands is a safe
//! point.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use nalgebra::Isometry3;

use super::breakpoint::{Breakpoints, RunValues};
use super::plan::Plan;
use super::runner::Runner;
use crate::hw::DeviceError;
use crate::recording::RecordingError;

/// How far to go.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Until the machine changes state.
    Step,
    /// Until a breakpoint, a pause or the end of the run.
    Continue,
}

/// Why the driver stopped.
#[derive(Debug, Clone, PartialEq)]
pub enum Stop {
    /// The machine entered `to` (`Mode::Step`).
    Transition {
        from: &'static str,
        to: &'static str,
    },
    /// Breakpoint `id` fired as the machine entered `state`.
    Breakpoint { id: usize, state: &'static str },
    /// The operator asked for a pause; it was taken at this safe point.
    Paused { state: &'static str },
    /// Nothing is left to do.
    Finished { state: &'static str },
}

/// Why there is no run to abort.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NothingToAbort {
    #[error("the run has not started: nothing to abort")]
    NotStarted,
    #[error("the run is over ({state})")]
    Over { state: &'static str },
}

pub struct Driver {
    runner: Runner,
    breakpoints: Breakpoints,
    /// Cell seconds per wall-clock second while running: 1 shows a
    /// simulated cell at the speed of a real one; `None` runs as fast as
    /// the cell goes. A real cell's clock is the wall clock, so pacing
    /// never waits for it.
    pace: Option<f64>,
}

impl Driver {
    /// A driver of `runner` with `breakpoints`, paced at `pace` (see
    /// [`Driver::advance`]; `None`: as fast as the cell goes).
    pub fn new(runner: Runner, breakpoints: Breakpoints, pace: Option<f64>) -> Self {
        Self {
            runner,
            breakpoints,
            pace,
        }
    }

    /// The run: its state, record, pending command and plan.
    pub fn runner(&self) -> &Runner {
        &self.runner
    }

    pub fn breakpoints(&self) -> &Breakpoints {
        &self.breakpoints
    }

    /// To add and delete breakpoints between steps.
    pub fn breakpoints_mut(&mut self) -> &mut Breakpoints {
        &mut self.breakpoints
    }

    /// The runner and the breakpoints, to finish the run and keep the
    /// breakpoints for the next.
    pub fn into_parts(self) -> (Runner, Breakpoints) {
        (self.runner, self.breakpoints)
    }

    /// Replaces the plan between two steps (see [`Runner::set_plan`]).
    pub fn set_plan(&mut self, plan: Plan) -> Result<(), RecordingError> {
        self.runner.set_plan(plan)
    }

    /// Where the arm's TCP is now, asked of the arm.
    pub fn base_from_tcp(&mut self) -> Result<Isometry3<f64>, DeviceError> {
        self.runner.base_from_tcp()
    }

    /// Stops the run and makes the cell safe: the machine goes to `fault`
    /// and its safe stop is carried out at once, whatever the breakpoints
    /// say (the pending command is dropped unexecuted). `on_step` as in
    /// [`Driver::advance`].
    ///
    /// The cell is made safe even if the recording fails: the error that
    /// ended the recording, if one did, is returned in `Ok`.
    pub fn abort(
        &mut self,
        on_step: impl FnMut(&Runner),
    ) -> Result<Option<RecordingError>, NothingToAbort> {
        let mut recording_error = match self.runner.abort() {
            Ok(true) => None,
            Ok(false) if self.runner.state().is_final() => {
                return Err(NothingToAbort::Over {
                    state: self.runner.state().name(),
                });
            }
            Ok(false) => return Err(NothingToAbort::NotStarted),
            Err(error) => Some(error),
        };
        let breakpoints = std::mem::take(&mut self.breakpoints);
        let no_pause = AtomicBool::new(false);
        let stopped = self.advance(Mode::Continue, &no_pause, on_step);
        self.breakpoints = breakpoints;
        if let Err(error) = stopped {
            recording_error.get_or_insert(error);
        }
        Ok(recording_error)
    }

    /// Runs until `mode` says stop, calling `on_step` after every step (to
    /// show the run as it goes). `pause` is the operator's request to pause
    /// (set by Ctrl-C): checked, and cleared when taken, at every safe
    /// point of a `Continue`.
    ///
    /// A recording error is returned once, after the step that met it;
    /// the run can go on unrecorded.
    pub fn advance(
        &mut self,
        mode: Mode,
        pause: &AtomicBool,
        mut on_step: impl FnMut(&Runner),
    ) -> Result<Stop, RecordingError> {
        let (wall_start, cell_start_s) = (Instant::now(), self.runner.now_s());
        loop {
            let transitions = self.runner.record().transitions.len();
            if !self.runner.step()? {
                return Ok(Stop::Finished {
                    state: self.runner.state().name(),
                });
            }
            self.wait_for_pace(wall_start, cell_start_s, pause);
            on_step(&self.runner);
            let record = self.runner.record();
            if let Some(entered) = record
                .transitions
                .get(transitions..)
                .and_then(|new| new.last())
            {
                let values = RunValues::of(record);
                if let Some(breakpoint) = self.breakpoints.hit(entered.to, &values) {
                    return Ok(Stop::Breakpoint {
                        id: breakpoint.id,
                        state: entered.to,
                    });
                }
                if mode == Mode::Step {
                    return Ok(Stop::Transition {
                        from: entered.from,
                        to: entered.to,
                    });
                }
            }
            if mode == Mode::Continue && pause.swap(false, Ordering::SeqCst) {
                return Ok(Stop::Paused {
                    state: self.runner.state().name(),
                });
            }
        }
    }

    /// Sleeps until the wall clock has caught up with the cell's clock
    /// (scaled by the pace), waking early for a pause request.
    fn wait_for_pace(&self, wall_start: Instant, cell_start_s: f64, pause: &AtomicBool) {
        let Some(pace) = self.pace.filter(|p| *p > 0.0) else {
            return;
        };
        let cell_elapsed_s = (self.runner.now_s() - cell_start_s).max(0.0);
        let due = wall_start + Duration::from_secs_f64(cell_elapsed_s / pace);
        while !pause.load(Ordering::SeqCst) {
            let now = Instant::now();
            if now >= due {
                break;
            }
            std::thread::sleep((due - now).min(Duration::from_millis(20)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::orchestrator::State;
    use crate::task::load_task;

    fn driver(seed: u64) -> Driver {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let task = load_task(&root.join("tasks/regrasp.toml")).unwrap();
        let cell = crate::orchestrator::test_cell::sim_cell_with_oracle();
        Driver::new(
            Runner::for_task(&task, &cell, seed).unwrap(),
            Breakpoints::default(),
            None,
        )
    }

    #[test]
    fn step_stops_at_every_transition_and_continue_runs_to_the_end() {
        let no_pause = AtomicBool::new(false);
        let mut stepped = driver(3);
        let mut stops = Vec::new();
        loop {
            match stepped.advance(Mode::Step, &no_pause, |_| {}).unwrap() {
                Stop::Transition { to, .. } => stops.push(to),
                Stop::Finished { state } => {
                    assert_eq!(state, State::Done {}.name());
                    break;
                }
                other => panic!("{other:?}"),
            }
        }
        let mut continued = driver(3);
        assert_eq!(
            continued
                .advance(Mode::Continue, &no_pause, |_| {})
                .unwrap(),
            Stop::Finished {
                state: State::Done {}.name()
            }
        );
        let states: Vec<_> = continued
            .runner
            .record()
            .transitions
            .iter()
            .map(|t| t.to)
            .collect();
        assert_eq!(stops, states);
        assert_eq!(stops.first(), Some(&State::Prepare {}.name()));
    }

    #[test]
    fn a_breakpoint_stops_before_its_state_runs_and_a_pause_is_taken() {
        let no_pause = AtomicBool::new(false);
        let mut d = driver(3);
        let (trial_grasp, regrasp) = (State::TrialGrasp {}.name(), State::Regrasp {}.name());
        d.breakpoints.add(trial_grasp, None).unwrap();
        d.breakpoints.add(regrasp, Some("abs(n_mm) > 100")).unwrap();
        assert_eq!(
            d.advance(Mode::Continue, &no_pause, |_| {}).unwrap(),
            Stop::Breakpoint {
                id: 1,
                state: trial_grasp
            }
        );
        // Nothing grasped yet: the grasp command waits.
        assert!(d.runner.record().grasps.is_empty());
        assert!(d.runner.pending_command().is_some());
        let pause = AtomicBool::new(true);
        assert_eq!(
            d.advance(Mode::Continue, &pause, |_| {}).unwrap(),
            Stop::Paused {
                state: State::Evaluate {}.name()
            }
        );
        assert!(!pause.load(Ordering::SeqCst), "the request is taken");
        assert_eq!(
            d.advance(Mode::Continue, &no_pause, |_| {}).unwrap(),
            Stop::Finished {
                state: State::Done {}.name()
            }
        );
    }
}
