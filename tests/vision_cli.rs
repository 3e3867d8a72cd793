//! `cablecell detect` and `cablecell eval-vision` on images the test
//! draws itself: plain backgrounds, where `--mask auto` takes the
//! classical mask and no network is needed.

use std::path::{Path, PathBuf};

mod common;

use common::{cablecell, json_of, text};

use cablecell::perception::vision::curves::segment_px;
use cablecell::perception::vision::network::{BUSY_MODEL, DEFAULT_MODEL};
use cablecell::sim::render::{Background, CableSpec, write_scene_files};
use common::scenes::{draw_scene, matte_cable};
use opencv::core::Vector;
use opencv::imgcodecs;
use opencv::prelude::*;

/// A ruler-straight dark cable 7 px across.
fn cable(from: [f64; 2], to: [f64; 2]) -> CableSpec {
    matte_cable(segment_px(from, to), 7.0, [30; 3])
}

/// Draws `cables` on a plain light background into DIR/STEM.jpg, with the
/// cables-dev ground truth beside it when `truth` is set.
fn write_scene(dir: &Path, stem: &str, cables: Vec<CableSpec>, truth: bool) -> PathBuf {
    write_scene_over(
        dir,
        stem,
        Background::Plain { bgr: [200; 3] },
        cables,
        truth,
    )
}

/// [`write_scene`] over `background`.
fn write_scene_over(
    dir: &Path,
    stem: &str,
    background: Background,
    cables: Vec<CableSpec>,
    truth: bool,
) -> PathBuf {
    let scene = draw_scene(480, 640, background, 0.0, cables, 7).expect("scene");
    let path = dir.join(format!("{stem}.jpg"));
    if truth {
        write_scene_files(dir, stem, &scene).expect("write scene");
    } else {
        assert!(imgcodecs::imwrite(text(&path), &scene.bgr, &Vector::new()).expect("write"));
    }
    path
}

/// Each image's report says whether its background is plain, busy or
/// painted, where the network for busy scenes makes the mask.
#[test]
fn detect_says_whether_the_background_is_plain_busy_or_painted() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (stem, background, plain, busy) in [
        ("table", Background::Plain { bgr: [200; 3] }, true, false),
        ("paint", Background::Pollock, false, true),
    ] {
        let cables = vec![cable([100.0, 100.0], [540.0, 380.0])];
        let path = write_scene_over(dir.path(), stem, background, cables, false);
        let reports = json_of(&["detect", text(&path), "--json"]);
        let report = &reports["images"][0];
        assert_eq!(report["plain_background"], plain, "{stem}");
        assert_eq!(report["busy_background"], busy, "{stem}");
        assert_eq!(report["painted_background"], busy, "{stem}");
    }
}

/// Without `--model`, the shipped network for busy scenes sees a painted
/// one; given `--model` alone, that network sees every scene.
#[test]
fn detect_sees_paint_with_the_busy_scenes_network_unless_given_one_model() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cables = vec![
        cable([100.0, 100.0], [540.0, 380.0]),
        cable([80.0, 400.0], [560.0, 60.0]),
    ];
    let path = write_scene_over(dir.path(), "paint", Background::Pollock, cables, false);
    let cables_found = |options: &[&str]| {
        let mut args = vec!["detect", text(&path), "--json"];
        args.extend(options);
        json_of(&args)["images"][0]["cables"].clone()
    };
    let by_default = cables_found(&[]);
    assert_eq!(
        by_default,
        cables_found(&["--model", DEFAULT_MODEL, "--busy-model", BUSY_MODEL])
    );
    assert_ne!(
        by_default,
        cables_found(&["--model", DEFAULT_MODEL]),
        "the two networks find the same cables: the test shows nothing"
    );
}

#[test]
fn detect_finds_one_cable_its_grasp_point_and_direction() {
    let dir = tempfile::tempdir().expect("tempdir");
    let image = write_scene(
        dir.path(),
        "one",
        vec![cable([100.0, 100.0], [540.0, 380.0])],
        false,
    );
    let (masks, overlay) = (dir.path().join("masks"), dir.path().join("overlay"));
    // The drawn cable is ruler-straight, but the table is alike on its two
    // sides: a taut cable, not an edge.
    let reports = json_of(&[
        "detect",
        text(&image),
        "--mask",
        "auto",
        "--json",
        "--masks",
        text(&masks),
        "--overlay",
        text(&overlay),
    ]);
    common::assert_follows_schema("detect", &reports);
    let report = &reports["images"][0];
    assert_eq!(report["mask_used"], "classical");
    assert_eq!(report["plain_background"], true);
    let cables = report["cables"].as_array().expect("cables");
    assert_eq!(cables.len(), 1);
    let grasp = &cables[0]["grasp_px"];
    let (x, y) = (grasp[0].as_f64().expect("x"), grasp[1].as_f64().expect("y"));
    assert!((x - 320.0).hypot(y - 240.0) < 5.0, "grasp at ({x}, {y})");
    let direction = cables[0]["direction_rad"].as_f64().expect("direction");
    let expected = (280.0_f64).atan2(440.0);
    assert!(
        (direction - expected).abs() < 0.05,
        "{direction} vs {expected}"
    );
    let stages = |report: &serde_json::Value| -> Vec<String> {
        let timings = report["stages"].as_array().expect("timings");
        timings
            .iter()
            .map(|t| t["stage"].as_str().expect("stage").to_owned())
            .collect()
    };
    assert!(stages(report).contains(&"instance_masks".to_owned()));
    for file in ["one_mask_0.png", "one_mask_all.png"] {
        let mask =
            imgcodecs::imread(text(&masks.join(file)), imgcodecs::IMREAD_GRAYSCALE).expect("read");
        assert_eq!((mask.cols(), mask.rows()), (640, 480), "{file}");
    }
    assert!(overlay.join("one.png").is_file());

    // Without `--masks` no cable's mask is drawn.
    let reports = &json_of(&["detect", text(&image), "--mask", "auto", "--json"])["images"];
    assert_eq!(reports[0]["cables"].as_array().map(Vec::len), Some(1));
    assert_eq!(stages(&reports[0]).len(), 4, "{:?}", stages(&reports[0]));
    assert!(!stages(&reports[0]).contains(&"instance_masks".to_owned()));
    assert_eq!(reports[0]["notes"].as_array().map(Vec::len), Some(0));

    // Read by a person: the one-off start-up first, then the image's
    // warmed-up times.
    let human = cablecell(&["detect", text(&image), "--mask", "auto"]);
    let printed = String::from_utf8_lossy(&human.stdout);
    let lines: Vec<&str> = printed.lines().collect();
    assert!(lines[0].starts_with("start-up: "), "{printed}");
    assert!(
        lines[1].contains("one.jpg: 1 cable(s), Classical mask"),
        "{printed}"
    );
    assert!(lines[2].starts_with("  cable 0: grasp at ("), "{printed}");
    // The cable's confidence, as in the JSON report.
    let confidence = reports[0]["cables"][0]["confidence"]
        .as_f64()
        .expect("a confidence in the JSON report");
    assert!(
        lines[2].ends_with(&format!(", confidence {confidence:.2}")),
        "{printed}"
    );
    // The spline: its control points, and points at s = 0, 0.1, ..., 1
    // from the end with the smaller x, the middle one the grasp point.
    let points = |line: &str, label: &str| -> Vec<[f64; 2]> {
        let list = line.strip_prefix(label).expect(line);
        let numbers: Vec<f64> = list
            .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
            .filter(|t| !t.is_empty())
            .map(|t| t.parse().expect(t))
            .collect();
        numbers.chunks(2).map(|p| [p[0], p[1]]).collect()
    };
    assert!(
        points(lines[3], "    control points (px): ").len() >= 4,
        "{printed}"
    );
    let along = points(lines[4], "    along it (px), s = 0, 0.1, ..., 1: ");
    assert_eq!(along.len(), 11, "{printed}");
    let near = |p: [f64; 2], q: [f64; 2], px: f64| (p[0] - q[0]).hypot(p[1] - q[1]) < px;
    assert!(near(along[0], [100.0, 100.0], 8.0), "{printed}");
    assert!(near(along[5], [x, y], 0.2), "{printed}");
    assert!(near(along[10], [540.0, 380.0], 8.0), "{printed}");
}

#[test]
fn detect_works_on_a_finer_image_at_the_working_width() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = draw_scene(
        960,
        1280,
        Background::Plain { bgr: [200; 3] },
        0.0,
        vec![matte_cable(
            segment_px([200.0, 200.0], [1080.0, 760.0]),
            14.0,
            [30; 3],
        )],
        7,
    )
    .expect("scene");
    let image = dir.path().join("fine.png");
    assert!(imgcodecs::imwrite(text(&image), &scene.bgr, &Vector::new()).expect("write"));
    let grasp = |extra: &[&str]| {
        let mut args = vec![
            "detect",
            text(&image),
            "--json",
            "--straight-edge-radius-px",
            "0",
        ];
        args.extend_from_slice(extra);
        let report = json_of(&args)["images"][0].clone();
        let g = &report["cables"][0]["grasp_px"];
        let at = [0, 1].map(|i| g[i].as_f64().expect("grasp point"));
        (report["work_scale"].as_f64().expect("work_scale"), at)
    };
    let (shrunk_scale, shrunk) = grasp(&[]);
    let (own_scale, own) = grasp(&["--work-width-px", "0"]);
    assert_eq!((shrunk_scale, own_scale), (0.5, 1.0));
    // Both in the image's pixels, at the cable's middle.
    for at in [shrunk, own] {
        assert!((at[0] - 640.0).hypot(at[1] - 480.0) < 3.0, "{at:?}");
    }
}

#[test]
fn detect_reports_no_cable_and_refuses_what_is_not_an_image() {
    let dir = tempfile::tempdir().expect("tempdir");
    let empty = write_scene(dir.path(), "empty", Vec::new(), false);
    let out = cablecell(&["detect", text(&empty), "--json"]);
    assert_eq!(out.status.code(), Some(0));
    let reports: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(
        reports["images"][0]["cables"].as_array().map(Vec::len),
        Some(0)
    );

    let bogus = dir.path().join("bogus.png");
    std::fs::write(&bogus, "not a picture").expect("write");
    let stderr = refused(&["detect", text(&bogus)]);
    assert!(
        stderr.contains("bogus.png: not an image OpenCV can decode"),
        "{stderr}"
    );
    let stderr = refused(&["detect", text(&dir.path().join("missing.png"))]);
    assert!(
        stderr.contains("missing.png: no such image file"),
        "{stderr}"
    );
    let stderr = refused(&["detect", text(dir.path())]);
    assert!(
        stderr.contains("is a folder, not an image file"),
        "{stderr}"
    );
    // OpenCV would decode the first half and grey the rest.
    let bytes = std::fs::read(&empty).expect("read");
    let cut = dir.path().join("cut.jpg");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).expect("write");
    let stderr = refused(&["detect", text(&cut)]);
    assert!(
        stderr.contains("cut.jpg: the JPEG data stops before its end-of-image marker"),
        "{stderr}"
    );
    // Whole, but with bytes of its scan overwritten: libjpeg would decode
    // it garbled, warning without the file's name.
    let mut garbled = bytes.clone();
    let middle = bytes.len() / 2;
    garbled[middle..middle + 40].fill(0x35);
    let corrupt = dir.path().join("corrupt.jpg");
    std::fs::write(&corrupt, &garbled).expect("write");
    let stderr = refused(&["detect", text(&corrupt)]);
    assert!(
        stderr.contains("corrupt.jpg: the JPEG data is corrupt ("),
        "{stderr}"
    );
}

#[test]
fn a_mask_folder_that_cannot_be_made_is_output_not_written() {
    let dir = tempfile::tempdir().expect("tempdir");
    let image = write_scene(
        dir.path(),
        "one",
        vec![cable([50.0, 240.0], [590.0, 240.0])],
        false,
    );
    // A folder inside a file: not even root can make it.
    let masks = image.join("masks");
    let out = cablecell(&["detect", text(&image), "--masks", text(&masks)]);
    assert_eq!(out.status.code(), Some(4));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("masks: cannot create the folder"), "{err}");
}

/// What `cablecell ARGS` wrote to stderr, having refused its input (exit 2).
fn refused(args: &[&str]) -> String {
    let out = cablecell(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    stderr
}

#[test]
fn a_missing_network_or_a_file_that_is_none_is_bad_input() {
    let dir = tempfile::tempdir().expect("tempdir");
    let image = write_scene(
        dir.path(),
        "net",
        vec![cable([50.0, 240.0], [590.0, 240.0])],
        false,
    );
    let out = cablecell(&[
        "detect",
        text(&image),
        "--mask",
        "network",
        "--model",
        "/no/such/model.onnx",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/no/such/model.onnx"), "{err}");
    // A file that is no network is the command line's fault too.
    let stderr = refused(&[
        "detect",
        text(&image),
        "--mask",
        "network",
        "--model",
        "README.md",
    ]);
    assert!(
        stderr.contains("segmentation network inference failed: model README.md"),
        "{stderr}"
    );
}

#[test]
fn eval_vision_with_a_model_that_is_no_network_is_bad_input() {
    // It exited with 1 (as if an image had failed) before; every image
    // would fail alike, so the command line is at fault.
    let dir = tempfile::tempdir().expect("tempdir");
    write_scene(
        dir.path(),
        "00000",
        vec![cable([80.0, 120.0], [560.0, 360.0])],
        true,
    );
    for more in [&[][..], &["--sweep", "--rounds", "1"]] {
        let mut args = vec!["eval-vision", text(dir.path()), "--model", "README.md"];
        args.extend(more);
        let stderr = refused(&args);
        assert!(
            stderr.contains("segmentation network inference failed: model README.md"),
            "{more:?}: {stderr}"
        );
    }
    // The busy scenes' network is loaded beforehand too, whether or not a
    // scene is busy.
    for (option, missing) in [
        ("--model", "/no/such/model.onnx"),
        ("--busy-model", "/no/such/busy-model.onnx"),
    ] {
        let stderr = refused(&["eval-vision", text(dir.path()), option, missing]);
        assert!(stderr.contains(missing), "{option}: {stderr}");
    }
}

/// The network and its runtime are found where the set-up put them from
/// any working directory, with nothing in the environment pointing there.
#[test]
fn detect_finds_the_network_from_any_working_directory() {
    let dir = tempfile::tempdir().expect("tempdir");
    write_scene(
        dir.path(),
        "elsewhere",
        vec![cable([60.0, 120.0], [580.0, 380.0])],
        false,
    );
    let out = common::command()
        .args(["detect", "elsewhere.jpg", "--json"])
        .args(["--straight-edge-radius-px", "0"])
        .current_dir(dir.path())
        .env_remove("ORT_DYLIB_PATH")
        .output()
        .expect("cablecell runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let found: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(found["images"][0]["mask_used"], "network", "{found}");
    assert_eq!(
        found["images"][0]["cables"].as_array().map(Vec::len),
        Some(1),
        "{found}"
    );
}

#[test]
fn eval_vision_names_every_malformed_image_and_where() {
    let dir = tempfile::tempdir().expect("tempdir");
    for stem in ["00000", "00001", "00002", "00003"] {
        write_scene(
            dir.path(),
            stem,
            vec![cable([80.0, 120.0], [560.0, 360.0])],
            true,
        );
    }
    std::fs::write(dir.path().join("00000.txt"), "2 10 10 20 20\n3 1 2 3\n").expect("write");
    std::fs::write(dir.path().join("00002_mask_0.png"), "not a picture").expect("write");
    let half_size = Mat::zeros(240, 320, opencv::core::CV_8UC1)
        .and_then(|m| m.to_mat())
        .expect("mask");
    for name in ["00003_mask_0.png", "00003_mask_all.png"] {
        let path = dir.path().join(name);
        assert!(imgcodecs::imwrite(text(&path), &half_size, &Vector::new()).expect("write"));
    }
    let stderr = refused(&["eval-vision", text(dir.path())]);
    assert!(
        stderr.contains("00000.txt, line 2: says 3 points but holds 3 coordinates"),
        "{stderr}"
    );
    assert!(stderr.contains("00002_mask_0.png"), "{stderr}");
    assert!(
        stderr
            .contains("00003_mask_0.png is 320x240 px, expected 640x480 px (the size of the image"),
        "{stderr}"
    );
    assert!(!stderr.contains("00001"), "{stderr}");
}

#[test]
fn eval_vision_scores_a_folder_laid_out_like_cables_dev() {
    let dir = tempfile::tempdir().expect("tempdir");
    write_scene(
        dir.path(),
        "00000",
        vec![cable([80.0, 120.0], [560.0, 360.0])],
        true,
    );
    write_scene(
        dir.path(),
        "00001",
        vec![
            cable([80.0, 100.0], [560.0, 380.0]),
            cable([80.0, 380.0], [560.0, 100.0]),
        ],
        true,
    );
    let e = json_of(&["eval-vision", text(dir.path()), "--mask", "auto", "--json"]);
    common::assert_follows_schema("eval-vision", &e);
    assert_eq!(e["images"], 2);
    assert!(e["union_dice"]["mean"].as_f64().expect("dice") > 0.8, "{e}");
    assert_eq!(e["count_right"]["successes"], 2, "{e}");
    assert!(
        e["grasp_error_px"]["max"].as_f64().expect("grasp") < 3.0,
        "{e}"
    );
    assert!(e["stage_ms"]["total"]["median"].as_f64().is_some());
    // Each image's most confident cable, which the task grasps first, is
    // grasped on a labelled one.
    assert_eq!(e["first_grasps_near_label"]["successes"], 2, "{e}");
    assert_eq!(e["first_grasps_near_label"]["trials"], 2, "{e}");
    // Dark cables on a plain table: `auto` takes the classical mask,
    // clean, on both.
    assert_eq!(
        e["mask_used"],
        serde_json::json!({"classical": 2, "network": 0, "labelled": 0}),
        "{e}"
    );
    assert_eq!(e["notes"].as_array().map(Vec::len), Some(0), "{e}");
    for side in ["labelled_length_found", "found_length_labelled"] {
        assert!(e[side]["share"].as_f64().expect("share") > 0.97, "{e}");
    }
    // The rendered masks are the 7 px cables along their centre lines, so
    // the labels agree with themselves at about that width.
    let labels = &e["labels_own_union_dice"];
    let width_px = labels["width_px"].as_f64().expect("width");
    assert!((6.0..=8.0).contains(&width_px), "{e}");
    assert!(
        labels["union_dice"]["mean"].as_f64().expect("dice") > 0.9,
        "{e}"
    );
    let human = cablecell(&["eval-vision", text(dir.path()), "--mask", "auto"]);
    let printed = String::from_utf8_lossy(&human.stdout);
    assert!(printed.contains("instance count right"), "{printed}");
    assert!(printed.contains("labels' own union DICE"), "{printed}");
    assert!(!printed.contains("count wrong in"), "{printed}");

    // A labelled cable that runs out of view with only 60 px in it is
    // dropped, too short to grasp: the evaluation says so per image.
    write_scene(
        dir.path(),
        "00002",
        vec![cable([-20.0, 240.0], [60.0, 240.0])],
        true,
    );
    let human = cablecell(&["eval-vision", text(dir.path()), "--mask", "auto"]);
    let printed = String::from_utf8_lossy(&human.stdout);
    assert!(
        printed.contains("count wrong in         00002 (0 found, 1 labelled)"),
        "{printed}"
    );
    assert!(
        printed.contains("note: 00002: dropped 1 cable(s) that run out of view shorter than 90 px"),
        "{printed}"
    );
}

/// Scores, as DIR/00000, an image of the `shown` cables against labels
/// of the `labelled` ones, with `auto`'s classical mask, keeping straight
/// cables: the `eval-vision` arguments and its JSON report.
fn eval_labels_over(
    dir: &Path,
    labelled: Vec<CableSpec>,
    shown: Vec<CableSpec>,
) -> ([&str; 6], serde_json::Value) {
    write_scene(dir, "00000", labelled, true);
    write_scene(dir, "00000", shown, false);
    let args = [
        "eval-vision",
        text(dir),
        "--mask",
        "auto",
        "--straight-edge-radius-px",
        "0",
    ];
    let e = json_of(&[&args[..], &["--json"]].concat());
    (args, e)
}

#[test]
fn eval_vision_names_the_cables_that_each_side_lacks() {
    // The image shows cables A and B; its labels give A and C, a cable
    // that runs out of the image at the top and is not there.
    let dir = tempfile::tempdir().expect("tempdir");
    let a = cable([80.0, 300.0], [560.0, 420.0]);
    let b = cable([150.0, 250.0], [450.0, 100.0]);
    let c = cable([500.0, 0.0], [600.0, 200.0]);
    let (args, e) = eval_labels_over(dir.path(), vec![a.clone(), c], vec![a, b]);
    let score = &e["per_image"][0][1];
    assert_eq!(score["count_right"], true, "{e}");
    let missed = score["missed"].as_array().expect("missed");
    assert_eq!(missed.len(), 1, "{e}");
    assert_eq!(missed[0]["index"], 1, "{e}");
    assert_eq!(missed[0]["at_border"], true, "{e}");
    // C is 224 px long.
    let c_px = missed[0]["length_px"].as_f64().expect("length");
    assert!((215.0..=230.0).contains(&c_px), "{e}");
    let unlabelled = score["unlabelled"].as_array().expect("unlabelled");
    assert_eq!(unlabelled.len(), 1, "{e}");
    assert_eq!(unlabelled[0]["at_border"], false, "{e}");
    // B is 335 px long; its detection a little shorter at the ends.
    let b_px = unlabelled[0]["length_px"].as_f64().expect("length");
    assert!((315.0..=340.0).contains(&b_px), "{e}");
    // Of the labelled length, A's 495 px is found and C's 224 px is not;
    // of the found length, A's is labelled and B's is not.
    let share = |side: &str| e[side]["share"].as_f64().expect("share");
    let labelled_share = 495.0 / (495.0 + c_px);
    let found_share = 495.0 / (495.0 + b_px);
    assert!(
        (share("labelled_length_found") - labelled_share).abs() < 0.02,
        "{e}"
    );
    assert!(
        (share("found_length_labelled") - found_share).abs() < 0.02,
        "{e}"
    );

    let overlay = dir.path().join("overlay");
    let human = cablecell(&[&args[..], &["--overlay", text(&overlay)]].concat());
    let printed = String::from_utf8_lossy(&human.stdout);
    let found = unlabelled[0]["index"].as_u64().expect("index");
    assert!(
        printed.contains(&format!(
            "labelled, not found    1 of 2: 00000 #1 ({c_px:.0} px, at the border)"
        )),
        "{printed}"
    );
    assert!(
        printed.contains(&format!(
            "found, not labelled    1 of 2: 00000 #{found} ({b_px:.0} px)"
        )),
        "{printed}"
    );
    assert!(
        printed.contains(&format!(
            "labelled length found  {:.1} % of",
            100.0 * share("labelled_length_found")
        )),
        "{printed}"
    );
    assert!(printed.contains("; under 90 % in 00000 "), "{printed}");
    // The overlay draws the labelled centre lines in white, and the one
    // not found thick in red: A's and C's midpoints.
    let drawn = imgcodecs::imread(text(&overlay.join("00000.png")), imgcodecs::IMREAD_COLOR)
        .expect("overlay");
    assert_eq!((drawn.cols(), drawn.rows()), (640, 480));
    let bgr = |x: i32, y: i32| *drawn.at_2d::<opencv::core::Vec3b>(y, x).expect("pixel");
    let on_a = bgr(320, 360);
    assert!(on_a.iter().all(|&v| v > 200), "{on_a:?}");
    let on_c = bgr(550, 100);
    assert!(on_c[2] > 200 && on_c[0] < 80 && on_c[1] < 80, "{on_c:?}");
}

#[test]
fn eval_vision_says_when_the_first_grasp_is_on_no_labelled_cable() {
    // The image shows cable A alone; its label is C, which is not there:
    // the task's first grasp, on A, holds no labelled cable.
    let dir = tempfile::tempdir().expect("tempdir");
    let a = cable([80.0, 300.0], [560.0, 420.0]);
    let c = cable([500.0, 0.0], [600.0, 200.0]);
    let (args, e) = eval_labels_over(dir.path(), vec![c.clone()], vec![a]);
    assert_eq!(e["per_image"][0][1]["first_grasp_near"], false, "{e}");
    assert_eq!(e["first_grasps_near_label"]["successes"], 0, "{e}");
    assert_eq!(e["first_grasps_near_label"]["trials"], 1, "{e}");
    let printed = String::from_utf8_lossy(&cablecell(&args).stdout).into_owned();
    assert!(
        printed.contains("first grasp near label 0/1 = 0.0 %"),
        "{printed}"
    );

    // With nothing in view, no grasp is tried.
    let (_, e) = eval_labels_over(dir.path(), vec![c], vec![]);
    assert_eq!(
        e["per_image"][0][1]["first_grasp_near"],
        serde_json::Value::Null,
        "{e}"
    );
    assert_eq!(e["first_grasps_near_label"], serde_json::Value::Null, "{e}");
}

#[test]
fn eval_vision_finds_labels_that_lie_beside_their_cables() {
    // The labels lie 2 px above the cable drawn in the image.
    let dir = tempfile::tempdir().expect("tempdir");
    let drawn = |left_y_px: f64| vec![cable([80.0, left_y_px], [560.0, left_y_px - 120.0])];
    let (args, e) = eval_labels_over(dir.path(), drawn(298.0), drawn(300.0));
    let score = &e["per_image"][0][1];
    assert_eq!(score["mask_offset_px"], serde_json::json!([0, -2]), "{e}");
    let (dice, moved) = (
        score["union_dice"].as_f64().expect("dice"),
        score["union_dice_at_offset"].as_f64().expect("moved"),
    );
    assert!(moved > dice + 0.1, "{e}");
    let printed = String::from_utf8_lossy(&cablecell(&args).stdout).into_owned();
    assert!(
        printed.contains("median move (dx, dy) (0, -2) px; 2 px or more in 00000 (0, -2))"),
        "{printed}"
    );
}
