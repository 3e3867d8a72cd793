//! A REPL session: the cell, the loaded task and its run.

use crate::cli::output::outln;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use cablecell::cell::CellFile;
use cablecell::hw::DeviceError;
use cablecell::orchestrator::Runner;
use cablecell::orchestrator::breakpoint::Breakpoints;
use cablecell::orchestrator::driver::Driver;
use cablecell::orchestrator::params::TaskParams;
use cablecell::recording::LiveServer;

use super::super::run::{Commentary, RecordArgs, finish_recording, start_recording};

/// A REPL session: the cell, the loaded task and its run.
pub(super) struct Session {
    pub(super) cell_path: PathBuf,
    pub(super) cell: CellFile,
    pub(super) seed: Option<u64>,
    pub(super) record: RecordArgs,
    /// The live view every run of the session is served on.
    pub(super) live: Option<Arc<LiveServer>>,
    pub(super) pace: Option<f64>,
    /// Runs recorded so far, to number the files of an explicit `--record`.
    pub(super) runs: usize,
    pub(super) task: Option<Loaded>,
    /// Set by Ctrl-C while a task runs.
    pub(super) pause: Arc<AtomicBool>,
}

pub(super) struct Loaded {
    pub(super) params: TaskParams,
    pub(super) seed: u64,
    pub(super) driver: Driver,
    pub(super) commentary: Commentary,
}

impl Session {
    pub(super) fn load(&mut self, path: &Path) -> Result<(), String> {
        let params = TaskParams::load_on_cell(path, &self.cell_path, &self.cell)
            .map_err(|e| e.to_string())?;
        let seed = self
            .seed
            .or(params.task().task.seed)
            .unwrap_or_else(rand::random);
        outln!(
            "loaded task {} from {} (seed {seed})",
            params.task().task.name,
            path.display()
        );
        self.start(params, seed)
    }

    /// Ends the current run, if any, and starts a new one from idle; the
    /// breakpoints carry over.
    pub(super) fn start(&mut self, params: TaskParams, seed: u64) -> Result<(), String> {
        let breakpoints = self.end_run().unwrap_or_default();
        let runner = self
            .new_runner(&params, seed)
            .map_err(|error| format!("the cell cannot start: {error}"))?;
        self.task = Some(Loaded {
            params,
            seed,
            driver: Driver::new(runner, breakpoints, self.pace),
            commentary: Commentary::default(),
        });
        Ok(())
    }

    fn new_runner(&mut self, params: &TaskParams, seed: u64) -> Result<Runner, DeviceError> {
        let mut runner = Runner::for_task(params.task(), &self.cell, seed)?;
        self.runs += 1;
        let path = self
            .record
            .path(&params.task().task.name, seed)
            .map(|path| numbered(&path, self.runs));
        start_recording(&mut runner, path.as_deref(), self.live.as_ref());
        Ok(runner)
    }

    /// Finishes the current run's recording; returns its breakpoints.
    pub(super) fn end_run(&mut self) -> Option<Breakpoints> {
        let (mut runner, breakpoints) = self.task.take()?.driver.into_parts();
        finish_recording(&mut runner);
        Some(breakpoints)
    }

    pub(super) fn loaded(&mut self) -> Result<&mut Loaded, String> {
        self.task
            .as_mut()
            .ok_or_else(|| "no task loaded: `load TASK` first".to_owned())
    }
}

/// `path` for the first run of a session, `path-N.mcap` for the N-th.
fn numbered(path: &Path, run: usize) -> PathBuf {
    if run <= 1 {
        return path.to_owned();
    }
    let stem = path
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let extension = path
        .extension()
        .map_or_else(String::new, |e| format!(".{}", e.to_string_lossy()));
    path.with_file_name(format!("{stem}-{run}{extension}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn explicit_recording_paths_are_numbered_after_the_first_run() {
        assert_eq!(
            numbered(Path::new("runs/a.mcap"), 1),
            Path::new("runs/a.mcap")
        );
        assert_eq!(
            numbered(Path::new("runs/a.mcap"), 3),
            Path::new("runs/a-3.mcap")
        );
    }
}
