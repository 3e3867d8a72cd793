//! What several end-to-end tests share: the shipped simulated cell with its
//! vision detector swapped for an oracle that misses the true grasp frame by
//! σ = 3 mm and 0.2 rad, so that trial grasps land a few millimetres off, as
//! in the paper, and the regrasp path is taken (seed 3: one regrasp).

#![allow(dead_code)] // each test binary uses its own part

pub mod scenes;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use cablecell::cell::CellFile;
use cablecell::cell::load_cell;
use cablecell::detector::config::{DetectorBackend, OracleConfig};
use cablecell::orchestrator::State;

pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The states the regrasp task enters after idle when one regrasp brings
/// its trial grasp into tolerance.
pub const ONE_REGRASP_PATH: [State; 8] = [
    State::Prepare {},
    State::Detect {},
    State::Approach {},
    State::TrialGrasp {},
    State::Evaluate {},
    State::Regrasp {},
    State::Verify {},
    State::Done {},
];

/// The binary, to be run from the project's root.
pub fn command() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_cablecell"));
    command.current_dir(root());
    command
}

/// The binary run with `args` from the project's root, to its end.
pub fn cablecell(args: &[&str]) -> Output {
    command().args(args).output().expect("cablecell runs")
}

/// The JSON the binary prints when run with `args`, which must succeed.
pub fn json_of(args: &[&str]) -> serde_json::Value {
    let out = cablecell(args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

/// Checks `value` against the JSON Schema shipped for `output` in
/// docs/schemas/ (which a test keeps equal to `cablecell json-schema`'s).
pub fn assert_follows_schema(output: &str, value: &serde_json::Value) {
    let path = root().join(format!("docs/schemas/{output}.schema.json"));
    let schema: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("the schema")).expect("JSON");
    let validator = jsonschema::validator_for(&schema).expect("a valid JSON Schema");
    let errors: Vec<String> = validator
        .iter_errors(value)
        .map(|error| format!("{} at {}", error, error.instance_path()))
        .collect();
    assert!(errors.is_empty(), "{output}: {errors:#?}");
}

/// A path as the `&str` a command line takes.
pub fn text(path: &Path) -> &str {
    path.to_str().expect("utf-8 path")
}

/// The development photographs, `../shared/data/cables-dev` beside the
/// checkout. The tests that read them are `#[ignore]`d, so that a checkout
/// without them reports those tests as ignored rather than passed;
/// `scripts/test` runs them (`--ignored`) when the folder is there, and
/// asked for without it, they fail here, saying what is missing.
pub fn cables_dev() -> PathBuf {
    let dir = root().join("../shared/data/cables-dev");
    assert!(
        dir.is_dir(),
        "{} is missing: this test needs the cables-dev photographs",
        dir.display()
    );
    dir
}

/// The shipped simulated cell's text, its model path made absolute so that
/// a copy elsewhere finds the model.
pub fn sim_cell_text() -> String {
    let text = std::fs::read_to_string(root().join("config/cell.sim.toml")).expect("cell file");
    let models = root().join("models");
    text.replace("../models", models.to_str().expect("utf-8"))
}

/// The shipped simulated cell's text after `edit`, written into `dir`, its
/// model path made absolute so that the copy finds the model.
pub fn sim_cell_copy(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let text = edit(sim_cell_text());
    let path = dir.join("cell.toml");
    std::fs::write(&path, text).expect("write");
    path
}

/// The JSON report of the regrasp task (seed 1) run on the cell file
/// `cell`, which must end in a device fault: exit status 3.
pub fn regrasp_fault_report(cell: &Path) -> serde_json::Value {
    let out = cablecell(&[
        "run",
        "tasks/regrasp.toml",
        "--cell",
        text(cell),
        "--seed",
        "1",
        "--json",
    ]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(report["outcome"]["kind"], "fault");
    report
}

/// σ of the oracle's miss across the cable and about the pad's normal.
pub const ORACLE_NOISE: (f64, f64) = (3.0, 0.2);

/// `cell` with its detector replaced by an oracle missing by the given σ.
pub fn with_oracle(mut cell: CellFile, position_noise_mm: f64, angle_noise_rad: f64) -> CellFile {
    cell.detector.backend = DetectorBackend::Oracle(OracleConfig {
        position_noise_mm,
        angle_noise_rad,
        offset_across_mm: 0.0,
        offset_angle_rad: 0.0,
    });
    cell
}

/// The shipped simulated cell with the oracle of `ORACLE_NOISE`.
pub fn sim_cell_with_oracle() -> CellFile {
    let cell = load_cell(&root().join("config/cell.sim.toml")).expect("the shipped cell");
    with_oracle(cell, ORACLE_NOISE.0, ORACLE_NOISE.1)
}

/// The same, as a cell file written into `dir`, for the binary.
pub fn sim_cell_with_oracle_file(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(root().join("config/cell.sim.toml")).expect("cell file");
    let start = text
        .find("[detector.backend.vision]")
        .expect("the vision detector");
    let end = text[start..].find("\n\n").map_or(text.len(), |i| start + i);
    let oracle = format!(
        "[detector.backend.oracle]\nposition_noise_mm = {}\nangle_noise_rad = {}",
        ORACLE_NOISE.0, ORACLE_NOISE.1
    );
    let path = dir.join("cell.oracle.toml");
    std::fs::write(&path, format!("{}{oracle}{}", &text[..start], &text[end..])).expect("write");
    path
}
