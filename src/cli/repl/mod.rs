//! `cablecell repl [TASK]`: step a task on a cell, look at what the
//! sensors see, change a parameter, go on.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use cablecell::cell::CellFile;
use cablecell::hw::DeviceError;
use cablecell::orchestrator::breakpoint::RunValues;
use cablecell::orchestrator::driver::{Driver, Mode, Stop};
use cablecell::orchestrator::params::TaskParams;
use cablecell::orchestrator::{Command, Plan, Runner, State};
use cablecell::perception::tactile::{Estimate, TAXEL_COLS, TAXEL_ROWS, TactileMap};
use cablecell::task::load_cell;
use rustyline::completion::{Completer, FilenameCompleter, Pair};
use rustyline::error::ReadlineError;
use rustyline::highlight::Highlighter;
use rustyline::hint::Hinter;
use rustyline::history::FileHistory;
use rustyline::validate::Validator;
use rustyline::{Editor, Helper};

use super::Status;
use super::run::{
    Commentary, RecordArgs, finish_recording, print_outcome, print_transition, start_recording,
};

/// A REPL command: everything `help`, completion and dispatch know of it.
struct Spec {
    name: &'static str,
    /// Short forms, e.g. `s` for `step`.
    aliases: &'static [&'static str],
    /// Its arguments as `help` shows them; empty if it takes none (a
    /// command that takes none refuses any before it runs).
    args: &'static str,
    help: &'static str,
    /// What its arguments complete to.
    completes: Completes,
    run: fn(&mut Session, &[&str]) -> Result<Flow, String>,
}

/// What a command's arguments complete to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Completes {
    Nothing,
    /// A file name.
    File,
    /// A state, then `if`, then the values and operators of a condition.
    Breakpoint,
    /// A `show` topic.
    Topic,
    /// A task parameter's name.
    Param,
    /// A command's name.
    Command,
}

/// The commands, in the order `help` lists them.
const COMMANDS: [Spec; 16] = [
    Spec {
        name: "load",
        aliases: &[],
        args: "TASK",
        help: "load a task file and start a new run of it",
        completes: Completes::File,
        run: load,
    },
    Spec {
        name: "reset",
        aliases: &[],
        args: "",
        help: "start the task again from idle (same seed, same parameters)",
        completes: Completes::Nothing,
        run: reset,
    },
    Spec {
        name: "step",
        aliases: &["s"],
        args: "",
        help: "run until the next state transition",
        completes: Completes::Nothing,
        run: |session, _| session.advance(Mode::Step),
    },
    Spec {
        name: "continue",
        aliases: &["c"],
        args: "",
        help: "run until a breakpoint, the end, or Ctrl-C (pauses at the next safe point)",
        completes: Completes::Nothing,
        run: |session, _| session.advance(Mode::Continue),
    },
    Spec {
        name: "pause",
        aliases: &[],
        args: "",
        help: "Ctrl-C pauses a running `continue`; between commands the run is already paused",
        completes: Completes::Nothing,
        run: pause,
    },
    Spec {
        name: "abort",
        aliases: &[],
        args: "",
        help: "stop the run: the cell is made safe (arm stopped, jaws opened)",
        completes: Completes::Nothing,
        run: abort,
    },
    Spec {
        name: "break",
        aliases: &["b"],
        args: "STATE [if EXPR]",
        help: "stop on entering STATE, if EXPR holds (e.g. abs(n_mm) > 2)",
        completes: Completes::Breakpoint,
        run: add_break,
    },
    Spec {
        name: "breaks",
        aliases: &[],
        args: "",
        help: "list the breakpoints",
        completes: Completes::Nothing,
        run: list_breaks,
    },
    Spec {
        name: "delete",
        aliases: &[],
        args: "N",
        help: "delete breakpoint N",
        completes: Completes::Nothing,
        run: delete_break,
    },
    Spec {
        name: "state",
        aliases: &[],
        args: "",
        help: "the current state, the pending command, the last transitions",
        completes: Completes::Nothing,
        run: state,
    },
    Spec {
        name: "show",
        aliases: &[],
        args: "tactile|pose|params",
        help: "the last tactile map, the arm's pose, the task's parameters",
        completes: Completes::Topic,
        run: show,
    },
    Spec {
        name: "set",
        aliases: &[],
        args: "PARAM VALUE",
        help: "change a task parameter, checked like the task file",
        completes: Completes::Param,
        run: set,
    },
    Spec {
        name: "values",
        aliases: &[],
        args: "",
        help: "the run's values a breakpoint condition can use",
        completes: Completes::Nothing,
        run: values,
    },
    Spec {
        name: "help",
        aliases: &[],
        args: "",
        help: "this list",
        completes: Completes::Command,
        run: |_, _| {
            print_help();
            Ok(Flow::Go)
        },
    },
    Spec {
        name: "quit",
        aliases: &[],
        args: "",
        help: "leave (Ctrl-D too)",
        completes: Completes::Nothing,
        run: |_, _| Ok(Flow::Quit),
    },
    Spec {
        name: "exit",
        aliases: &[],
        args: "",
        help: "same as quit",
        completes: Completes::Nothing,
        run: |_, _| Ok(Flow::Quit),
    },
];

/// The command called `name`, by its name or a short form.
fn find(name: &str) -> Option<&'static Spec> {
    COMMANDS
        .iter()
        .find(|spec| spec.name == name || spec.aliases.contains(&name))
}

/// The topics of `show`, in the order `help` lists them.
const SHOW_TOPICS: [(&str, fn(&mut Loaded) -> Result<(), String>); 3] = [
    ("tactile", |loaded| show_tactile(loaded)),
    ("pose", show_pose),
    ("params", |loaded| {
        for (name, value) in loaded.params.list() {
            println!("{name} = {value}");
        }
        Ok(())
    }),
];

/// A REPL session: the cell, the loaded task and its run.
struct Session {
    cell_path: PathBuf,
    cell: CellFile,
    seed: Option<u64>,
    record: RecordArgs,
    pace: Option<f64>,
    /// Runs recorded so far, to number the files of an explicit `--record`.
    runs: usize,
    task: Option<Loaded>,
    /// Set by Ctrl-C while a task runs.
    pause: Arc<AtomicBool>,
}

struct Loaded {
    params: TaskParams,
    seed: u64,
    driver: Driver,
    commentary: Commentary,
}

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
    println!(
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
                println!("(nothing is running; `quit` leaves)");
                continue;
            }
            Err(ReadlineError::Eof) => break,
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
        match session.command(line) {
            Ok(Flow::Go) => {}
            Ok(Flow::Quit) => break,
            Err(message) => println!("cannot: {message}"),
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

enum Flow {
    Go,
    Quit,
}

impl Session {
    fn load(&mut self, path: &Path) -> Result<(), String> {
        let params = TaskParams::load(path).map_err(|e| e.to_string())?;
        let seed = self
            .seed
            .or(params.task().task.seed)
            .unwrap_or_else(rand::random);
        println!(
            "loaded task {} from {} (seed {seed})",
            params.task().task.name,
            path.display()
        );
        self.start(params, seed)
    }

    /// Ends the current run, if any, and starts a new one from idle; the
    /// breakpoints carry over.
    fn start(&mut self, params: TaskParams, seed: u64) -> Result<(), String> {
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
        start_recording(&mut runner, path.as_deref());
        Ok(runner)
    }

    /// Finishes the current run's recording; returns its breakpoints.
    fn end_run(&mut self) -> Option<cablecell::orchestrator::breakpoint::Breakpoints> {
        let (mut runner, breakpoints) = self.task.take()?.driver.into_parts();
        finish_recording(&mut runner);
        Some(breakpoints)
    }

    fn loaded(&mut self) -> Result<&mut Loaded, String> {
        self.task
            .as_mut()
            .ok_or_else(|| "no task loaded: `load TASK` first".to_owned())
    }

    /// Runs one line: its first word names the command, the rest are its
    /// arguments.
    fn command(&mut self, line: &str) -> Result<Flow, String> {
        let mut words = line.split_whitespace();
        let name = words.next().unwrap_or_default();
        let args: Vec<&str> = words.collect();
        let spec =
            find(name).ok_or_else(|| format!("unknown command `{name}` (`help` lists them)"))?;
        if let (true, Some(extra)) = (spec.args.is_empty(), args.first()) {
            return Err(format!("`{name}` takes no argument (found `{extra}`)"));
        }
        (spec.run)(self, &args)
    }

    fn advance(&mut self, mode: Mode) -> Result<Flow, String> {
        let pause = self.pause.clone();
        let loaded = self.loaded()?;
        if run_over(loaded.driver.runner()) {
            return Err(format!(
                "the run is over ({}): `reset` starts it again",
                loaded.driver.runner().state().name()
            ));
        }
        // A Ctrl-C pressed while nothing ran is not a request to pause this.
        pause.store(false, Ordering::SeqCst);
        let commentary = &mut loaded.commentary;
        let stop = loaded
            .driver
            .advance(mode, &pause, |runner| commentary.print_new(runner.record()));
        let stop = stop.map_err(|e| format!("{e}; the run goes on unrecorded"))?;
        let runner = loaded.driver.runner();
        let record = runner.record();
        match stop {
            Stop::Transition { to, .. } if !run_over(runner) => {
                println!("in {to}{}", next_command(runner));
            }
            Stop::Transition { .. } | Stop::Finished { .. } => {}
            Stop::Breakpoint { id, state } => {
                let breakpoint = loaded.driver.breakpoints().iter().find(|b| b.id == id);
                let condition = breakpoint
                    .and_then(|b| b.condition.as_ref())
                    .map(|c| format!(" (if {})", c.text()))
                    .unwrap_or_default();
                println!(
                    "breakpoint {id} hit on entering {state}{condition}{}",
                    next_command(runner)
                );
            }
            Stop::Paused { state } => println!("paused in {state}{}", next_command(runner)),
        }
        if run_over(runner) {
            println!("run over in {}", runner.state().name());
            print_outcome(record);
        }
        Ok(Flow::Go)
    }
}

fn load(session: &mut Session, args: &[&str]) -> Result<Flow, String> {
    match args {
        [path] => session.load(Path::new(path)).map(|()| Flow::Go),
        _ => Err("usage: load TASK".into()),
    }
}

fn reset(session: &mut Session, _: &[&str]) -> Result<Flow, String> {
    let (params, seed) = {
        let loaded = session.loaded()?;
        (loaded.params.clone(), loaded.seed)
    };
    session.start(params, seed)?;
    let state = session.loaded()?.driver.runner().state().name();
    println!("reset: {state} (seed {seed})");
    Ok(Flow::Go)
}

fn pause(session: &mut Session, _: &[&str]) -> Result<Flow, String> {
    session.loaded()?;
    Err("nothing is running: the run is paused between commands already; Ctrl-C pauses a `continue`".into())
}

fn abort(session: &mut Session, _: &[&str]) -> Result<Flow, String> {
    let loaded = session.loaded()?;
    let commentary = &mut loaded.commentary;
    let recording_error = loaded
        .driver
        .abort(|runner| commentary.print_new(runner.record()))
        .map_err(|nothing| nothing.to_string())?;
    if let Some(error) = recording_error {
        println!("warning: {error}; the run goes on unrecorded");
    }
    print_outcome(loaded.driver.runner().record());
    Ok(Flow::Go)
}

fn add_break(session: &mut Session, args: &[&str]) -> Result<Flow, String> {
    let (state, condition) = match args {
        [state] => (*state, None),
        [state, "if", condition @ ..] if !condition.is_empty() => {
            (*state, Some(condition.join(" ")))
        }
        _ => return Err("usage: break STATE [if EXPR]".into()),
    };
    let loaded = session.loaded()?;
    let id = loaded
        .driver
        .breakpoints_mut()
        .add(state, condition.as_deref())
        .map_err(|e| e.to_string())?;
    match condition {
        Some(condition) => println!("breakpoint {id}: {state} if {condition}"),
        None => println!("breakpoint {id}: {state}"),
    }
    Ok(Flow::Go)
}

fn list_breaks(session: &mut Session, _: &[&str]) -> Result<Flow, String> {
    let breakpoints = session.loaded()?.driver.breakpoints();
    if breakpoints.iter().next().is_none() {
        println!("no breakpoints");
    }
    for breakpoint in breakpoints.iter() {
        println!("{breakpoint}");
    }
    Ok(Flow::Go)
}

fn delete_break(session: &mut Session, args: &[&str]) -> Result<Flow, String> {
    let [id] = args else {
        return Err("usage: delete N".into());
    };
    let id: usize = id
        .parse()
        .map_err(|_| format!("`{id}` is not a breakpoint number"))?;
    if !session.loaded()?.driver.breakpoints_mut().delete(id) {
        return Err(format!("there is no breakpoint {id} (`breaks` lists them)"));
    }
    println!("deleted breakpoint {id}");
    Ok(Flow::Go)
}

fn state(session: &mut Session, _: &[&str]) -> Result<Flow, String> {
    show_state(session.loaded()?);
    Ok(Flow::Go)
}

fn show(session: &mut Session, args: &[&str]) -> Result<Flow, String> {
    let topic = match args {
        [topic] => SHOW_TOPICS.iter().find(|(name, _)| name == topic),
        _ => None,
    };
    let Some((_, show)) = topic else {
        let topics: Vec<_> = SHOW_TOPICS.iter().map(|(name, _)| *name).collect();
        return Err(format!("usage: show {}", topics.join("|")));
    };
    show(session.loaded()?)?;
    Ok(Flow::Go)
}

fn set(session: &mut Session, args: &[&str]) -> Result<Flow, String> {
    let [param, value @ ..] = args else {
        return Err(SET_USAGE.into());
    };
    if value.is_empty() {
        return Err(SET_USAGE.into());
    }
    let value = value.join(" ");
    let cell = session.cell.clone();
    let loaded = session.loaded()?;
    loaded
        .params
        .set(param, &value)
        .map_err(|e| e.to_string())?;
    let recorded = loaded
        .driver
        .set_plan(Plan::new(loaded.params.task(), &cell));
    println!("{param} = {value} (from the next command on)");
    if let Err(error) = recorded {
        println!("warning: {error}; the run goes on unrecorded");
    }
    Ok(Flow::Go)
}

const SET_USAGE: &str = "usage: set PARAM VALUE (`show params` lists them)";

fn values(session: &mut Session, _: &[&str]) -> Result<Flow, String> {
    let values = RunValues::of(session.loaded()?.driver.runner().record());
    for name in RunValues::NAMES {
        let value = values
            .get(name)
            .map_or("(none yet)".to_owned(), |v| format!("{v:.4}"));
        println!("{name:>22} = {value:<12} {}", RunValues::describe(name));
    }
    Ok(Flow::Go)
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

/// In a final state with nothing left to carry out.
fn run_over(runner: &Runner) -> bool {
    runner.state().is_final() && runner.pending_command().is_none()
}

fn next_command(runner: &Runner) -> String {
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
        Command::SafeStop { .. } => "safe stop (stop the arm, open the jaws)",
    }
}

fn print_help() {
    println!("commands:");
    for spec in &COMMANDS {
        println!(
            "  {:<28} {}",
            format!("{} {}", spec.name, spec.args),
            spec.help
        );
    }
    let short: Vec<_> = COMMANDS.iter().filter(|s| !s.aliases.is_empty()).collect();
    println!(
        "({} also as {})",
        and_list(short.iter().map(|spec| spec.name)),
        and_list(short.iter().flat_map(|spec| spec.aliases.iter().copied()))
    );
    println!("states: {}", State::NAMES.join(", "));
    println!("values for `break STATE if EXPR` (`values` shows them now):");
    println!("  {}", RunValues::NAMES.join(", "));
    println!("  with numbers, + - * /, abs(...), < <= > >= == !=, and, or, not");
}

/// `a, b and c`.
fn and_list<'a>(items: impl Iterator<Item = &'a str>) -> String {
    let items: Vec<&str> = items.collect();
    match items.split_last() {
        Some((last, [])) => (*last).to_owned(),
        Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
        None => String::new(),
    }
}

fn show_state(loaded: &Loaded) {
    let runner = loaded.driver.runner();
    let record = runner.record();
    println!(
        "state {} at {:.3} s{}",
        runner.state().name(),
        runner.now_s(),
        next_command(runner)
    );
    let first = record.transitions.len().saturating_sub(8);
    if first > 0 {
        println!("  ({first} earlier transitions)");
    }
    for (i, t) in record.transitions.iter().enumerate().skip(first) {
        print_transition(record, i, t);
    }
    if let Some(entered) = record.transitions.last() {
        println!(
            "  in {} for {:.3} s",
            entered.to,
            runner.now_s() - entered.t_s
        );
    }
    if record.outcome.is_some() {
        print_outcome(record);
    }
}

fn show_pose(loaded: &mut Loaded) -> Result<(), String> {
    let base_from_tcp = loaded
        .driver
        .base_from_tcp()
        .map_err(|e| format!("the arm did not answer: {e}"))?;
    println!("arm TCP in base now:      {}", pose_text(&base_from_tcp));
    if let Some(grasp) = loaded.driver.runner().record().grasps.last() {
        println!(
            "at the latest grasp ({}): {}",
            attempt_name(grasp.attempt),
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

fn attempt_name(attempt: u32) -> String {
    match attempt {
        0 => "trial grasp".into(),
        k => format!("regrasp {k}"),
    }
}

/// Canvas cells per taxel: terminal cells are about twice as tall as wide.
const CELL_COLS: usize = 8;
const CELL_ROWS: usize = 4;
const SHADES: [char; 5] = [' ', '░', '▒', '▓', '█'];

fn show_tactile(loaded: &Loaded) -> Result<(), String> {
    let record = loaded.driver.runner().record();
    let grasp = record
        .grasps
        .last()
        .ok_or("no tactile map yet: the first one is read after the trial grasp")?;
    let pitch_mm = loaded.driver.runner().plan().fit.pitch_mm;
    let line = grasp.fit.as_ref().map(Estimate::line);
    let centroids: Vec<(f64, f64)> = match &grasp.fit {
        Some(Estimate::Centroids(fit)) => fit.centroids.iter().map(|c| (c.x_mm, c.y_mm)).collect(),
        _ => Vec::new(),
    };
    println!(
        "{} at {:.3} s: mean Δv, peak {:.3} V (shading ∝ Δv; o centroid, * fitted line)",
        attempt_name(grasp.attempt),
        grasp.t_s,
        grasp.map.peak_dv_v()
    );
    for row in draw_map(&grasp.map, pitch_mm, line, &centroids) {
        println!("  |{row}|");
    }
    println!("Δv (mV), rows c1j (top, +y) to c5j, columns ci1 (left) to ci5 (+x):");
    for row in 0..TAXEL_ROWS {
        let values: Vec<String> = (0..TAXEL_COLS)
            .map(|col| format!("{:7.1}", grasp.map.dv_v[row][col] * 1000.0))
            .collect();
        println!("  {}", values.join(""));
    }
    match (&grasp.fit, line) {
        (Some(fit), Some(line)) => {
            let name = match fit {
                Estimate::Centroids(_) => "centroids",
                Estimate::Ridge(_) => "ridge",
                Estimate::Oracle { .. } => "oracle",
            };
            println!(
                "fitted line ({name}): n {:+.3} mm, α {:+.4} rad",
                line.offset_mm, line.alpha_rad
            );
        }
        _ => println!("no fitted line: the fit failed"),
    }
    if let Some(truth) = &grasp.truth {
        println!(
            "true line:            n {:+.3} mm, α {:+.4} rad",
            truth.line.offset_mm, truth.line.alpha_rad
        );
    }
    Ok(())
}

/// The map drawn on a character canvas in the sensor frame (x right, y up),
/// with the line and the centroids over it.
fn draw_map(
    map: &TactileMap,
    pitch_mm: f64,
    line: Option<cablecell::geometry::LineInSensor>,
    centroids: &[(f64, f64)],
) -> Vec<String> {
    let (width, height) = (TAXEL_COLS * CELL_COLS, TAXEL_ROWS * CELL_ROWS);
    let peak = map.peak_dv_v().max(1e-9);
    let x_mm = |cx: usize| ((cx as f64 + 0.5) / CELL_COLS as f64 - 2.5) * pitch_mm;
    let y_mm = |cy: usize| (2.5 - (cy as f64 + 0.5) / CELL_ROWS as f64) * pitch_mm;
    let mut canvas: Vec<Vec<char>> = (0..height)
        .map(|cy| {
            (0..width)
                .map(|cx| {
                    let dv = map.dv_v[cy / CELL_ROWS][cx / CELL_COLS].max(0.0);
                    let level = ((dv / peak) * (SHADES.len() - 1) as f64).round() as usize;
                    SHADES[level.min(SHADES.len() - 1)]
                })
                .collect()
        })
        .collect();
    if let Some(line) = line {
        let (sin, cos) = line.alpha_rad.sin_cos();
        // A canvas cell is marked if the line crosses it: its centre lies
        // within the cell's half extent along the line's normal.
        let (cell_w_mm, cell_h_mm) = (pitch_mm / CELL_COLS as f64, pitch_mm / CELL_ROWS as f64);
        let half_extent_mm = 0.5 * (sin.abs() * cell_w_mm + cos.abs() * cell_h_mm);
        for (cy, row) in canvas.iter_mut().enumerate() {
            for (cx, cell) in row.iter_mut().enumerate() {
                let distance_mm = -sin * x_mm(cx) + cos * y_mm(cy) - line.offset_mm;
                if distance_mm.abs() <= half_extent_mm {
                    *cell = '*';
                }
            }
        }
    }
    for &(x, y) in centroids {
        let cx = ((x / pitch_mm + 2.5) * CELL_COLS as f64).floor();
        let cy = ((2.5 - y / pitch_mm) * CELL_ROWS as f64).floor();
        if (0.0..width as f64).contains(&cx) && (0.0..height as f64).contains(&cy) {
            canvas[cy as usize][cx as usize] = 'o';
        }
    }
    canvas
        .into_iter()
        .map(|row| row.into_iter().collect())
        .collect()
}

/// Completion of commands, states, parameters, `show` topics, value
/// names in conditions, and file names for `load`.
struct ReplHelper {
    params: Vec<String>,
    files: FilenameCompleter,
}

impl ReplHelper {
    fn new(session: &Session) -> Self {
        Self {
            params: session
                .task
                .as_ref()
                .map(|t| t.params.names())
                .unwrap_or_default(),
            files: FilenameCompleter::new(),
        }
    }
}

impl Completer for ReplHelper {
    type Candidate = Pair;

    fn complete(
        &self,
        line: &str,
        pos: usize,
        ctx: &rustyline::Context<'_>,
    ) -> rustyline::Result<(usize, Vec<Pair>)> {
        let before = &line[..pos];
        let start = before.rfind(char::is_whitespace).map_or(0, |i| i + 1);
        let word = &before[start..];
        let words: Vec<&str> = before[..start].split_whitespace().collect();
        let names = || COMMANDS.iter().map(|spec| spec.name.to_owned()).collect();
        let candidates: Vec<String> = match words.as_slice() {
            [] => names(),
            [command, args @ ..] => match (find(command).map(|spec| spec.completes), args) {
                (Some(Completes::File), []) => return self.files.complete(line, pos, ctx),
                (Some(Completes::Breakpoint), []) => {
                    State::NAMES.iter().map(|s| (*s).to_owned()).collect()
                }
                (Some(Completes::Breakpoint), [_]) => vec!["if".to_owned()],
                (Some(Completes::Breakpoint), [_, "if", ..]) => RunValues::NAMES
                    .iter()
                    .map(|s| (*s).to_owned())
                    .chain(["abs(", "and", "or", "not"].map(str::to_owned))
                    .collect(),
                (Some(Completes::Topic), []) => SHOW_TOPICS
                    .iter()
                    .map(|(name, _)| (*name).to_owned())
                    .collect(),
                (Some(Completes::Param), []) => self.params.clone(),
                (Some(Completes::Command), []) => names(),
                _ => Vec::new(),
            },
        };
        let pairs = candidates
            .into_iter()
            .filter(|c| c.starts_with(word))
            .map(|c| Pair {
                // A finished word is followed by a space, ready for the next.
                replacement: if c.ends_with('(') {
                    c.clone()
                } else {
                    format!("{c} ")
                },
                display: c,
            })
            .collect();
        Ok((start, pairs))
    }
}

impl Hinter for ReplHelper {
    type Hint = String;
}

impl Highlighter for ReplHelper {}

impl Validator for ReplHelper {}

impl Helper for ReplHelper {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_horizontal_line_near_the_middle_marks_the_row_it_crosses() {
        let map = TactileMap::from_fn(|row, _| if row == 2 { 0.5 } else { 0.0 });
        let line = cablecell::geometry::LineInSensor::new(0.0, 0.1);
        let rows = draw_map(&map, 3.55, Some(line), &[(0.0, 0.0)]);
        assert_eq!(rows.len(), TAXEL_ROWS * CELL_ROWS);
        let marked: Vec<usize> = rows
            .iter()
            .enumerate()
            .filter(|(_, r)| r.contains('*'))
            .map(|(i, _)| i)
            .collect();
        assert_eq!(marked, [9]);
        assert_eq!(
            rows[9].chars().filter(|c| *c == '*').count(),
            TAXEL_COLS * CELL_COLS
        );
        assert_eq!(rows[10].chars().nth(20), Some('o'));
        assert!(rows[0].chars().all(|c| c == ' '));
        assert!(rows[8].contains('█'));
    }

    #[test]
    fn every_command_and_short_form_is_found_once() {
        let mut seen = std::collections::BTreeSet::new();
        for spec in &COMMANDS {
            for name in std::iter::once(&spec.name).chain(spec.aliases) {
                assert!(seen.insert(*name), "`{name}` twice");
                assert_eq!(find(name).map(|s| s.name), Some(spec.name));
            }
        }
        assert!(find("frobnicate").is_none());
        // `help` shows the topics `show` takes.
        let topics: Vec<_> = SHOW_TOPICS.iter().map(|(name, _)| *name).collect();
        assert_eq!(
            find("show").map(|s| s.args),
            Some(topics.join("|").as_str())
        );
        assert_eq!(and_list(["s", "c", "b"].into_iter()), "s, c and b");
    }

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
