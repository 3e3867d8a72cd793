//! `cablecell repl [TASK]`: step a task on a cell, look at what the
//! sensors see, change a parameter, go on. The session and its run
//! (`session`), the commands (`commands`: one table for dispatch, help and
//! completion), what they show of a run (`show`, the tactile map drawn by
//! `map`), and completion on the terminal (`completion`).

mod commands;
mod completion;
mod map;
mod session;
mod show;

use crate::cli::output::outln;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use cablecell::cell::load_cell;
use rustyline::Editor;
use rustyline::error::ReadlineError;
use rustyline::history::FileHistory;

use super::Status;
use super::run::RecordArgs;
use commands::{Flow, run_line};
use completion::ReplHelper;
use session::Session;

pub fn repl(
    task: Option<&Path>,
    cell_path: &Path,
    seed: Option<u64>,
    record: RecordArgs,
    pace: f64,
) -> Status {
    let cell = match load_cell(cell_path) {
        Ok(cell) => cell,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    let pause = Arc::new(AtomicBool::new(false));
    let mut session = Session {
        cell_path: cell_path.to_owned(),
        cell,
        seed,
        record,
        pace: (pace > 0.0).then_some(pace),
        runs: 0,
        task: None,
        pause,
    };
    if let Some(task) = task
        && let Err(message) = session.load(task)
    {
        eprintln!("error: {message}");
        return Status::BadInput;
    }
    let mut editor = match Editor::<ReplHelper, FileHistory>::new() {
        Ok(editor) => editor,
        Err(error) => {
            eprintln!("error: cannot open the terminal: {error}");
            return Status::BadInput;
        }
    };
    editor.set_helper(Some(ReplHelper::new(&session)));
    // After the editor, which takes SIGINT for itself when it is made:
    // while a line is read the terminal is raw and Ctrl-C arrives as a key;
    // while a task runs it is a signal, and asks for a pause.
    let flag = session.pause.clone();
    if let Err(error) = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst)) {
        eprintln!("warning: Ctrl-C cannot pause a run ({error}); it will stop the program");
    }
    let history = history_path();
    // A missing history file is the first session's normal case.
    let _ = editor.load_history(&history);
    outln!(
        "cablecell repl on {} ({}): `help` lists the commands",
        session.cell.cell.name,
        session.cell_path.display()
    );
    loop {
        let prompt = match &session.task {
            Some(loaded) => format!(
                "{}:{}> ",
                loaded.params.task().task.name,
                loaded.driver.runner().state().name()
            ),
            None => "cablecell> ".to_owned(),
        };
        let line = match editor.readline(&prompt) {
            Ok(line) => line,
            Err(ReadlineError::Interrupted) => {
                outln!("(nothing is running; `quit` leaves)");
                continue;
            }
            Err(ReadlineError::Eof) => break,
            // A byte that is no UTF-8 (a stray key, a paste in another
            // encoding) loses that line only.
            Err(ReadlineError::Io(error)) if error.kind() == std::io::ErrorKind::InvalidData => {
                outln!("cannot: the line is not valid UTF-8; type it again");
                continue;
            }
            Err(error) => {
                eprintln!("error: cannot read the terminal: {error}");
                break;
            }
        };
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let _ = editor.add_history_entry(line);
        if let Err(error) = editor.save_history(&history) {
            tracing::debug!("history not saved to {}: {error}", history.display());
        }
        match run_line(&mut session, line) {
            Ok(Flow::Go) => {}
            Ok(Flow::Quit) => break,
            Err(message) => outln!("cannot: {message}"),
        }
        if let Some(helper) = editor.helper_mut() {
            *helper = ReplHelper::new(&session);
        }
    }
    session.end_run();
    Status::Success
}

/// `$HOME/.cablecell_history`, else in the current folder.
fn history_path() -> PathBuf {
    std::env::var_os("HOME")
        .map_or_else(PathBuf::new, PathBuf::from)
        .join(".cablecell_history")
}
