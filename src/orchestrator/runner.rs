//! Feeds the machine: carries out its pending command on the cell and
//! hands it the answer, one event per step, so that a caller can run a
//! task to the end or step through it. A run with a recorder attached
//! writes every event, transition and grasp to it as it goes.

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;
use statig::blocking::InitializedStateMachine;
use statig::prelude::*;

use super::command::{Command, Event};
use super::executor::execute;
use super::machine::{Context, GraspTask, State};
use super::plan::Plan;
use super::shapes::{grasp_shapes, pad_half_side_mm};
use crate::cell::CellDevices;
use crate::cell::CellFile;
use crate::hw::DeviceError;
use crate::perception::shape::ShapePoint;
use crate::record::RunRecord;
use crate::recording::schema::{RunMessage, Timestamp};
use crate::recording::{Recorder, RecordingError, RecordingTarget, Topic};
use crate::task::TaskFile;

pub struct Runner {
    machine: InitializedStateMachine<GraspTask>,
    context: Context,
    cell: CellDevices,
    recording: Option<Recording>,
    /// The centre line of the cable the machine aimed at, as detected.
    vision_shape: Option<Vec<ShapePoint>>,
}

/// A recorder and how far the record has been written to it.
struct Recording {
    recorder: Recorder,
    transitions: usize,
    grasps: usize,
    /// A search by touch's misses written: grasps too, so that a replay
    /// finds each grasp's frames.
    misses: usize,
    /// Flush after every step (interactive runs), or only at the end.
    flush_each_step: bool,
}

impl Runner {
    pub fn new(plan: Plan, cell: CellDevices, task_name: &str, seed: u64) -> Self {
        let record = RunRecord::new(task_name, &cell.name, seed, plan.target, plan.tolerance);
        let mut context = Context::new(plan, record);
        let machine = GraspTask::new()
            .uninitialized_state_machine()
            .init_with_context(&mut context);
        Self {
            machine,
            context,
            cell,
            recording: None,
            vision_shape: None,
        }
    }

    /// The runner of `task` on the cell of `cell_file`, its simulated
    /// sources seeded with `seed`; fails if a device cannot be opened.
    pub fn for_task(task: &TaskFile, cell_file: &CellFile, seed: u64) -> Result<Self, DeviceError> {
        let plan = Plan::new(task, cell_file);
        Ok(Self::new(
            plan,
            CellDevices::build(cell_file, seed)?,
            &task.task.name,
            seed,
        ))
    }

    /// Records the run to a new MCAP file at `path` from now on.
    /// `flush_each_step` makes every step durable as it ends (for runs a
    /// person watches); a campaign's trials flush only when they finish.
    pub fn record_to(&mut self, path: &Path, flush_each_step: bool) -> Result<(), RecordingError> {
        let target = RecordingTarget {
            file: Some(path),
            live: None,
            metadata: Default::default(),
        };
        self.start_recording(target, flush_each_step)
    }

    /// Records the run from now on to `target`'s file and live view; the
    /// file's metadata gets the task, cell and seed beside `target`'s.
    pub fn start_recording(
        &mut self,
        mut target: RecordingTarget<'_>,
        flush_each_step: bool,
    ) -> Result<(), RecordingError> {
        let record = &self.context.record;
        target.metadata.extend([
            ("task".to_owned(), record.task.clone()),
            ("cell".to_owned(), record.cell.clone()),
            ("seed".to_owned(), record.seed.to_string()),
        ]);
        let now_s = self.cell.clock.now_s();
        let mut recorder = Recorder::create(target, self.context.plan.view.clone(), now_s)?;
        recorder.run(now_s, &self.run_message(recorder.timestamp(now_s)))?;
        self.recording = Some(Recording {
            recorder,
            transitions: 0,
            grasps: 0,
            misses: 0,
            flush_each_step,
        });
        Ok(())
    }

    /// The run's description with the plan in force at `timestamp`.
    fn run_message(&self, timestamp: Timestamp) -> RunMessage {
        let (record, plan) = (&self.context.record, &self.context.plan);
        RunMessage {
            timestamp,
            task: record.task.clone(),
            cell: record.cell.clone(),
            seed: record.seed,
            target: plan.target,
            tolerance: plan.tolerance,
            estimator: plan.estimator,
            pitch_mm: plan.fit.pitch_mm,
            contact_threshold_v: plan.fit.contact_threshold_v,
            bias_frames: plan.bias_frames,
        }
    }

    /// Handles one event: `Start` when idle, else the answer to the pending
    /// command. Returns `Ok(false)` once there is nothing left to do.
    ///
    /// A recording that cannot be written is an error, returned once: the
    /// recorder is dropped (what it flushed stays readable) and the run
    /// goes on unrecorded.
    pub fn step(&mut self) -> Result<bool, RecordingError> {
        let state = self.machine.state().name();
        let (event, command) = match self.context.command.take() {
            Some(command) => {
                tracing::debug!(?command, state, "executing");
                (execute(&mut self.cell, &command), Some(command))
            }
            None if matches!(self.machine.state(), State::Idle { .. }) => (Event::Start, None),
            None => return Ok(false),
        };
        self.handle(state, command.as_ref(), &event)?;
        Ok(true)
    }

    /// Asks the machine to stop: it goes to `fault`, whose command makes
    /// the cell safe; the pending command is dropped unexecuted. Returns
    /// `false` (and changes nothing) if there is no run to abort: not
    /// started yet, or over.
    pub fn abort(&mut self) -> Result<bool, RecordingError> {
        let state = self.machine.state();
        if matches!(state, State::Idle { .. }) || state.is_final() {
            return Ok(false);
        }
        let state = state.name();
        self.context.command = None;
        self.handle(state, None, &Event::Abort)?;
        Ok(true)
    }

    fn handle(
        &mut self,
        state: &'static str,
        command: Option<&Command>,
        event: &Event,
    ) -> Result<(), RecordingError> {
        self.context.now_s = self.cell.clock.now_s();
        if let Event::Detected(detections) = event {
            // The machine aims at the first.
            self.vision_shape = detections
                .cables
                .first()
                .map(|cable| cable.centre_line.clone())
                .filter(|line| !line.is_empty());
        }
        let grasps_before = self.context.record.grasps.len();
        self.machine.handle_with_context(event, &mut self.context);
        self.add_shapes(grasps_before);
        let result = self.write_recording(state, command, event);
        if result.is_err() {
            self.recording = None;
        }
        result
    }

    /// The cable's shapes at each grasp the machine recorded from
    /// `grasps_before` on, fused where the fit is: as it was recorded,
    /// with the cell's truth of that moment.
    fn add_shapes(&mut self, grasps_before: usize) {
        let (record, plan) = (&mut self.context.record, &self.context.plan);
        if record.grasps.len() <= grasps_before {
            return;
        }
        let truth = self.cell.true_centre_line(pad_half_side_mm(plan));
        for grasp in &mut record.grasps[grasps_before..] {
            let shapes = grasp_shapes(grasp, plan, self.vision_shape.as_deref(), truth.as_deref());
            grasp.shapes = Some(shapes);
        }
    }

    fn write_recording(
        &mut self,
        state: &str,
        command: Option<&Command>,
        event: &Event,
    ) -> Result<(), RecordingError> {
        let Some(recording) = &mut self.recording else {
            return Ok(());
        };
        let recorder = &mut recording.recorder;
        let now_s = self.context.now_s;
        if let Some(
            Command::MoveTo { base_from_tcp, .. }
            | Command::Grasp { base_from_tcp, .. }
            | Command::Regrasp { base_from_tcp, .. }
            | Command::Probe { base_from_tcp, .. },
        ) = command
        {
            recorder.pose(Topic::ArmTarget, now_s, base_from_tcp)?;
        }
        if let Event::Tactile { frames, .. } = event {
            recorder.tactile_frames(state, frames)?;
        }
        if let Event::Detected(detections) = event {
            recorder.detections(now_s, detections)?;
        }
        let record = &self.context.record;
        let misses = record.touch_only.as_ref().map_or(&[][..], |t| &t.misses);
        let plan = &self.context.plan;
        for miss in &misses[recording.misses..] {
            recorder.grasp(miss, plan.estimator, &plan.fit)?;
        }
        recording.misses = misses.len();
        for grasp in &record.grasps[recording.grasps..] {
            recorder.grasp(grasp, plan.estimator, &plan.fit)?;
        }
        recording.grasps = record.grasps.len();
        for transition in &record.transitions[recording.transitions..] {
            recorder.transition(transition)?;
        }
        let new_transitions = recording.transitions < record.transitions.len();
        recording.transitions = record.transitions.len();
        if new_transitions && self.machine.state().is_final() {
            recorder.outcome(record, now_s)?;
        }
        // Where the arm is now, for `/tf` (last: the step's latest time);
        // an arm that cannot say is asked again after the next step (its
        // error reaches the machine through the next command).
        let base_from_tcp = self
            .cell
            .arm
            .base_from_tcp()
            .inspect_err(|error| tracing::debug!(%error, "no arm pose for /tf"))
            .ok();
        recorder.frames(now_s, base_from_tcp.as_ref())?;
        if recording.flush_each_step {
            recorder.flush()?;
        }
        Ok(())
    }

    /// Finishes the recording, if there is one, and returns its path.
    pub fn finish_recording(&mut self) -> Result<Option<PathBuf>, RecordingError> {
        match self.recording.take() {
            Some(recording) => recording.recorder.finish(),
            None => Ok(None),
        }
    }

    /// Steps until the run is over. A recording error ends the recording,
    /// not the run; the first one is returned.
    pub fn run_to_end(&mut self) -> Result<(), RecordingError> {
        let mut first_error = None;
        loop {
            match self.step() {
                Ok(true) => {}
                Ok(false) => break,
                Err(error) => {
                    first_error.get_or_insert(error);
                }
            }
        }
        first_error.map_or(Ok(()), Err)
    }

    pub fn state(&self) -> &State {
        self.machine.state()
    }

    /// The command the machine waits to have carried out, if any.
    pub fn pending_command(&self) -> Option<&Command> {
        self.context.command.as_ref()
    }

    pub fn record(&self) -> &RunRecord {
        &self.context.record
    }

    pub fn plan(&self) -> &Plan {
        &self.context.plan
    }

    /// Replaces the plan between two steps. The pending command was given
    /// with the old one; every later command and judgement uses `plan`.
    /// A recording gets the new plan as a new `/run` message; if that
    /// cannot be written the recording ends (the error is returned once).
    pub fn set_plan(&mut self, plan: Plan) -> Result<(), RecordingError> {
        self.context.record.target = plan.target;
        self.context.record.tolerance = plan.tolerance;
        // The machine reads the plan from the context it is lent with
        // each event: between two events it is the runner's to change.
        self.context.plan = plan;
        let now_s = self.cell.clock.now_s();
        let Some(timestamp) = self.recording.as_ref().map(|r| r.recorder.timestamp(now_s)) else {
            return Ok(());
        };
        let run = self.run_message(timestamp);
        let Some(recording) = &mut self.recording else {
            return Ok(());
        };
        let written = recording.recorder.run(now_s, &run);
        if written.is_err() {
            self.recording = None;
        }
        written
    }

    /// Where the arm's TCP is now, asked of the arm.
    pub fn base_from_tcp(&mut self) -> Result<Isometry3<f64>, DeviceError> {
        self.cell.arm.base_from_tcp()
    }

    /// The cell's clock.
    pub fn now_s(&self) -> f64 {
        self.cell.clock.now_s()
    }

    pub fn cell_name(&self) -> &str {
        &self.cell.name
    }

    pub fn into_record(self) -> RunRecord {
        self.context.record
    }
}
