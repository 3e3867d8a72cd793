//! `cablecell repl` driven through a pseudo-terminal, as an operator
//! would: stepping the whole regrasp task, breakpoints with conditions,
//! refused commands, Ctrl-C during `continue`, a break in a search by
//! touch, and leaving.

use std::path::Path;

mod common;

use cablecell::orchestrator::State;
use rexpect::session::{PtySession, spawn_command};

/// The REPL on the regrasp task, seed 3, on the simulated cell with an
/// oracle detector (the trial grasp lands at n = -2.386 mm, α = -0.124
/// rad; one regrasp reaches tolerance), with `home` as its home folder
/// (for the history file).
fn repl(home: &Path, pace: &str, extra: &[&str]) -> PtySession {
    repl_on(home, "tasks/regrasp.toml", pace, extra)
}

/// The same on the task file `task` (named `regrasp` too).
fn repl_on(home: &Path, task: &str, pace: &str, extra: &[&str]) -> PtySession {
    let cell = common::sim_cell_with_oracle_file(home);
    let mut command = common::command();
    command
        .args(["repl", task, "--seed", "3", "--pace", pace])
        .args(["--cell", cell.to_str().expect("utf-8")])
        .args(extra)
        .env("HOME", home)
        .env("TERM", "xterm")
        .env_remove("RUST_LOG");
    let mut session = spawn_command(command, Some(30_000)).expect("the repl starts");
    expect(&mut session, "loaded task regrasp");
    session
}

/// Waits for `text` in the output. rexpect reads the terminal a byte at a
/// time, one char per byte, so UTF-8 text is looked for byte by byte.
fn expect(session: &mut PtySession, text: &str) {
    let as_read: String = text.bytes().map(char::from).collect();
    if let Err(error) = session.exp_string(&as_read) {
        panic!("expected {text:?}: {error}");
    }
}

fn prompt(session: &mut PtySession, state: State) {
    expect(session, &format!("regrasp:{}> ", state.name()));
}

/// A transition as the REPL shows it.
fn arrow(from: State, to: State) -> String {
    format!("{} → {}", from.name(), to.name())
}

fn send(session: &mut PtySession, line: &str) {
    session.send_line(line).expect("the repl reads");
}

fn quit(mut session: PtySession) {
    send(&mut session, "quit");
    session.exp_eof().expect("the repl ends");
    // nix's WaitStatus, which rexpect does not re-export: Exited(pid, 0).
    let status = format!("{:?}", session.process().wait().expect("the repl exits"));
    assert!(
        status.starts_with("Exited(") && status.ends_with(", 0)"),
        "{status}"
    );
}

#[test]
fn step_through_the_whole_regrasp_task() {
    let home = tempfile::tempdir().unwrap();
    let mut s = repl(home.path(), "0", &["--no-record"]);
    prompt(&mut s, State::Idle {});
    let mut previous = State::Idle {};
    for state in common::ONE_REGRASP_PATH {
        send(&mut s, "step");
        expect(&mut s, &arrow(previous, state));
        if state != (State::Done {}) {
            expect(&mut s, &format!("in {}; next: ", state.name()));
            prompt(&mut s, state);
        }
        if state == (State::Regrasp {}) {
            // The trial grasp's map, its centroids and its line, drawn.
            send(&mut s, "show tactile");
            expect(&mut s, "trial grasp at 3.289 s: mean Δv");
            expect(
                &mut s,
                "fitted line (centroids): n -2.386 mm, α -0.1237 rad",
            );
            expect(&mut s, "true line:");
            prompt(&mut s, state);
            send(&mut s, "show pose");
            expect(&mut s, "arm TCP in base now:");
            expect(&mut s, "at the latest grasp (trial grasp):");
            prompt(&mut s, state);
        }
        previous = state;
    }
    // Entering `done` ends the run.
    expect(&mut s, "run over in done");
    expect(&mut s, "success: within tolerance");
    prompt(&mut s, State::Done {});
    send(&mut s, "step");
    expect(
        &mut s,
        "cannot: the run is over (done): `reset` starts it again",
    );
    prompt(&mut s, State::Done {});
    send(&mut s, "state");
    expect(&mut s, "state done");
    expect(&mut s, &arrow(State::Verify {}, State::Done {}));
    prompt(&mut s, State::Done {});
    send(&mut s, "reset");
    expect(&mut s, "reset: idle (seed 3)");
    prompt(&mut s, State::Idle {});
    quit(s);
}

#[test]
fn a_conditional_breakpoint_fires_and_another_does_not() {
    let home = tempfile::tempdir().unwrap();
    let mut s = repl(home.path(), "0", &["--no-record"]);
    prompt(&mut s, State::Idle {});
    send(&mut s, "break regrasp if abs(n_mm > 2");
    expect(
        &mut s,
        "cannot: in the condition, column 5: expected a number",
    );
    prompt(&mut s, State::Idle {});
    send(&mut s, "break regrasp if abs(n_mm) > 2");
    expect(&mut s, "breakpoint 1: regrasp if abs(n_mm) > 2");
    prompt(&mut s, State::Idle {});
    // At `done` the latest estimate is the regrasp's, -0.586 mm.
    send(&mut s, "break done if abs(n_mm) > 2");
    expect(&mut s, "breakpoint 2: done if abs(n_mm) > 2");
    prompt(&mut s, State::Idle {});
    send(&mut s, "continue");
    expect(&mut s, &arrow(State::Evaluate {}, State::Regrasp {}));
    expect(
        &mut s,
        "breakpoint 1 hit on entering regrasp (if abs(n_mm) > 2)",
    );
    prompt(&mut s, State::Regrasp {});
    send(&mut s, "values");
    expect(&mut s, "n_mm = -2.386");
    prompt(&mut s, State::Regrasp {});
    send(&mut s, "continue");
    expect(&mut s, &arrow(State::Verify {}, State::Done {}));
    expect(&mut s, "run over in done");
    prompt(&mut s, State::Done {});
    send(&mut s, "breaks");
    expect(&mut s, "1: regrasp if abs(n_mm) > 2 (hit 1 times)");
    expect(&mut s, "2: done if abs(n_mm) > 2 (hit 0 times)");
    prompt(&mut s, State::Done {});
    send(&mut s, "delete 7");
    expect(&mut s, "cannot: there is no breakpoint 7");
    prompt(&mut s, State::Done {});
    quit(s);
}

#[test]
fn set_checks_values_like_the_task_file_and_takes_effect() {
    let home = tempfile::tempdir().unwrap();
    let mut s = repl(home.path(), "0", &["--no-record"]);
    prompt(&mut s, State::Idle {});
    send(&mut s, "set tolerance.n_mm -1");
    expect(
        &mut s,
        "cannot: tolerance.n_mm: expected a number > 0, found -1",
    );
    prompt(&mut s, State::Idle {});
    send(&mut s, "set tolerance.n_m 1");
    expect(&mut s, "cannot: unknown parameter `tolerance.n_m`");
    prompt(&mut s, State::Idle {});
    send(&mut s, "frobnicate");
    expect(&mut s, "cannot: unknown command `frobnicate`");
    prompt(&mut s, State::Idle {});
    // Loose enough that the trial grasp (-2.386 mm, -0.124 rad) will do.
    send(&mut s, "set tolerance.n_mm 3");
    expect(&mut s, "tolerance.n_mm = 3 (from the next command on)");
    prompt(&mut s, State::Idle {});
    send(&mut s, "set tolerance.alpha_rad 0.2");
    prompt(&mut s, State::Idle {});
    // Tab completes the command and the parameter.
    s.send("sho\tpar\t").unwrap();
    send(&mut s, "");
    expect(&mut s, "tolerance.n_mm = 3");
    prompt(&mut s, State::Idle {});
    send(&mut s, "continue");
    expect(&mut s, &arrow(State::Evaluate {}, State::Done {}));
    expect(&mut s, "after 0 regrasp(s)");
    prompt(&mut s, State::Done {});
    quit(s);
}

#[test]
fn ctrl_c_during_continue_pauses_at_a_safe_point_and_the_run_goes_on() {
    let home = tempfile::tempdir().unwrap();
    let recording = home.path().join("run.mcap");
    let record = recording.to_str().unwrap();
    // At the pace of a real cell the run takes 4.5 s of wall time.
    let mut s = repl(home.path(), "1", &["--record", record]);
    prompt(&mut s, State::Idle {});
    send(&mut s, "continue");
    expect(&mut s, &arrow(State::Prepare {}, State::Detect {}));
    s.send_control('c').unwrap();
    let (_, paused) = s.exp_regex("paused in [a-z_]+").unwrap();
    let state = State::named(paused.trim_start_matches("paused in ")).expect("a state");
    // Anywhere from detect to verify.
    assert!(common::ONE_REGRASP_PATH[1..7].contains(&state), "{paused}");
    prompt(&mut s, state);
    send(&mut s, "continue");
    expect(&mut s, "run over in done");
    prompt(&mut s, State::Done {});
    quit(s);
    // The history and the recording are kept.
    let history = std::fs::read_to_string(home.path().join(".cablecell_history")).unwrap();
    assert!(history.contains("continue"), "{history}");
    let recorded = cablecell::recording::Recording::read(&recording).unwrap();
    assert!(recorded.truncated.is_none());
    assert_eq!(recorded.count(cablecell::recording::Topic::State), 8);
}

#[test]
fn abort_makes_the_cell_safe_and_refuses_what_cannot_be_done() {
    let home = tempfile::tempdir().unwrap();
    let mut s = repl(home.path(), "0", &["--no-record"]);
    prompt(&mut s, State::Idle {});
    send(&mut s, "abort");
    expect(&mut s, "cannot: the run has not started: nothing to abort");
    prompt(&mut s, State::Idle {});
    send(&mut s, "show tactile");
    expect(&mut s, "cannot: no tactile map yet");
    prompt(&mut s, State::Idle {});
    send(&mut s, "break approach");
    prompt(&mut s, State::Idle {});
    send(&mut s, "continue");
    expect(
        &mut s,
        "breakpoint 1 hit on entering approach; next: move to the standoff pose",
    );
    prompt(&mut s, State::Approach {});
    send(&mut s, "abort");
    expect(&mut s, &arrow(State::Approach {}, State::Fault {}));
    expect(
        &mut s,
        "device fault in approach: aborted by the operator; the cell was made safe",
    );
    prompt(&mut s, State::Fault {});
    send(&mut s, "load tasks/missing.toml");
    expect(&mut s, "cannot: tasks/missing.toml: cannot read the file");
    prompt(&mut s, State::Fault {});
    quit(s);
}

#[test]
fn break_in_a_search_by_touch_and_step_through_it() {
    let home = tempfile::tempdir().unwrap();
    // Touch only, the prior 53 mm above the cable: the ninth pose finds it.
    let shipped = std::fs::read_to_string(common::root().join("tasks/regrasp.toml")).unwrap();
    let far = shipped
        .replace("# touch_only = true", "touch_only = true")
        .replace(
            "translation_mm = [450.0, 0.0, 255.0]",
            "translation_mm = [450.0, 0.0, 303.0]",
        )
        .replace("position_sigma_mm = 5.0", "position_sigma_mm = 18.0")
        .replace("max_search_moves = 5", "max_search_moves = 20");
    let task = home.path().join("far.toml");
    std::fs::write(&task, far).unwrap();
    let mut s = repl_on(home.path(), task.to_str().unwrap(), "0", &["--no-record"]);
    prompt(&mut s, State::Idle {});
    send(&mut s, "break search if search_moves >= 3");
    expect(&mut s, "breakpoint 1: search if search_moves >= 3");
    prompt(&mut s, State::Idle {});
    send(&mut s, "continue");
    // The trial grasp at the prior's mean closed on nothing, then the
    // first search move; the breakpoint fires on the second.
    expect(&mut s, &arrow(State::TrialGrasp {}, State::Search {}));
    expect(&mut s, &arrow(State::Search {}, State::Search {}));
    expect(
        &mut s,
        "breakpoint 1 hit on entering search (if search_moves >= 3); \
         next: release, move to the search's next pose, grasp",
    );
    prompt(&mut s, State::Search {});
    send(&mut s, "values");
    expect(&mut s, "search_moves = 3.0000");
    prompt(&mut s, State::Search {});
    send(&mut s, "delete 1");
    prompt(&mut s, State::Search {});
    send(&mut s, "step");
    expect(&mut s, &arrow(State::Search {}, State::Search {}));
    expect(&mut s, "in search; next: ");
    prompt(&mut s, State::Search {});
    send(&mut s, "continue");
    expect(&mut s, &arrow(State::Search {}, State::Evaluate {}));
    expect(&mut s, "run over in done");
    expect(
        &mut s,
        "touch only (the task is touch only): 9 search move(s)",
    );
    prompt(&mut s, State::Done {});
    quit(s);
}
