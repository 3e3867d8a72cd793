//! The state machine as Graphviz DOT: its states, the `grasping`
//! superstate, and every transition with the event that makes it. The
//! table below is checked against the machine by running it (see the
//! tests), so the drawing cannot drift from the code unnoticed.

use std::fmt::Write;

use super::machine::{State, Superstate};
use crate::task::TaskFile;

/// Every transition a state makes: (from, event and condition, to).
pub const TRANSITIONS: [(State, &str, State); 26] = [
    (State::Idle {}, "Start", State::Prepare {}),
    (
        State::Prepare {},
        "Tactile (bias measured)",
        State::Detect {},
    ),
    (
        State::Prepare {},
        "Tactile (bias measured, touch only)",
        State::Approach {},
    ),
    (
        State::Prepare {},
        "Tactile (too few frames)",
        State::Fault {},
    ),
    (State::Detect {}, "Detected (a cable)", State::Approach {}),
    (
        State::Detect {},
        "Detected (none), a prior: search",
        State::Approach {},
    ),
    (
        State::Detect {},
        "DeviceFault (detector unusable), a prior: search",
        State::Approach {},
    ),
    (State::Detect {}, "Detected (none)", State::Failed {}),
    (State::Approach {}, "Arrived", State::TrialGrasp {}),
    (
        State::TrialGrasp {},
        "Grasped (holding)",
        State::Evaluate {},
    ),
    (
        State::TrialGrasp {},
        "Grasped (empty), search poses left",
        State::Search {},
    ),
    (State::TrialGrasp {}, "Grasped (empty)", State::Failed {}),
    (State::Search {}, "Grasped (holding)", State::Evaluate {}),
    (
        State::Search {},
        "Grasped (empty), search poses left",
        State::Search {},
    ),
    (
        State::Search {},
        "Grasped (empty), no search pose left",
        State::Failed {},
    ),
    (
        State::Evaluate {},
        "Tactile (within tolerance)",
        State::Done {},
    ),
    (
        State::Evaluate {},
        "Tactile (regrasps left)",
        State::Regrasp {},
    ),
    (
        State::Evaluate {},
        "Tactile (nothing felt, search poses left)",
        State::Search {},
    ),
    (
        State::Evaluate {},
        "Tactile (no contact, fit failed, no regrasp or search pose left)",
        State::Failed {},
    ),
    (State::Evaluate {}, "Tactile (no frames)", State::Fault {}),
    (State::Regrasp {}, "Grasped (holding)", State::Verify {}),
    (State::Regrasp {}, "Grasped (empty)", State::Failed {}),
    (
        State::Verify {},
        "Tactile (within tolerance)",
        State::Done {},
    ),
    (
        State::Verify {},
        "Tactile (regrasps left)",
        State::Regrasp {},
    ),
    (
        State::Verify {},
        "Tactile (no contact, fit failed, no regrasp left)",
        State::Failed {},
    ),
    (State::Verify {}, "Tactile (no frames)", State::Fault {}),
];

/// Transitions a superstate makes for every state it holds: (superstate,
/// event, to).
pub const SUPERSTATE_TRANSITIONS: [(Superstate, &str, State); 1] = [(
    Superstate::Grasping {},
    "DeviceFault, Abort",
    State::Fault {},
)];

/// Each superstate with the states it holds, in the order of the sequence.
pub fn superstates() -> Vec<(Superstate, Vec<State>)> {
    let mut out: Vec<(Superstate, Vec<State>)> = Vec::new();
    for state in State::all() {
        let Some(parent) = state.parent() else {
            continue;
        };
        match out.iter_mut().find(|(superstate, _)| *superstate == parent) {
            Some((_, children)) => children.push(state),
            None => out.push((parent, vec![state])),
        }
    }
    out
}

/// The states `task` never enters, each with the reason.
pub fn skipped_states(task: &TaskFile) -> Vec<(State, String)> {
    let mut skipped = Vec::new();
    if task.task.touch_only {
        skipped.push((State::Detect {}, "skipped: task.touch_only".to_owned()));
    }
    if task.prior.is_none() {
        skipped.push((State::Search {}, "skipped: no [prior]".to_owned()));
    }
    if task.regrasp.max_regrasps == 0 {
        let reason = "skipped: regrasp.max_regrasps = 0".to_owned();
        skipped.push((State::Regrasp {}, reason.clone()));
        skipped.push((State::Verify {}, reason));
    }
    skipped
}

/// The machine as a DOT digraph, the states `task` skips drawn dashed and
/// grey with the reason.
pub fn dot(task: &TaskFile) -> String {
    let skipped = skipped_states(task);
    let is_skipped = |state: &State| skipped.iter().any(|(s, _)| s == state);
    let node = |out: &mut String, state: &State, indent: &str| {
        let shape = match state {
            State::Done {} => "doublecircle",
            final_state if final_state.is_final() => "doubleoctagon",
            _ => "box",
        };
        let name = state.name();
        let _ = match skipped.iter().find(|(s, _)| s == state) {
            Some((_, reason)) => writeln!(
                out,
                "{indent}{name} [shape={shape}, style=\"rounded,dashed\", color=grey, fontcolor=grey, label=\"{name}\\n({reason})\"];"
            ),
            None => writeln!(out, "{indent}{name} [shape={shape}, style=rounded];"),
        };
    };
    let mut out = String::new();
    let _ = writeln!(out, "digraph {} {{", quote(&task.task.name));
    out.push_str("  compound=true;\n  rankdir=LR;\n  node [fontname=\"Helvetica\"];\n  edge [fontname=\"Helvetica\", fontsize=10];\n");
    // The states outside any superstate where a run starts, each
    // superstate as a cluster of its states, then where a run ends.
    let all = State::all();
    let outside = all.iter().filter(|s| s.parent().is_none());
    for state in outside.clone().filter(|s| !s.is_final()) {
        node(&mut out, state, "  ");
    }
    let superstates = superstates();
    for (superstate, children) in &superstates {
        let superstate = superstate.name();
        let _ = writeln!(
            out,
            "  subgraph cluster_{superstate} {{\n    label=\"{superstate}\";\n    style=rounded;"
        );
        for child in children {
            node(&mut out, child, "    ");
        }
        out.push_str("  }\n");
    }
    for state in outside.filter(|s| s.is_final()) {
        node(&mut out, state, "  ");
    }
    for (from, event, to) in &TRANSITIONS {
        let style = if is_skipped(from) || is_skipped(to) {
            ", style=dashed, color=grey, fontcolor=grey"
        } else {
            ""
        };
        let (from, to) = (from.name(), to.name());
        let _ = writeln!(out, "  {from} -> {to} [label={}{style}];", quote(event));
    }
    // An edge leaving a cluster stands for one from each of its states.
    for (superstate, event, to) in &SUPERSTATE_TRANSITIONS {
        let Some((_, children)) = superstates.iter().find(|(s, _)| s == superstate) else {
            continue;
        };
        let (anchor, superstate) = (children[children.len() / 2].name(), superstate.name());
        let _ = writeln!(
            out,
            "  {anchor} -> {} [ltail=cluster_{superstate}, label={}, style=bold];",
            to.name(),
            quote(&format!("{event} (any state of {superstate})"))
        );
    }
    out.push_str("}\n");
    out
}

fn quote(text: &str) -> String {
    format!("\"{}\"", text.replace('\\', "\\\\").replace('"', "\\\""))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::orchestrator::Runner;
    use crate::task::load_task;

    /// Every (from, to) a run makes is drawn, directly or through the
    /// superstate.
    fn assert_drawn(runner: &Runner) {
        for t in &runner.record().transitions {
            let from = State::named(t.from).expect("a state's name");
            let to = State::named(t.to).expect("a state's name");
            let direct = TRANSITIONS.iter().any(|(f, _, t)| (*f, *t) == (from, to));
            let via_superstate = SUPERSTATE_TRANSITIONS
                .iter()
                .any(|(s, _, t)| from.parent() == Some(*s) && *t == to);
            assert!(
                direct || via_superstate,
                "{} → {} is not drawn",
                t.from,
                t.to
            );
        }
    }

    #[test]
    fn the_table_holds_every_transition_the_machine_makes() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut task = load_task(&root.join("tasks/regrasp.toml")).unwrap();
        let cell = crate::orchestrator::test_cell::sim_cell_with_oracle();
        let mut seen = std::collections::BTreeSet::new();
        for max_regrasps in [0, 1, 2] {
            task.regrasp.max_regrasps = max_regrasps;
            for seed in 0..20 {
                let mut runner = Runner::for_task(&task, &cell, seed).unwrap();
                runner.run_to_end().unwrap();
                assert_drawn(&runner);
                seen.extend(runner.record().transitions.iter().map(|t| (t.from, t.to)));
            }
        }
        // An abort from inside the superstate.
        let mut runner = Runner::for_task(&task, &cell, 1).unwrap();
        for _ in 0..3 {
            runner.step().unwrap();
        }
        assert!(runner.abort().unwrap());
        runner.run_to_end().unwrap();
        assert_eq!(runner.state(), &State::Fault {});
        assert_drawn(&runner);
        // The runs went through the whole sequence, both ways out of a judgement.
        for (from, to) in [
            (State::Evaluate {}, State::Done {}),
            (State::Evaluate {}, State::Regrasp {}),
            (State::Verify {}, State::Done {}),
            (State::Regrasp {}, State::Verify {}),
        ] {
            let pair = (from.name(), to.name());
            assert!(seen.contains(&pair), "{pair:?} never happened");
        }
        // Every state is drawn.
        let drawn = dot(&task);
        for state in State::NAMES {
            assert!(drawn.contains(&format!("  {state} [")), "{state} missing");
        }
    }

    #[test]
    fn the_searches_transitions_are_drawn() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let shipped = load_task(&root.join("tasks/regrasp.toml")).unwrap();
        let mut seen = std::collections::BTreeSet::new();
        let mut run = |task: &TaskFile, cell: &crate::cell::CellFile, seed: u64| {
            let mut runner = Runner::for_task(task, cell, seed).unwrap();
            runner.run_to_end().unwrap();
            assert_drawn(&runner);
            seen.extend(runner.record().transitions.iter().map(|t| (t.from, t.to)));
        };
        // Touch only, the prior 53 mm (three pads) above the cable, then
        // 100 mm above it, where the search cannot reach it.
        let mut task = shipped.clone();
        task.task.touch_only = true;
        let cell = crate::orchestrator::test_cell::sim_cell_with_oracle();
        for (z_mm, sigma_mm) in [(303.0, 18.0), (350.0, 10.0)] {
            let prior = task.prior.as_mut().expect("the shipped task has a prior");
            prior.base_from_cable.translation_mm[2] = z_mm;
            prior.position_sigma_mm = sigma_mm;
            prior.max_search_moves = 20;
            run(&task, &cell, 1);
        }
        // The vision detector with an uncalibrated camera cannot look.
        let mut cell = crate::cell::load_cell(&root.join("config/cell.sim.toml")).unwrap();
        cell.camera.calibration = None;
        run(&shipped, &cell, 1);
        for (from, to) in [
            (State::Prepare {}, State::Approach {}),
            (State::Detect {}, State::Approach {}),
            (State::TrialGrasp {}, State::Search {}),
            (State::Search {}, State::Search {}),
            (State::Search {}, State::Evaluate {}),
            (State::Search {}, State::Failed {}),
        ] {
            let pair = (from.name(), to.name());
            assert!(seen.contains(&pair), "{pair:?} never happened");
        }
    }
}
