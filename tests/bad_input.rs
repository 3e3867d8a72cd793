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
    check_shipped_cell_error("config/cell.sim.toml", from, to)
}

/// [`check_cell_error`] on the shipped cell file `shipped`.
fn check_shipped_cell_error(
    shipped: &str,
    from: &str,
    to: &str,
) -> (String, PathBuf, tempfile::TempDir) {
    let text = std::fs::read_to_string(root().join(shipped)).expect("cell file");
    assert!(text.contains(from), "the shipped cell holds {from:?}");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("cell.toml");
    std::fs::write(&path, text.replacen(from, to, 1)).expect("write");
    let out = cablecell(&["check", path.to_str().expect("utf-8 path")]);
    assert_eq!(out.status.code(), Some(BAD_INPUT));
    (String::from_utf8(out.stderr).expect("utf-8"), path, dir)
}

/// Asserts that `run` refuses the cell file `cell` as `check` did, with
/// the same `error`, before the cell moves.
fn assert_run_refuses_cell(cell: &Path, error: &str) {
    let run = cablecell(&[
        "run",
        "tasks/regrasp.toml",
        "--cell",
        cell.to_str().expect("utf-8 path"),
        "--seed",
        "1",
    ]);
    assert_eq!(run.status.code(), Some(BAD_INPUT));
    assert_eq!(String::from_utf8_lossy(&run.stderr), error);
    assert!(run.stdout.is_empty());
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
fn a_task_faster_than_the_cell_allows_is_refused_at_load() {
    // Before, the run started and the arm refused the approach: a device
    // fault (3) after the cell had moved.
    let dir = tempfile::tempdir().expect("tempdir");
    let path = edited_task(&dir, "speed_mm_s = 100.0", "speed_mm_s = 400.0");
    let run = cablecell(&["run", path.to_str().expect("utf-8 path"), "--seed", "1"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(BAD_INPUT), "{stderr}");
    let line = line_of(&path, "speed_mm_s");
    assert_eq!(
        stderr,
        format!(
            "error: {}:{line}:1: approach.speed_mm_s: expected a value in (0, 250] mm/s \
             (arm.max_speed_mm_s of config/cell.sim.toml), found 400\n",
            path.display()
        )
    );
    assert!(run.stdout.is_empty(), "nothing ran");
    // At the cell's limit it runs.
    let path = edited_task(&dir, "speed_mm_s = 100.0", "speed_mm_s = 250.0");
    let run = cablecell(&[
        "run",
        path.to_str().expect("utf-8 path"),
        "--seed",
        "1",
        "--no-record",
    ]);
    assert_ne!(run.status.code(), Some(BAD_INPUT));
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
    assert_cell_refused_at_its_line(
        "net_scale = 0.5",
        "net_scale = 0.5\nclose_net_scale = 0.0",
        "close_net_scale 0 is outside (0, 2]",
    );
    assert_cell_refused_at_its_line(
        "net_scale = 0.5",
        "net_scale = 0.5\nbusy_net_scale = 2.5",
        "busy_net_scale 2.5 is outside (0, 2]",
    );
}

#[test]
fn a_busy_threshold_out_of_range_is_refused_at_its_line() {
    assert_cell_refused_at_its_line(
        "net_scale = 0.5",
        "net_scale = 0.5\nbusy_threshold = 1.5",
        "busy_threshold: expected a fraction in [0, 1], found 1.5",
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
fn a_confidence_floor_outside_0_to_1_is_refused_at_its_line() {
    assert_cell_refused_at_its_line(
        "straight_edge_radius_px = 0.0",
        "straight_edge_radius_px = 0.0\nmin_confidence = 1.5",
        "expected a fraction in [0, 1], found 1.5",
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

/// Asserts that the shipped cell with `from` replaced by `to`, which names
/// the model file `missing` under `detector.backend.vision.KEY`, is
/// refused by `check` at that line, and by `run` before the cell moves.
fn assert_missing_model_refused(from: &str, to: &str, key: &str, missing: &str) {
    let (err, path, _dir) = check_cell_error(from, to);
    let line = line_of(&path, missing);
    assert!(
        err.contains(&format!(
            "{}:{line}:1: detector.backend.vision.{key}: segmentation model",
            path.display()
        )) && err.contains(&format!("{missing} is missing or unreadable")),
        "{err}"
    );
    assert_run_refuses_cell(&path, &err);
}

#[test]
fn a_missing_model_is_refused_at_its_line_before_the_cell_moves() {
    assert_missing_model_refused(
        "cable_segmentation.onnx",
        "no-such-model.onnx",
        "model",
        "no-such-model.onnx",
    );
}

/// The busy scenes' network is checked as the first one is: a run that
/// would meet a painted scene halfway through must not start without it.
#[test]
fn a_missing_busy_scenes_model_is_refused_at_its_line_before_the_cell_moves() {
    let shipped = root().join("models/cable_segmentation.onnx");
    assert_missing_model_refused(
        "\"../models/cable_segmentation.onnx\"\nbusy_model = \"../models/cable_segmentation_busy_mirrored.onnx\"",
        &format!(
            "{:?}\nbusy_model = \"no-such-busy-model.onnx\"",
            shipped.display().to_string()
        ),
        "busy_model",
        "no-such-busy-model.onnx",
    );
}

#[test]
fn a_pitch_no_pad_has_is_refused_by_check_and_run_at_its_line() {
    for (pitch, shown) in [
        ("9223372036854775807", "9.223372036854776e18"),
        ("1e9", "1e9"),
        ("0.0", "0"),
        ("nan", "NaN"),
    ] {
        let to = format!("pitch_mm = {pitch}");
        let (err, path, _dir) = check_cell_error("pitch_mm = 3.55", &to);
        let line = line_of(&path, &to);
        assert!(
            err.contains(&format!(
                "{}:{line}:12: tactile.pitch_mm: expected a value in [1, 20] mm, found {shown}",
                path.display()
            )),
            "{err}"
        );
        assert_run_refuses_cell(&path, &err);
    }
}

#[test]
fn a_polling_rate_the_serial_link_cannot_carry_is_refused_at_its_line() {
    let (err, path, _dir) = check_shipped_cell_error(
        "config/cell.emulated.toml",
        "rate_hz = 500.0",
        "rate_hz = 1e-320",
    );
    let line = line_of(&path, "rate_hz = 1e-320");
    assert!(
        err.contains(&format!(
            ":{line}:11: tactile.rate_hz: expected a value in [100, 1960] Hz, found 1e-320"
        )),
        "{err}"
    );
    assert_run_refuses_cell(&path, &err);
    // A real finger on a 9600 baud link: 19 samples a second at most.
    let (err, path, _dir) = check_cell_error(
        "[tactile.backend.sim]\nline_spread_pitch = 0.55\nspan_v = 1.2\nrest_v = [0.9, 1.5]\ngain_spread = 0.1\nnoise_fraction = 0.02\n",
        "[tactile.backend.remodel]\nport = \"/dev/ttyACM0\"\nbaud = 9600\n",
    );
    let line = line_of(&path, "rate_hz = 500.0");
    assert!(
        err.contains(&format!(
            ":{line}:1: tactile.rate_hz: 500 Hz is more than the link at 9600 baud carries: 19 samples/s of 51 bytes"
        )),
        "{err}"
    );
}

#[test]
fn counts_a_run_cannot_hold_are_refused_by_check_and_run() {
    for (from, to, message) in [
        (
            "average_frames = 10",
            "average_frames = 99999999",
            "tactile.average_frames: expected a value in [1, 1000] frames, found 99999999",
        ),
        (
            "bias_samples = 50",
            "bias_samples = 4294967296",
            "tactile.bias_samples: expected a value in [1, 1000] frames, found 4294967296",
        ),
        (
            "max_regrasps = 2",
            "max_regrasps = 4294967295",
            "regrasp.max_regrasps: expected a value in [0, 100] regrasps, found 4294967295",
        ),
    ] {
        let (err, path, _dir) = check_error(from, to);
        let line = line_of(&path, to);
        assert!(err.contains(&format!(":{line}:")), "{err}");
        assert!(err.contains(message), "{err}");
    }
}

#[test]
fn task_values_no_cell_carries_out_are_refused_by_check_and_run() {
    for (from, to, message) in [
        (
            "open_mm = 20.0",
            "open_mm = 1e300",
            "grasp.open_mm: expected a value in [1, 68] mm, found 1e300",
        ),
        (
            "grip_current_a = 1.0",
            "grip_current_a = nan",
            "grasp.grip_current_a: expected a value in [0.1, 10] A, found NaN",
        ),
        (
            "standoff_mm = 60.0",
            "standoff_mm = 1e300",
            "approach.standoff_mm: expected a value in [1, 500] mm, found 1e300",
        ),
        (
            "contact_threshold_v = 0.05",
            "contact_threshold_v = 5.0",
            "tactile.contact_threshold_v: expected a value in [0.001, 3.3] V, found 5",
        ),
    ] {
        let (err, path, _dir) = check_error(from, to);
        let line = line_of(&path, to);
        assert!(err.contains(&format!(":{line}:")), "{err}");
        assert!(err.contains(message), "{err}");
    }
}

#[test]
fn a_correction_gain_that_is_no_gain_is_refused_at_its_field() {
    for (gain, message) in [
        (
            "{ n = nan, alpha = 1.0 }",
            "regrasp.correction_gain.n: expected a value in [0, 2], found NaN",
        ),
        (
            "{ n = 1.0, alpha = -0.5 }",
            "regrasp.correction_gain.alpha: expected a value in [0, 2], found -0.5",
        ),
        (
            "{ n = 1.0, alpha = 1.0, beta = 1.0 }",
            "regrasp.correction_gain.beta: unknown field `beta`, expected `n` or `alpha`",
        ),
    ] {
        let to = format!("max_regrasps = 2\ncorrection_gain = {gain}");
        let (err, path, _dir) = check_error("max_regrasps = 2", &to);
        let line = line_of(&path, "correction_gain");
        assert!(err.contains(&format!(":{line}:")), "{err}");
        assert!(err.contains(message), "{err}");
    }
}

#[test]
fn a_marker_outside_its_dictionary_is_refused_before_calibration() {
    for id in ["50", "-1"] {
        let to = format!("id = {id},");
        let (err, path, _dir) = check_cell_error("id = 3,", &to);
        let line = line_of(&path, &to);
        assert!(
            err.contains(&format!(
                ":{line}:35: camera.marker.id: expected a marker id in [0, 49] (the dictionary holds 50 markers), found {id}"
            )),
            "{err}"
        );
        let calibrate = cablecell(&[
            "calibrate-camera",
            "--cell",
            path.to_str().expect("utf-8 path"),
            "--dry-run",
        ]);
        assert_eq!(calibrate.status.code(), Some(BAD_INPUT));
        assert_eq!(String::from_utf8_lossy(&calibrate.stderr), err);
    }
}

/// Asserts that the binary run with `args` refuses them with exit status 2
/// and an error that holds each of `messages`.
fn assert_command_line_refused(args: &[&str], messages: &[&str]) {
    let out = cablecell(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(BAD_INPUT), "{args:?}: {err}");
    for message in messages {
        assert!(err.contains(message), "{args:?}: {err}");
    }
}

#[test]
fn command_line_numbers_out_of_range_are_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("set");
    let out = out.to_str().expect("utf-8 path");
    for (args, messages) in [
        (
            &[
                "render-dataset",
                out,
                "--min-cables",
                "4294967295",
                "--max-cables",
                "4294967295",
            ][..],
            &[
                "--min-cables",
                "expected a value in [0, 16] cables, found 4294967295",
            ][..],
        ),
        (
            &["render-dataset", out, "--max-cables", "100000"],
            &[
                "--max-cables",
                "expected a value in [0, 16] cables, found 100000",
            ],
        ),
        (
            &["render-dataset", out, "--width-px", "100000"],
            &[
                "--width-px",
                "expected a value in [16, 4096] px, found 100000",
            ],
        ),
        (
            &["render-dataset", out, "--min-diameter-px", "nan"],
            &["--min-diameter-px", "found NaN"],
        ),
        (
            &[
                "campaign",
                "tasks/paper-regrasp-campaign.toml",
                "--trials",
                "4294967296",
            ],
            &[
                "--trials",
                "expected a value in [1, 10000] trials, found 4294967296",
            ],
        ),
        (
            &[
                "campaign",
                "tasks/paper-regrasp-campaign.toml",
                "--threads",
                "0",
            ],
            &[
                "--threads",
                "expected a value in [1, 1024] threads, found 0",
            ],
        ),
        (
            &["repl", "tasks/regrasp.toml", "--pace", "nan"],
            &["--pace", "found NaN"],
        ),
        (
            &["tactile-fit", "--pitch-mm", "nan"],
            &["--pitch-mm", "expected a value in [1, 20] mm, found NaN"],
        ),
        (
            &["tactile-fit", "--contact-threshold-v", "0"],
            &[
                "--contact-threshold-v",
                "expected a value in [0.001, 3.3] V, found 0",
            ],
        ),
    ] {
        assert_command_line_refused(args, messages);
    }
    assert!(!Path::new(out).exists(), "nothing was rendered");
}

#[test]
fn a_calibration_speed_the_cell_refuses_is_bad_input() {
    for speed in ["0", "nan", "1e9"] {
        assert_command_line_refused(
            &["calibrate-camera", "--speed-mm-s", speed, "--dry-run"],
            &[
                "calibration pose 0: arm: refused",
                "the cell allows (0, 250] mm/s",
            ],
        );
    }
}
