//! The state machine as Graphviz DOT: its states, the `grasping`
//! superstate, and every transition with the event that makes it. The
//! table below is checked against the machine by running it (see the
//! tests), so the drawing cannot drift from the code unnoticed.

use std::fmt::Write;

use crate::task::TaskFile;

/// The superstate and the states it holds.
pub const SUPERSTATE: (&str, [&str; 7]) = (
    "grasping",
    [
        "prepare",
        "detect",
        "approach",
        "trial_grasp",
        "evaluate",
        "regrasp",
        "verify",
    ],
);

/// Every transition a state makes: (from, event and condition, to).
pub const TRANSITIONS: [(&str, &str, &str); 18] = [
    ("idle", "Start", "prepare"),
    ("prepare", "Tactile (bias measured)", "detect"),
    ("prepare", "Tactile (too few frames)", "fault"),
    ("detect", "Detected (a cable)", "approach"),
    ("detect", "Detected (none)", "failed"),
    ("approach", "Arrived", "trial_grasp"),
    ("trial_grasp", "Grasped (holding)", "evaluate"),
    ("trial_grasp", "Grasped (empty)", "failed"),
    ("evaluate", "Tactile (within tolerance)", "done"),
    ("evaluate", "Tactile (regrasps left)", "regrasp"),
    (
        "evaluate",
        "Tactile (no contact, fit failed, no regrasp left)",
        "failed",
    ),
    ("evaluate", "Tactile (no frames)", "fault"),
    ("regrasp", "Grasped (holding)", "verify"),
    ("regrasp", "Grasped (empty)", "failed"),
    ("verify", "Tactile (within tolerance)", "done"),
    ("verify", "Tactile (regrasps left)", "regrasp"),
    (
        "verify",
        "Tactile (no contact, fit failed, no regrasp left)",
        "failed",
    ),
    ("verify", "Tactile (no frames)", "fault"),
];

/// Transitions the superstate makes for every state it holds.
pub const SUPERSTATE_TRANSITIONS: [(&str, &str); 1] = [("DeviceFault, Abort", "fault")];

/// The states `task` never enters, each with the reason.
pub fn skipped_states(task: &TaskFile) -> Vec<(&'static str, String)> {
    if task.regrasp.max_regrasps == 0 {
        let reason = "skipped: regrasp.max_regrasps = 0".to_owned();
        vec![("regrasp", reason.clone()), ("verify", reason)]
    } else {
        Vec::new()
    }
}

/// The machine as a DOT digraph, the states `task` skips drawn dashed and
/// grey with the reason.
pub fn dot(task: &TaskFile) -> String {
    let skipped = skipped_states(task);
    let is_skipped = |state: &str| skipped.iter().any(|(s, _)| *s == state);
    let node = |out: &mut String, state: &str, indent: &str| {
        let shape = match state {
            "done" => "doublecircle",
            "failed" | "fault" => "doubleoctagon",
            _ => "box",
        };
        let _ = match skipped.iter().find(|(s, _)| *s == state) {
            Some((_, reason)) => writeln!(
                out,
                "{indent}{state} [shape={shape}, style=\"rounded,dashed\", color=grey, fontcolor=grey, label=\"{state}\\n({reason})\"];"
            ),
            None => writeln!(out, "{indent}{state} [shape={shape}, style=rounded];"),
        };
    };
    let mut out = String::new();
    let _ = writeln!(out, "digraph {} {{", quote(&task.task.name));
    out.push_str("  compound=true;\n  rankdir=LR;\n  node [fontname=\"Helvetica\"];\n  edge [fontname=\"Helvetica\", fontsize=10];\n");
    node(&mut out, "idle", "  ");
    let (superstate, children) = SUPERSTATE;
    let _ = writeln!(
        out,
        "  subgraph cluster_{superstate} {{\n    label=\"{superstate}\";\n    style=rounded;"
    );
    for child in children {
        node(&mut out, child, "    ");
    }
    out.push_str("  }\n");
    for state in ["done", "failed", "fault"] {
        node(&mut out, state, "  ");
    }
    for (from, event, to) in TRANSITIONS {
        let style = if is_skipped(from) || is_skipped(to) {
            ", style=dashed, color=grey, fontcolor=grey"
        } else {
            ""
        };
        let _ = writeln!(out, "  {from} -> {to} [label={}{style}];", quote(event));
    }
    // An edge leaving the cluster stands for one from each of its states.
    let anchor = children[children.len() / 2];
    for (event, to) in SUPERSTATE_TRANSITIONS {
        let _ = writeln!(
            out,
            "  {anchor} -> {to} [ltail=cluster_{superstate}, label={}, style=bold];",
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
    use crate::orchestrator::{Runner, State};
    use crate::task::load_task;

    /// Every (from, to) a run makes is drawn, directly or through the
    /// superstate.
    fn assert_drawn(runner: &Runner) {
        for t in &runner.record().transitions {
            let direct = TRANSITIONS
                .iter()
                .any(|(f, _, to)| *f == t.from && *to == t.to);
            let via_superstate = SUPERSTATE.1.contains(&t.from)
                && SUPERSTATE_TRANSITIONS.iter().any(|(_, to)| *to == t.to);
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
        assert_eq!(runner.state().name(), "fault");
        assert_drawn(&runner);
        // The runs went through the whole sequence, both ways out of a judgement.
        for pair in [
            ("evaluate", "done"),
            ("evaluate", "regrasp"),
            ("verify", "done"),
            ("regrasp", "verify"),
        ] {
            assert!(seen.contains(&pair), "{pair:?} never happened");
        }
        // Every state is drawn.
        let drawn = dot(&task);
        for state in State::NAMES {
            assert!(drawn.contains(&format!("  {state} [")), "{state} missing");
        }
    }
}
