//! `cablecell render-dataset`: the layout it writes (that of cables-dev,
//! which `eval-vision` and the training script read), with rendered cables
//! or another folder's, its determinism for a seed, and its refusals.

use std::path::Path;
use std::process::Output;

mod common;

use common::{cablecell, text};

use opencv::core::{self, Mat};
use opencv::imgcodecs;
use opencv::prelude::*;

fn read(path: &Path, flags: i32) -> Mat {
    let image = imgcodecs::imread(text(path), flags).expect("imread");
    assert!(!image.empty(), "{} missing or unreadable", path.display());
    image
}

fn render(out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["render-dataset", text(out)];
    args.extend_from_slice(extra);
    cablecell(&args)
}

#[test]
fn writes_the_cables_dev_layout() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("set");
    let run = render(
        &out,
        &[
            "--count",
            "4",
            "--seed",
            "5",
            "--width-px",
            "320",
            "--height-px",
            "240",
            "--min-cables",
            "2",
            "--max-cables",
            "3",
        ],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for index in 0..4 {
        let cables = check_layout(&out, &format!("{index:05}"), (320, 240));
        assert!((2..=3).contains(&cables), "{index}: {cables} cables");
    }
    assert!(!out.join("00004.jpg").exists());
}

/// Checks image `stem` of the data set in `out` against the cables-dev
/// layout: the image `size` (width, height), one mask per polyline, each
/// polyline's points in view on its own mask, the union mask the masks'
/// union. Returns its number of cables.
fn check_layout(out: &Path, stem: &str, size: (i32, i32)) -> usize {
    let (width, height) = size;
    let image = read(&out.join(format!("{stem}.jpg")), imgcodecs::IMREAD_COLOR);
    assert_eq!((image.cols(), image.rows()), size, "{stem}");

    let polylines = std::fs::read_to_string(out.join(format!("{stem}.txt"))).expect("txt");
    let lines: Vec<Vec<f64>> = polylines
        .lines()
        .map(|l| {
            l.split_whitespace()
                .map(|w| w.parse().expect("number"))
                .collect()
        })
        .collect();

    let union = read(
        &out.join(format!("{stem}_mask_all.png")),
        imgcodecs::IMREAD_GRAYSCALE,
    );
    let mut rebuilt = Mat::zeros(height, width, core::CV_8U)
        .expect("zeros")
        .to_mat()
        .expect("mat");
    for (k, numbers) in lines.iter().enumerate() {
        // `N x0 y0 ...`: N pairs follow.
        let n = numbers[0] as usize;
        assert_eq!(numbers.len(), 1 + 2 * n, "{stem} line {}", k + 1);
        let mask = read(
            &out.join(format!("{stem}_mask_{k}.png")),
            imgcodecs::IMREAD_GRAYSCALE,
        );
        assert_eq!((mask.cols(), mask.rows()), size);
        // A polyline point inside the image lies on its own cable's mask.
        let inside: Vec<(i32, i32)> = numbers[1..]
            .chunks_exact(2)
            .map(|p| (p[0] as i32, p[1] as i32))
            .filter(|&(x, y)| (0..width).contains(&x) && (0..height).contains(&y))
            .collect();
        assert!(!inside.is_empty(), "{stem}: cable {k} never in the image");
        for (x, y) in inside {
            assert_eq!(*mask.at_2d::<u8>(y, x).expect("pixel"), 255, "{stem} {k}");
        }
        let mut next = Mat::default();
        core::bitwise_or(&rebuilt, &mask, &mut next, &core::no_array()).expect("or");
        rebuilt = next;
    }
    assert!(
        !out.join(format!("{stem}_mask_{}.png", lines.len()))
            .exists(),
        "{stem}: more masks than polylines"
    );
    let mut diff = Mat::default();
    core::absdiff(&rebuilt, &union, &mut diff).expect("absdiff");
    assert_eq!(
        core::count_non_zero(&diff).expect("count"),
        0,
        "{stem}: the union mask is not the union of the cables' masks"
    );
    lines.len()
}

/// The mean colour of `out`'s image `stem` under its union mask.
fn cable_colour(out: &Path, stem: &str) -> core::Scalar {
    let image = read(&out.join(format!("{stem}.jpg")), imgcodecs::IMREAD_COLOR);
    let union = read(
        &out.join(format!("{stem}_mask_all.png")),
        imgcodecs::IMREAD_GRAYSCALE,
    );
    core::mean(&image, &union).expect("mean")
}

#[test]
fn another_folders_cables_lie_over_rendered_backgrounds_with_their_labels() {
    let dir = tempfile::tempdir().expect("tempdir");
    let photos = dir.path().join("photos");
    let size = ["--width-px", "320", "--height-px", "240"];
    let source = [
        &size[..],
        &[
            "--count",
            "1",
            "--seed",
            "13",
            "--backgrounds",
            "plain",
            "--max-cables",
            "1",
        ],
    ]
    .concat();
    assert!(render(&photos, &source).status.success());

    let out = dir.path().join("pasted");
    let pasted = [
        &size[..],
        &[
            "--count",
            "3",
            "--seed",
            "7",
            "--backgrounds",
            "busy",
            "--cables-from",
            text(&photos),
            "--to",
            "00000",
        ],
    ]
    .concat();
    let run = render(&out, &pasted);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(String::from_utf8_lossy(&run.stdout).contains("(1 image)"));
    // All three hold photograph 00000's cable, each placed its own way:
    // its colours under its mask, its label in other places.
    let colour = cable_colour(&photos, "00000");
    let mut labels = Vec::new();
    for index in 0..3 {
        let stem = format!("{index:05}");
        let cables = check_layout(&out, &stem, (320, 240));
        assert_eq!(cables, 1, "{stem}");
        let pasted = cable_colour(&out, &stem);
        for channel in 0..3 {
            assert!(
                (pasted[channel] - colour[channel]).abs() < 25.0,
                "{stem}: {pasted:?} against {colour:?}"
            );
        }
        labels.push(std::fs::read_to_string(out.join(format!("{stem}.txt"))).expect("txt"));
    }
    assert!(
        labels[0] != labels[1] && labels[1] != labels[2],
        "{labels:?}"
    );
    assert!(!out.join("00003.jpg").exists());

    // With shadows: the same scenes and labels, the background darker
    // just beside the cables and as it was far from them.
    let shadowed = dir.path().join("shadowed");
    let run = render(&shadowed, &[&pasted[..], &["--cast-shadows"]].concat());
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (mut near, mut far) = ([0.0; 2], [0.0; 2]);
    for index in 0..3 {
        let stem = format!("{index:05}");
        for name in [format!("{stem}.txt"), format!("{stem}_mask_0.png")] {
            assert_eq!(
                std::fs::read(out.join(&name)).expect("unshadowed"),
                std::fs::read(shadowed.join(&name)).expect("shadowed"),
                "{name}"
            );
        }
        let union = read(
            &out.join(format!("{stem}_mask_all.png")),
            imgcodecs::IMREAD_GRAYSCALE,
        );
        let grown = |by_px: i32| {
            let mut grown = Mat::default();
            let kernel = opencv::imgproc::get_structuring_element_def(
                opencv::imgproc::MORPH_ELLIPSE,
                core::Size::new(2 * by_px + 1, 2 * by_px + 1),
            )
            .expect("kernel");
            opencv::imgproc::dilate_def(&union, &mut grown, &kernel).expect("dilate");
            grown
        };
        let ring = |from_px: i32, to_px: i32| {
            let mut ring = Mat::default();
            core::subtract_def(&grown(to_px), &grown(from_px), &mut ring).expect("ring");
            ring
        };
        let mut beyond = Mat::default();
        core::bitwise_not_def(&grown(24), &mut beyond).expect("beyond");
        for (k, folder) in [&out, &shadowed].into_iter().enumerate() {
            let gray = read(
                &folder.join(format!("{stem}.jpg")),
                imgcodecs::IMREAD_GRAYSCALE,
            );
            near[k] += core::mean(&gray, &ring(2, 6)).expect("mean")[0];
            far[k] += core::mean(&gray, &beyond).expect("mean")[0];
        }
    }
    assert!(near[1] < near[0] - 5.0, "near the cables: {near:?}");
    assert!((far[1] - far[0]).abs() < 0.5, "far from them: {far:?}");

    // Refused: a folder with no labelled images, rendered cables' options
    // beside it, and a photograph range or shadows without it.
    let missing = dir.path().join("no-such-folder");
    let run = render(&dir.path().join("a"), &["--cables-from", text(&missing)]);
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("no-such-folder"));
    let run = render(
        &dir.path().join("b"),
        &["--cables-from", text(&photos), "--max-cables", "2"],
    );
    assert_eq!(run.status.code(), Some(2));
    let run = render(&dir.path().join("c"), &["--from", "00001"]);
    assert_eq!(run.status.code(), Some(2));
    let run = render(&dir.path().join("d"), &["--cast-shadows"]);
    assert_eq!(run.status.code(), Some(2));
    for name in ["a", "b", "c", "d"] {
        assert!(!dir.path().join(name).exists(), "{name}");
    }
}

#[test]
fn a_board_over_a_cable_hides_it_from_the_written_masks() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("set");
    let run = render(
        &out,
        &[
            "--count",
            "6",
            "--seed",
            "13",
            "--backgrounds",
            "workbench",
            "--max-cables",
            "1",
            "--min-diameter-px",
            "6",
            "--max-diameter-px",
            "8",
        ],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // A cable's full tube, drawn along its labelled centre line, against its
    // written mask: the board's stretch is missing from the mask in some
    // images, and the union mask is the cables' masks together.
    let mut boarded = 0;
    for index in 0..6 {
        let stem = format!("{index:05}");
        let mask = read(
            &out.join(format!("{stem}_mask_0.png")),
            imgcodecs::IMREAD_GRAYSCALE,
        );
        let union = read(
            &out.join(format!("{stem}_mask_all.png")),
            imgcodecs::IMREAD_GRAYSCALE,
        );
        let mut differ = Mat::default();
        core::compare(&mask, &union, &mut differ, core::CMP_NE).expect("compare");
        assert_eq!(core::count_non_zero(&differ).expect("count"), 0, "{stem}");
        let line = std::fs::read_to_string(out.join(format!("{stem}.txt"))).expect("txt");
        let numbers: Vec<f64> = line
            .split_whitespace()
            .skip(1)
            .map(|v| v.parse().expect("a number"))
            .collect();
        let on_mask = numbers
            .chunks(2)
            .filter(|p| *mask.at_2d::<u8>(p[1] as i32, p[0] as i32).expect("inside") > 0)
            .count();
        let points = numbers.len() / 2;
        if on_mask + 2 < points {
            boarded += 1;
            assert!(on_mask > 0, "{stem}: all hidden");
        }
    }
    assert!(boarded > 0, "no image of six had a board");
}

#[test]
fn the_same_seed_gives_the_same_images_and_another_seed_others() {
    let dir = tempfile::tempdir().expect("tempdir");
    let args = ["--count", "2", "--width-px", "160", "--height-px", "120"];
    let mut outputs = Vec::new();
    for (name, seed) in [("a", "9"), ("b", "9"), ("c", "10")] {
        let out = dir.path().join(name);
        let mut all = args.to_vec();
        all.extend(["--seed", seed]);
        assert!(render(&out, &all).status.success());
        outputs.push(std::fs::read(out.join("00001.jpg")).expect("image"));
    }
    assert_eq!(outputs[0], outputs[1]);
    assert_ne!(outputs[0], outputs[2]);
}

#[test]
fn refuses_a_folder_that_holds_files_and_bad_options() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("00000.jpg"), b"old").expect("write");
    let run = render(dir.path(), &["--count", "1"]);
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("not empty"));
    assert_eq!(
        std::fs::read(dir.path().join("00000.jpg")).expect("kept"),
        b"old"
    );

    let out = dir.path().join("new");
    let run = render(&out, &["--min-cables", "5", "--max-cables", "2"]);
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("--min-cables 5"));
    let run = render(&out, &["--min-diameter-px", "0"]);
    assert_eq!(run.status.code(), Some(2));
    assert!(!out.exists());
}

#[test]
fn eval_vision_scores_a_rendered_set_selects_images_and_sweeps_settings() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("plain");
    let run = render(
        &out,
        &[
            "--count",
            "3",
            "--seed",
            "21",
            "--backgrounds",
            "plain",
            "--max-cables",
            "2",
            "--no-crossings",
        ],
    );
    assert!(run.status.success());

    let eval = cablecell(&[
        "eval-vision",
        text(&out),
        "--mask",
        "classical",
        "--from",
        "00001",
        "--json",
    ]);
    assert!(
        eval.status.success(),
        "{}",
        String::from_utf8_lossy(&eval.stderr)
    );
    let e: serde_json::Value = serde_json::from_slice(&eval.stdout).expect("JSON");
    common::assert_follows_schema("eval-vision", &e);
    assert_eq!(e["images"], 2, "{e}");
    let stems: Vec<&str> = e["per_image"]
        .as_array()
        .expect("per image")
        .iter()
        .map(|p| p[0].as_str().expect("stem"))
        .collect();
    assert_eq!(stems, ["00001", "00002"]);
    assert_eq!(
        e["mask_used"],
        serde_json::json!({"classical": 2, "network": 0, "labelled": 0}),
        "{e}"
    );
    // Exact ground truth and plain backgrounds: the classical mask matches,
    // and each labelled cable is one found.
    assert!(e["union_dice"]["mean"].as_f64().expect("dice") > 0.8, "{e}");
    let found = e["per_image"][0][1]["predicted_count"].clone();
    assert_eq!(e["per_image"][0][1]["truth_count"], found, "{e}");
    assert_eq!(e["labels_found"]["rate"], 1.0, "{e}");
    assert_eq!(e["found_labelled"]["rate"], 1.0, "{e}");
    // Exact truth lies where the cables are: no move matches it better.
    for image in e["per_image"].as_array().expect("per image") {
        let score = &image[1];
        assert_eq!(score["mask_offset_px"], serde_json::json!([0, 0]), "{e}");
        assert_eq!(score["union_dice_at_offset"], score["union_dice"], "{e}");
    }

    let none = cablecell(&["eval-vision", text(&out), "--from", "00005"]);
    assert_eq!(none.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&none.stderr).contains("between 00005 and the last"));

    let sweep = cablecell(&[
        "eval-vision",
        text(&out),
        "--to",
        "00000",
        "--sweep",
        "--rounds",
        "2",
        "--json",
    ]);
    assert!(
        sweep.status.success(),
        "{}",
        String::from_utf8_lossy(&sweep.stderr)
    );
    let sweep: serde_json::Value = serde_json::from_slice(&sweep.stdout).expect("JSON");
    common::assert_follows_schema("eval-vision-sweep", &sweep);
    let rows = &sweep["rows"];
    let settings: Vec<&str> = rows
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| r["setting"].as_str().expect("setting"))
        .collect();
    assert_eq!(settings.len(), 10, "{settings:?}");
    assert!(settings[0].starts_with("classical mask"));
    assert!(settings.iter().any(|s| s.contains("superpixels")));
    // The shipped 8-bit network scores as the float one it came from, and
    // as the mirrored one that wraps it.
    assert!(settings[1].starts_with("network at 0.375×"));
    assert!(settings[4].starts_with("float network at 0.375×"));
    assert!(settings[5].starts_with("mirrored network at 0.375×"));
    let dice = |row: usize| rows[row]["union_dice"].as_f64().expect("dice");
    assert!((dice(1) - dice(4)).abs() < 0.02, "{rows}");
    assert!((dice(1) - dice(5)).abs() < 0.02, "{rows}");
    // The last row is the labels against themselves: the rendered masks are
    // their centre lines' tubes, so they agree closely.
    assert!(settings[9].starts_with("labels' own centre lines"));
    assert!(dice(9) > 0.9, "{rows}");
    assert!(rows[9]["total_ms_median"].is_null(), "{rows}");
    assert!(rows[9]["labels_found"].is_null(), "{rows}");
    assert_eq!(rows[0]["labels_found"], 1.0, "{rows}");
    // The classical mask finds both cables along their whole length.
    for side in ["labelled_length_found", "found_length_labelled"] {
        assert!(rows[0][side].as_f64().expect("share") > 0.97, "{rows}");
        assert!(rows[9][side].is_null(), "{rows}");
    }
    let no_rounds = cablecell(&["eval-vision", text(&out), "--sweep", "--rounds", "0"]);
    assert_eq!(no_rounds.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&no_rounds.stderr).contains("--rounds"));
    assert!(
        rows[0]["union_dice"].as_f64().expect("dice") > 0.8,
        "{rows}"
    );
}

#[test]
fn eval_vision_finds_the_cables_in_the_labelled_masks_without_a_network() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("busy");
    let run = render(
        &out,
        &["--count", "2", "--seed", "31", "--backgrounds", "busy"],
    );
    assert!(run.status.success());
    // A model that is no network: the labelled masks need none.
    let args = [
        "eval-vision",
        text(&out),
        "--labelled-mask",
        "--model",
        "README.md",
    ];
    let e = common::json_of(&[&args[..], &["--json"]].concat());
    common::assert_follows_schema("eval-vision", &e);
    assert_eq!(
        e["mask_used"],
        serde_json::json!({"classical": 0, "network": 0, "labelled": 2}),
        "{e}"
    );
    // The cables' masks are cut from the labelled one: they cover nearly
    // all of it and nothing else, over a background as busy as the paper's.
    assert!(
        e["union_dice"]["mean"].as_f64().expect("dice") > 0.95,
        "{e}"
    );
    assert_eq!(e["found_labelled"]["rate"], 1.0, "{e}");
    assert!(e["stage_ms"].get("instances").is_some(), "{e}");
    assert!(e["stage_ms"].get("mask").is_none(), "{e}");

    // Drawn as with a found mask: what the instance stages made of the
    // labelled one, to see where they went wrong.
    let overlays = dir.path().join("overlays");
    let with_overlay = cablecell(&[&args[..], &["--overlay", text(&overlays)]].concat());
    assert!(with_overlay.status.success(), "{with_overlay:?}");
    for stem in ["00000", "00001"] {
        let drawn = overlays.join(format!("{stem}.png"));
        let image =
            imgcodecs::imread(text(&drawn), imgcodecs::IMREAD_COLOR).expect("read the overlay");
        assert_eq!(
            (image.cols(), image.rows()),
            (640, 480),
            "{}",
            drawn.display()
        );
    }
}
