//! Feeds the machine: carries out its pending command on the cell and
//! hands it the answer, one event per step, so that a caller can run a
//! task to the end or step through it.

use statig::blocking::InitializedStateMachine;
use statig::prelude::*;

use super::command::Event;
use super::executor::execute;
use super::machine::{Context, GraspTask, State};
use super::plan::Plan;
use super::record::RunRecord;
use crate::cell::Cell;
use crate::hw::DeviceError;
use crate::task::{CellFile, TaskFile};

pub struct Runner {
    machine: InitializedStateMachine<GraspTask>,
    context: Context,
    cell: Cell,
}

impl Runner {
    pub fn new(plan: Plan, cell: Cell, task_name: &str, seed: u64) -> Self {
        let record = RunRecord::new(task_name, &cell.name, seed, plan.target, plan.tolerance);
        let mut context = Context::new(record);
        let machine = GraspTask::new(plan)
            .uninitialized_state_machine()
            .init_with_context(&mut context);
        Self {
            machine,
            context,
            cell,
        }
    }

    /// The runner of `task` on the cell of `cell_file`, its simulated
    /// sources seeded with `seed`; fails if a device cannot be opened.
    pub fn for_task(task: &TaskFile, cell_file: &CellFile, seed: u64) -> Result<Self, DeviceError> {
        let plan = Plan::new(task, cell_file);
        Ok(Self::new(
            plan,
            Cell::build(cell_file, seed)?,
            &task.task.name,
            seed,
        ))
    }

    /// Handles one event: `Start` when idle, else the answer to the pending
    /// command. Returns `false` once there is nothing left to do.
    pub fn step(&mut self) -> bool {
        let event = match self.context.command.take() {
            Some(command) => {
                tracing::debug!(?command, state = self.machine.state().name(), "executing");
                execute(&mut self.cell, &command)
            }
            None if matches!(self.machine.state(), State::Idle { .. }) => Event::Start,
            None => return false,
        };
        self.context.now_s = self.cell.clock.now_s();
        self.machine.handle_with_context(&event, &mut self.context);
        true
    }

    /// Steps until the run is over.
    pub fn run_to_end(&mut self) {
        while self.step() {}
    }

    pub fn state(&self) -> &State {
        self.machine.state()
    }

    pub fn record(&self) -> &RunRecord {
        &self.context.record
    }

    pub fn into_record(self) -> RunRecord {
        self.context.record
    }
}
