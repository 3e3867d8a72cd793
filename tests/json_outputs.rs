//! What scripts rely on: the JSON Schemas shipped in docs/schemas/ are the
//! commands' own, and a reader that goes away (`| head -1`) ends nothing
//! with a panic. (Each command's test checks its output against its
//! schema: `common::assert_follows_schema`.)

mod common;

use std::process::Stdio;

use common::{cablecell, root, text};

/// Every output `cablecell json-schema` knows, as its help lists them.
fn outputs() -> Vec<String> {
    let help = cablecell(&["json-schema", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout).into_owned();
    let names: Vec<String> = help
        .lines()
        .filter_map(|line| line.trim().strip_prefix("- "))
        .filter_map(|item| item.split(':').next())
        .map(str::to_owned)
        .collect();
    assert!(names.len() >= 7, "{help}");
    names
}

#[test]
fn the_shipped_schemas_are_the_commands_own() {
    for output in outputs() {
        let printed = cablecell(&["json-schema", &output]);
        assert_eq!(printed.status.code(), Some(0), "{output}");
        let path = root().join(format!("docs/schemas/{output}.schema.json"));
        let shipped = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            String::from_utf8_lossy(&printed.stdout) == shipped,
            "{} is not what `cablecell json-schema {output}` prints: run scripts/json-schemas",
            path.display()
        );
        let schema: serde_json::Value = serde_json::from_str(&shipped).expect("JSON");
        assert!(jsonschema::meta::is_valid(&schema), "{output}");
        assert_eq!(schema["properties"]["schema_version"]["const"], 1);
    }
}

#[test]
fn an_unknown_output_is_refused_with_the_known_ones() {
    let out = cablecell(&["json-schema", "nonsense"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("tactile-fit"));
}

/// Runs `args` with standard output a pipe whose reader is already gone:
/// every write fails as it does after `| head -1` has read its line.
fn with_closed_stdout(args: &[&str]) -> std::process::Output {
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    common::command()
        .args(args)
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .expect("cablecell runs")
}

#[test]
fn a_closed_pipe_ends_nothing_with_a_panic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let map = dir.path().join("map.txt");
    let row = "0 0 0 0 0\n";
    let across = "1 1 1 1 1\n";
    std::fs::write(&map, format!("{row}{row}{across}{row}{row}")).expect("write");
    let cases: [(&[&str], i32); 3] = [
        (&["json-schema", "run"], 0),
        (&["tactile-fit", text(&map)], 0),
        // A run whose reader went away still drives the cell to its end
        // (seed 3 succeeds after one regrasp).
        (
            &["run", "tasks/regrasp.toml", "--seed", "3", "--no-record"],
            0,
        ),
    ];
    for (args, status) in cases {
        let out = with_closed_stdout(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(status), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(!stderr.contains("Broken pipe"), "{args:?}: {stderr}");
    }
}

#[test]
fn graphviz_draws_the_machine_as_svg() {
    let Ok(mut dot) = std::process::Command::new("dot")
        .arg("-Tsvg")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
    else {
        panic!("Graphviz's `dot` is not installed: scripts/setup installs it (Debian's graphviz)");
    };
    let graph = cablecell(&["graph", "tasks/regrasp.toml"]);
    assert_eq!(graph.status.code(), Some(0));
    std::io::Write::write_all(&mut dot.stdin.take().expect("stdin"), &graph.stdout)
        .expect("DOT written to dot");
    let svg = dot.wait_with_output().expect("dot runs");
    assert!(svg.status.success());
    let svg = String::from_utf8_lossy(&svg.stdout);
    assert!(svg.contains("<svg"), "{svg}");
    for state in [
        "prepare",
        "detect",
        "trial_grasp",
        "evaluate",
        "regrasp",
        "verify",
    ] {
        assert!(svg.contains(&format!(">{state}</text>")), "{state}");
    }
}
