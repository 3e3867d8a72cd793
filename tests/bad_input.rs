//! Bad task and cell files give errors that name the file, line, column
//! and field, and exit with status 2.

mod common;

use std::path::{Path, PathBuf};

use common::{cablecell, root};

const BAD_INPUT: i32 = 2;

/// The shipped regrasp task with `from` replaced by `to`, in a temp file.
fn edited_task(dir: &tempfile::TempDir, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(root().join("tasks/regrasp.toml")).expect("task file");
    assert!(text.contains(from), "the shipped task holds {from:?}");
    let path = dir.path().join("task.toml");
    std::fs::write(&path, text.replacen(from, to, 1)).expect("write");
    path
}

/// Runs `check` on the edited task and returns its error output, the
/// file, and the folder that keeps the file alive.
fn check_error(from: &str, to: &str) -> (String, PathBuf, tempfile::TempDir) {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = edited_task(&dir, from, to);
    let out = cablecell(&["check", path.to_str().expect("utf-8 path")]);
    assert_eq!(out.status.code(), Some(BAD_INPUT));
    // `run` must refuse the same file the same way.
    let run = cablecell(&["run", path.to_str().expect("utf-8 path"), "--seed", "1"]);
    assert_eq!(run.status.code(), Some(BAD_INPUT));
    assert_eq!(run.stderr, out.stderr);
    (String::from_utf8(out.stderr).expect("utf-8"), path, dir)
}

/// Runs `check` on the shipped simulated cell with `from` replaced by
/// `to`, and returns its error output, the file, and the folder that keeps
/// the file alive.
fn check_cell_error(from: &str, to: &str) -> (String, PathBuf, tempfile::TempDir) {
    let text = std::fs::read_to_string(root().join("config/cell.sim.toml")).expect("cell file");
    assert!(text.contains(from), "the shipped cell holds {from:?}");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("cell.toml");
    std::fs::write(&path, text.replacen(from, to, 1)).expect("write");
    let out = cablecell(&["check", path.to_str().expect("utf-8 path")]);
    assert_eq!(out.status.code(), Some(BAD_INPUT));
    (String::from_utf8(out.stderr).expect("utf-8"), path, dir)
}

/// The line (1-based) of `needle` in the edited file.
fn line_of(path: &Path, needle: &str) -> usize {
    let text = std::fs::read_to_string(path).expect("read");
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle in file")
        + 1
}

#[test]
fn unknown_key_names_file_line_column_and_field() {
    let (err, path, _dir) =
        check_error("retreat_mm = 30.0", "retreat_mm = 30.0\nretreat_speed = 4");
    let line = line_of(&path, "retreat_speed");
    assert!(
        err.contains(&format!(
            "{}:{line}:1: regrasp.retreat_speed: unknown field `retreat_speed`",
            path.display()
        )),
        "{err}"
    );
    assert!(
        err.contains("expected one of `max_regrasps`, `retreat_mm`"),
        "{err}"
    );
}

#[test]
fn out_of_range_value_is_reported_at_the_value() {
    let (err, path, _dir) = check_error("n_mm = 1.0", "n_mm = -1.0");
    let line = line_of(&path, "n_mm = -1.0");
    assert!(
        err.contains(&format!(
            ":{line}:8: tolerance.n_mm: expected a number > 0, found -1"
        )),
        "{err}"
    );
}

#[test]
fn wrong_type_says_what_was_expected() {
    let (err, _, _dir) = check_error("max_regrasps = 2", "max_regrasps = \"two\"");
    assert!(
        err.contains("regrasp.max_regrasps: invalid type: string \"two\", expected u32"),
        "{err}"
    );
}

#[test]
fn missing_field_names_the_table() {
    let (err, _, _dir) = check_error("grip_current_a = 1.0\n", "");
    assert!(
        err.contains("grasp: missing field `grip_current_a`"),
        "{err}"
    );
}

#[test]
fn angle_outside_half_turn_is_refused() {
    let (err, _, _dir) = check_error("alpha_rad = 0.0", "alpha_rad = 2.0");
    assert!(
        err.contains("target.alpha_rad: expected an angle in (-π/2, π/2] rad, found 2"),
        "{err}"
    );
}

#[test]
fn broken_toml_gives_its_position() {
    let (err, path, _dir) = check_error("[approach]", "[approach");
    let line = line_of(&path, "[approach");
    assert!(
        err.contains(&format!("{}:{line}:", path.display())),
        "{err}"
    );
}

#[test]
fn unknown_backend_lists_the_known_ones() {
    let (err, _path, _dir) = check_cell_error("[arm.backend.sim]", "[arm.backend.ur5]");
    assert!(
        err.contains("arm.backend: unknown variant `ur5`, expected `sim`"),
        "{err}"
    );
}

#[test]
fn a_file_that_is_neither_task_nor_cell_is_named_as_such() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("other.toml");
    std::fs::write(&path, "[robot]\nname = \"x\"\n").expect("write");
    let out = cablecell(&["check", path.to_str().expect("utf-8")]);
    assert_eq!(out.status.code(), Some(BAD_INPUT));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a task, cell or campaign file"));
}

#[test]
fn missing_file_is_named() {
    let out = cablecell(&["run", "tasks/no-such-task.toml"]);
    assert_eq!(out.status.code(), Some(BAD_INPUT));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("tasks/no-such-task.toml: cannot read the file"),
        "{err}"
    );
}

#[test]
fn check_accepts_the_shipped_files() {
    let out = cablecell(&["check", "tasks/regrasp.toml", "config/cell.sim.toml"]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("tasks/regrasp.toml: ok (task file)"),
        "{text}"
    );
    assert!(
        text.contains("config/cell.sim.toml: ok (cell file)"),
        "{text}"
    );
}

/// Checks that the shipped simulated cell with `from` replaced by `to` is
/// refused at the line of `to`'s last line, with `message`.
fn assert_cell_refused_at_its_line(from: &str, to: &str, message: &str) {
    let (err, path, _dir) = check_cell_error(from, to);
    let line = line_of(&path, to.lines().last().expect("a line"));
    assert!(err.contains(&format!(":{line}:")), "{err}");
    assert!(err.contains(message), "{err}");
}

#[test]
fn a_network_input_size_out_of_range_is_refused_at_its_line() {
    assert_cell_refused_at_its_line(
        "net_scale = 0.5",
        "net_scale = 3.0",
        "net_scale 3 is outside (0, 2]",
    );
}

#[test]
fn a_negative_working_width_is_refused_at_its_line() {
    assert_cell_refused_at_its_line(
        "straight_edge_radius_px = 0.0",
        "straight_edge_radius_px = 0.0\nwork_width_px = -640",
        "work_width_px: invalid value: integer `-640`",
    );
}

#[test]
fn a_negative_straight_edge_radius_is_refused_at_its_line() {
    assert_cell_refused_at_its_line(
        "straight_edge_radius_px = 0.0",
        "straight_edge_radius_px = -1.0",
        "expected a number ≥ 0, found -1",
    );
}

#[test]
fn a_region_of_interest_outside_the_camera_image_is_refused_at_its_line() {
    for roi in [
        "[400, 270, 360, 110]",
        "[140, 270, 0, 110]",
        "[-1, 270, 360, 110]",
        "[2147483647, 270, 360, 110]",
    ] {
        assert_cell_refused_at_its_line(
            "roi_px = [140, 270, 360, 110]",
            &format!("roi_px = {roi}"),
            "must have an area and lie within the camera's 640x480 px image",
        );
    }
}

#[test]
fn a_missing_model_is_refused_at_its_line_before_the_cell_moves() {
    let (err, path, _dir) = check_cell_error("cable_segmentation.onnx", "no-such-model.onnx");
    let line = line_of(&path, "no-such-model.onnx");
    assert!(
        err.contains(&format!(
            "{}:{line}:1: detector.backend.vision.model: segmentation model",
            path.display()
        )) && err.contains("no-such-model.onnx is missing or unreadable"),
        "{err}"
    );
    let run = cablecell(&[
        "run",
        "tasks/regrasp.toml",
        "--cell",
        path.to_str().expect("utf-8 path"),
        "--seed",
        "1",
    ]);
    assert_eq!(run.status.code(), Some(BAD_INPUT));
    assert_eq!(String::from_utf8_lossy(&run.stderr), err);
    assert!(
        run.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&run.stdout)
    );
}
