//! The REPL's commands: one table, from which the line is dispatched,
//! `help` is printed and the arguments are completed.

use crate::cli::output::outln;
use std::path::Path;
use std::sync::atomic::Ordering;

use cablecell::orchestrator::breakpoint::RunValues;
use cablecell::orchestrator::driver::{Mode, Stop};
use cablecell::orchestrator::{Plan, State};

use super::super::run::print_outcome;
use super::session::{Loaded, Session};
use super::show::{next_command, run_over, show_pose, show_state, show_tactile};

/// What the REPL does after a command.
pub(super) enum Flow {
    /// Reads the next line.
    Go,
    /// Leaves.
    Quit,
}

/// A REPL command: everything `help`, completion and dispatch know of it.
pub(super) struct Spec {
    pub(super) name: &'static str,
    /// Short forms, e.g. `s` for `step`.
    aliases: &'static [&'static str],
    /// Its arguments as `help` shows them; empty if it takes none (a
    /// command that takes none refuses any before it runs).
    args: &'static str,
    help: &'static str,
    /// What its arguments complete to.
    pub(super) completes: Completes,
    run: fn(&mut Session, &[&str]) -> Result<Flow, String>,
}

/// What a command's arguments complete to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Completes {
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
pub(super) const COMMANDS: [Spec; 16] = [
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
        run: |session, _| advance(session, Mode::Step),
    },
    Spec {
        name: "continue",
        aliases: &["c"],
        args: "",
        help: "run until a breakpoint, the end, or Ctrl-C (pauses at the next safe point)",
        completes: Completes::Nothing,
        run: |session, _| advance(session, Mode::Continue),
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
        args: "tactile [FILE]|pose|params",
        help: "the last tactile map (with FILE.png|.svg also drawn there, Fig. 7), the arm's pose, the task's parameters",
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
pub(super) fn find(name: &str) -> Option<&'static Spec> {
    COMMANDS
        .iter()
        .find(|spec| spec.name == name || spec.aliases.contains(&name))
}

/// What `show` shows of a topic, given the words after the topic.
type Show = fn(&mut Loaded, &[&str]) -> Result<(), String>;

/// A `show` topic: its name, its arguments as `help` shows them (empty if
/// it takes none), what it shows.
pub(super) struct ShowTopic {
    pub(super) name: &'static str,
    args: &'static str,
    show: Show,
}

/// The topics of `show`, in the order `help` lists them.
pub(super) const SHOW_TOPICS: [ShowTopic; 3] = [
    ShowTopic {
        name: "tactile",
        args: "[FILE]",
        show: |loaded, args| match args {
            [] => show_tactile(loaded, None),
            [file] => show_tactile(loaded, Some(Path::new(file))),
            _ => Err("usage: show tactile [FILE.png|FILE.svg]".into()),
        },
    },
    ShowTopic {
        name: "pose",
        args: "",
        show: |loaded, _| show_pose(loaded),
    },
    ShowTopic {
        name: "params",
        args: "",
        show: |loaded, _| {
            for (name, value) in loaded.params.list() {
                outln!("{name} = {value}");
            }
            Ok(())
        },
    },
];

impl ShowTopic {
    /// Whether its argument is a file name, for completion.
    pub(super) fn takes_file(&self) -> bool {
        self.args == "[FILE]"
    }
}

/// "tactile [FILE]|pose|params": the topics with their arguments.
fn show_usage() -> String {
    let topics: Vec<String> = SHOW_TOPICS
        .iter()
        .map(|t| {
            if t.args.is_empty() {
                t.name.to_owned()
            } else {
                format!("{} {}", t.name, t.args)
            }
        })
        .collect();
    topics.join("|")
}

/// Runs one line: its first word names the command, the rest are its
/// arguments.
pub(super) fn run_line(session: &mut Session, line: &str) -> Result<Flow, String> {
    let mut words = line.split_whitespace();
    let name = words.next().unwrap_or_default();
    let args: Vec<&str> = words.collect();
    let spec = find(name).ok_or_else(|| format!("unknown command `{name}` (`help` lists them)"))?;
    if let (true, Some(extra)) = (spec.args.is_empty(), args.first()) {
        return Err(format!("`{name}` takes no argument (found `{extra}`)"));
    }
    (spec.run)(session, &args)
}

/// `step` and `continue`: runs until `mode` says stop, and says why it
/// stopped.
fn advance(session: &mut Session, mode: Mode) -> Result<Flow, String> {
    let pause = session.pause.clone();
    let loaded = session.loaded()?;
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
            outln!("in {to}{}", next_command(runner));
        }
        Stop::Transition { .. } | Stop::Finished { .. } => {}
        Stop::Breakpoint { id, state } => {
            let breakpoint = loaded.driver.breakpoints().iter().find(|b| b.id == id);
            let condition = breakpoint
                .and_then(|b| b.condition.as_ref())
                .map(|c| format!(" (if {})", c.text()))
                .unwrap_or_default();
            outln!(
                "breakpoint {id} hit on entering {state}{condition}{}",
                next_command(runner)
            );
        }
        Stop::Paused { state } => outln!("paused in {state}{}", next_command(runner)),
    }
    if run_over(runner) {
        outln!("run over in {}", runner.state().name());
        print_outcome(record);
    }
    Ok(Flow::Go)
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
    outln!("reset: {state} (seed {seed})");
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
        outln!("warning: {error}; the run goes on unrecorded");
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
        Some(condition) => outln!("breakpoint {id}: {state} if {condition}"),
        None => outln!("breakpoint {id}: {state}"),
    }
    Ok(Flow::Go)
}

fn list_breaks(session: &mut Session, _: &[&str]) -> Result<Flow, String> {
    let breakpoints = session.loaded()?.driver.breakpoints();
    if breakpoints.iter().next().is_none() {
        outln!("no breakpoints");
    }
    for breakpoint in breakpoints.iter() {
        outln!("{breakpoint}");
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
    outln!("deleted breakpoint {id}");
    Ok(Flow::Go)
}

fn state(session: &mut Session, _: &[&str]) -> Result<Flow, String> {
    show_state(session.loaded()?);
    Ok(Flow::Go)
}

fn show(session: &mut Session, args: &[&str]) -> Result<Flow, String> {
    let topic = match args {
        [name, rest @ ..] => SHOW_TOPICS
            .iter()
            .find(|t| t.name == *name)
            .filter(|t| !t.args.is_empty() || rest.is_empty())
            .map(|t| (t, rest)),
        [] => None,
    };
    let Some((topic, rest)) = topic else {
        return Err(format!("usage: show {}", show_usage()));
    };
    (topic.show)(session.loaded()?, rest)?;
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
    outln!("{param} = {value} (from the next command on)");
    if let Err(error) = recorded {
        outln!("warning: {error}; the run goes on unrecorded");
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
        outln!("{name:>22} = {value:<12} {}", RunValues::describe(name));
    }
    Ok(Flow::Go)
}

fn print_help() {
    outln!("commands:");
    for spec in &COMMANDS {
        outln!(
            "  {:<28} {}",
            format!("{} {}", spec.name, spec.args),
            spec.help
        );
    }
    let short: Vec<_> = COMMANDS.iter().filter(|s| !s.aliases.is_empty()).collect();
    outln!(
        "({} also as {})",
        and_list(short.iter().map(|spec| spec.name)),
        and_list(short.iter().flat_map(|spec| spec.aliases.iter().copied()))
    );
    outln!("states: {}", State::NAMES.join(", "));
    outln!("values for `break STATE if EXPR` (`values` shows them now):");
    outln!("  {}", RunValues::NAMES.join(", "));
    outln!("  with numbers, + - * /, abs(...), < <= > >= == !=, and, or, not");
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

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(find("show").map(|s| s.args), Some(show_usage().as_str()));
        assert_eq!(and_list(["s", "c", "b"].into_iter()), "s, c and b");
    }
}
