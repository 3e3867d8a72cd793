//! `cablecell graph TASK`: the machine as Graphviz DOT.

mod common;

use std::path::Path;
use std::process::Output;

use cablecell::orchestrator::graph::superstates;
use cablecell::orchestrator::{State, Superstate};

fn graph(task: &Path) -> Output {
    common::command()
        .args(["graph", task.to_str().unwrap()])
        .output()
        .expect("cablecell runs")
}

/// The edge `from -> to` with its label, as the graph draws it (but for
/// any style after the label).
fn edge(from: State, label: &str, to: State) -> String {
    format!("{} -> {} [label=\"{label}\"", from.name(), to.name())
}

#[test]
fn the_graph_holds_states_superstate_and_transitions() {
    let output = graph(&common::root().join("tasks/regrasp.toml"));
    assert!(output.status.success());
    let dot = String::from_utf8(output.stdout).unwrap();
    assert!(dot.starts_with("digraph \"regrasp\" {"), "{dot}");
    assert!(dot.trim_end().ends_with('}'));
    assert_eq!(dot.matches('{').count(), dot.matches('}').count());
    let grasping = Superstate::Grasping {}.name();
    assert!(dot.contains(&format!("subgraph cluster_{grasping} {{")));
    // The superstate's children, as the machine has them, sit inside its
    // cluster.
    let cluster = &dot[dot.find(&format!("subgraph cluster_{grasping}")).unwrap()..];
    let cluster = &cluster[..cluster.find("  }").unwrap()];
    let [(superstate, children)] = superstates().try_into().expect("one superstate");
    assert_eq!(superstate, Superstate::Grasping {});
    assert_eq!(children.len(), 8);
    for state in children {
        let state = state.name();
        assert!(
            cluster.contains(&format!("    {state} [")),
            "{state} not in the cluster"
        );
    }
    assert!(!cluster.contains(&format!("{} [", State::Idle {}.name())));
    for edge in [
        edge(State::Idle {}, "Start", State::Prepare {}),
        edge(
            State::Evaluate {},
            "Tactile (regrasps left)",
            State::Regrasp {},
        ),
        edge(
            State::Verify {},
            "Tactile (within tolerance)",
            State::Done {},
        ),
        // The search by touch from the task's prior.
        edge(
            State::Detect {},
            "Detected (none), a prior: search",
            State::Approach {},
        ),
        edge(
            State::Search {},
            "Grasped (empty), search poses left",
            State::Search {},
        ),
        edge(State::Search {}, "Grasped (holding)", State::Evaluate {}),
        format!(
            "[ltail=cluster_{grasping}, label=\"DeviceFault, Abort (any state of {grasping})\""
        ),
    ] {
        assert!(dot.contains(&edge), "missing {edge}");
    }
    assert!(!dot.contains("skipped"), "the shipped task skips nothing");
}

#[test]
fn states_the_task_skips_are_drawn_as_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(common::root().join("tasks/regrasp.toml")).unwrap();
    let no_regrasp = text.replace("max_regrasps = 2", "max_regrasps = 0");
    assert_ne!(text, no_regrasp);
    let path = dir.path().join("no-regrasp.toml");
    std::fs::write(&path, no_regrasp).unwrap();
    let dot = String::from_utf8(graph(&path).stdout).unwrap();
    for state in [State::Regrasp {}, State::Verify {}].map(|s| s.name()) {
        assert!(
            dot.contains(&format!(
                "{state} [shape=box, style=\"rounded,dashed\", color=grey, fontcolor=grey, label=\"{state}\\n(skipped: regrasp.max_regrasps = 0)\"]"
            )),
            "{dot}"
        );
    }
    let to_regrasp = edge(
        State::Evaluate {},
        "Tactile (regrasps left)",
        State::Regrasp {},
    );
    assert!(dot.contains(&format!("{to_regrasp}, style=dashed")));
    let evaluate = State::Evaluate {}.name();
    assert!(dot.contains(&format!("{evaluate} [shape=box, style=rounded]")));
}

#[test]
fn a_touch_only_task_skips_the_detector_and_one_without_a_prior_the_search() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(common::root().join("tasks/regrasp.toml")).unwrap();
    let touch_only = dir.path().join("touch-only.toml");
    std::fs::write(
        &touch_only,
        text.replace("# touch_only = true", "touch_only = true"),
    )
    .unwrap();
    let dot = String::from_utf8(graph(&touch_only).stdout).unwrap();
    let detect = State::Detect {}.name();
    assert!(
        dot.contains(&format!("label=\"{detect}\\n(skipped: task.touch_only)\"")),
        "{dot}"
    );
    let prior = text.find("\n# Where the cable roughly lies").unwrap();
    let no_prior = dir.path().join("no-prior.toml");
    std::fs::write(&no_prior, &text[..prior]).unwrap();
    let dot = String::from_utf8(graph(&no_prior).stdout).unwrap();
    let search = State::Search {}.name();
    assert!(
        dot.contains(&format!("label=\"{search}\\n(skipped: no [prior])\"")),
        "{dot}"
    );
}

#[test]
fn a_bad_task_file_is_bad_input() {
    let output = graph(&common::root().join("tasks/missing.toml"));
    assert_eq!(output.status.code(), Some(2));
}
