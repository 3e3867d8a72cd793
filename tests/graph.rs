//! `cablecell graph TASK`: the machine as Graphviz DOT.

use std::path::Path;
use std::process::{Command, Output};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn graph(task: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cablecell"))
        .args(["graph", task.to_str().unwrap()])
        .current_dir(root())
        .output()
        .expect("cablecell runs")
}

#[test]
fn the_graph_holds_states_superstate_and_transitions() {
    let output = graph(&root().join("tasks/regrasp.toml"));
    assert!(output.status.success());
    let dot = String::from_utf8(output.stdout).unwrap();
    assert!(dot.starts_with("digraph \"regrasp\" {"), "{dot}");
    assert!(dot.trim_end().ends_with('}'));
    assert_eq!(dot.matches('{').count(), dot.matches('}').count());
    assert!(dot.contains("subgraph cluster_grasping {"));
    // The superstate's children sit inside its cluster.
    let cluster = &dot[dot.find("subgraph cluster_grasping").unwrap()..];
    let cluster = &cluster[..cluster.find("  }").unwrap()];
    for state in [
        "prepare",
        "detect",
        "approach",
        "trial_grasp",
        "evaluate",
        "regrasp",
        "verify",
    ] {
        assert!(
            cluster.contains(&format!("    {state} [")),
            "{state} not in the cluster"
        );
    }
    assert!(!cluster.contains("idle ["));
    for edge in [
        "idle -> prepare [label=\"Start\"]",
        "evaluate -> regrasp [label=\"Tactile (regrasps left)\"]",
        "verify -> done [label=\"Tactile (within tolerance)\"]",
        "[ltail=cluster_grasping, label=\"DeviceFault, Abort (any state of grasping)\"",
    ] {
        assert!(dot.contains(edge), "missing {edge}");
    }
    assert!(!dot.contains("skipped"), "the shipped task skips nothing");
}

#[test]
fn states_the_task_skips_are_drawn_as_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("tasks/regrasp.toml")).unwrap();
    let no_regrasp = text.replace("max_regrasps = 2", "max_regrasps = 0");
    assert_ne!(text, no_regrasp);
    let path = dir.path().join("no-regrasp.toml");
    std::fs::write(&path, no_regrasp).unwrap();
    let dot = String::from_utf8(graph(&path).stdout).unwrap();
    for state in ["regrasp", "verify"] {
        assert!(
            dot.contains(&format!(
                "{state} [shape=box, style=\"rounded,dashed\", color=grey, fontcolor=grey, label=\"{state}\\n(skipped: regrasp.max_regrasps = 0)\"]"
            )),
            "{dot}"
        );
    }
    assert!(dot.contains("evaluate -> regrasp [label=\"Tactile (regrasps left)\", style=dashed"));
    assert!(dot.contains("evaluate [shape=box, style=rounded]"));
}

#[test]
fn a_bad_task_file_is_bad_input() {
    let output = graph(&root().join("tasks/missing.toml"));
    assert_eq!(output.status.code(), Some(2));
}
