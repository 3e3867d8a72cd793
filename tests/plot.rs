//! `cablecell plot tactile|regrasp|campaign` end to end: a short simulated
//! run recorded, a tiny campaign, each figure drawn as SVG and PNG and read
//! back; bad input refused with exit status 2, naming the file.

use std::path::Path;

mod common;

use common::{root, text};

use cablecell::plot::colour;
use opencv::core::Vec3b;
use opencv::prelude::*;
use plotters::style::RGBColor;

/// `#RRGGBB` as plotters' SVG writes a colour.
fn hex(RGBColor(r, g, b): RGBColor) -> String {
    format!("#{r:02X}{g:02X}{b:02X}")
}

/// The binary with `args`, which must succeed.
fn plot(args: &[&str]) {
    let out = common::cablecell(args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The regrasp task, seed 3, on the simulated cell with the oracle that
/// misses by a few millimetres (one regrasp), recorded to DIR/run.mcap.
fn recorded_run(dir: &Path) -> std::path::PathBuf {
    let cell = common::sim_cell_with_oracle_file(dir);
    let recording = dir.join("run.mcap");
    plot(&[
        "run",
        "tasks/regrasp.toml",
        "--cell",
        text(&cell),
        "--seed",
        "3",
        "--record",
        text(&recording),
    ]);
    recording
}

/// The SVG's text, after checking it is not empty.
fn svg(path: &Path) -> String {
    let svg = std::fs::read_to_string(path).expect("the SVG");
    assert!(svg.starts_with("<svg") && svg.len() > 1000, "{svg}");
    svg
}

/// Reads the PNG back: it decodes, has the figures' size and shows more
/// than a blank page.
fn check_png(path: &Path) {
    let image =
        opencv::imgcodecs::imread(text(path), opencv::imgcodecs::IMREAD_COLOR).expect("imread");
    assert_eq!(
        (image.cols(), image.rows()),
        (1000, 620),
        "{}",
        path.display()
    );
    let mut drawn = 0;
    for row in 0..image.rows() {
        for col in 0..image.cols() {
            let [b, g, r] = image.at_2d::<Vec3b>(row, col).expect("pixel").0;
            if (r, g, b) != (255, 255, 255) {
                drawn += 1;
            }
        }
    }
    assert!(drawn > 20_000, "{}: {drawn} pixels drawn", path.display());
}

/// `<circle` elements filled with `colour`.
fn filled_circles(svg: &str, colour: RGBColor) -> usize {
    let fill = format!("fill=\"{}\"", hex(colour));
    svg.split("<circle")
        .skip(1)
        .filter(|c| c.contains(&fill))
        .count()
}

/// `<polyline` elements stroked with `colour` at `width`.
fn polylines(svg: &str, colour: RGBColor, width: u32) -> usize {
    let stroke = format!("stroke=\"{}\" stroke-width=\"{width}\"", hex(colour));
    svg.split("<polyline")
        .skip(1)
        .filter(|p| p.contains(&stroke))
        .count()
}

#[test]
fn plot_tactile_draws_the_25_taxels_fits_and_truth() {
    let dir = tempfile::tempdir().unwrap();
    let recording = recorded_run(dir.path());
    let path = dir.path().join("fig7.svg");
    plot(&[
        "plot",
        "tactile",
        text(&recording),
        "--grasp",
        "1",
        "--out",
        text(&path),
    ]);
    let drawn = svg(&path);
    assert_eq!(filled_circles(&drawn, colour::TAXEL), 25);
    for label in [
        "Tactile map at the regrasp 1, regrasp seed 3",
        "centroids, one per",
        "linear fit (eq. 2)",
        "quadratic fit (eq.",
        "true cable: n",
    ] {
        assert!(drawn.contains(label), "no {label:?}");
    }
    // The centroids, one per column or row that holds the cable (at least
    // three), and the legend's.
    assert!(filled_circles(&drawn, colour::CENTROID) >= 4);
    // By default a PNG beside the recording, of the trial grasp.
    plot(&["plot", "tactile", text(&recording)]);
    check_png(&dir.path().join("run-tactile-0.png"));

    // A map file as `tactile-fit` reads it: a cable along the middle row.
    let map = dir.path().join("map.txt");
    let rows: Vec<&str> = vec!["0 0 0 0 0", "0.1 0.1 0.1 0.1 0.1", "0.8 0.8 0.8 0.8 0.8"];
    let text_map = [&rows[..], &["0.1 0.1 0.1 0.1 0.1", "0 0 0 0 0"]].concat();
    std::fs::write(&map, text_map.join("\n")).unwrap();
    plot(&["plot", "tactile", text(&map)]);
    check_png(&dir.path().join("map-tactile.png"));
    let map_svg = dir.path().join("map.svg");
    plot(&["plot", "tactile", text(&map), "--out", text(&map_svg)]);
    let drawn = svg(&map_svg);
    assert_eq!(filled_circles(&drawn, colour::TAXEL), 25);
    assert!(drawn.contains("linear fit (eq. 2): n +0.00 mm"));
    assert!(!drawn.contains("true cable"));
}

#[test]
fn plot_regrasp_draws_one_line_per_grasp_and_the_target() {
    let dir = tempfile::tempdir().unwrap();
    let recording = recorded_run(dir.path());
    let path = dir.path().join("fig11.svg");
    plot(&["plot", "regrasp", text(&recording), "--out", text(&path)]);
    let drawn = svg(&path);
    // Seed 3: the trial grasp and one regrasp, each its colour: its fitted
    // line and its legend's sample, nothing else at that width.
    let width = cablecell::plot::regrasp::FIT_WIDTH;
    for grasp in 0..2 {
        let grasp_colour = colour::GRASPS[grasp];
        assert_eq!(polylines(&drawn, grasp_colour, width), 2, "grasp {grasp}");
    }
    assert_eq!(polylines(&drawn, colour::GRASPS[2], width), 0);
    for label in [
        "target: n +0.00 mm, α +0.000 rad",
        "tolerance: |n| ≤ 1.00 mm",
        "trial grasp, the pad&apos;s fit: n",
        "trial grasp, the true cable: n",
        "regrasp 1, the pad&apos;s fit: n",
        "regrasp 1, the true cable: n",
    ] {
        assert!(drawn.contains(label), "no {label:?}");
    }
    plot(&["plot", "regrasp", text(&recording)]);
    check_png(&dir.path().join("run-regrasp.png"));
}

/// A campaign of the shipped one's policies, 3 trials, into DIR/out.
fn tiny_campaign(dir: &Path) -> std::path::PathBuf {
    let shipped = std::fs::read_to_string(root().join("tasks/paper-regrasp-campaign.toml"))
        .expect("the shipped campaign");
    let tasks = root().join("tasks");
    let file = shipped
        .replace(
            "\"regrasp.toml\"",
            &format!("{:?}", tasks.join("regrasp.toml")),
        )
        .replace(
            "\"../config/cell.sim.toml\"",
            &format!("{:?}", root().join("config/cell.sim.toml")),
        );
    let path = dir.join("campaign.toml");
    std::fs::write(&path, file).unwrap();
    let out = dir.join("out");
    plot(&[
        "campaign",
        text(&path),
        "--trials",
        "3",
        "--out",
        text(&out),
        "--no-record",
    ]);
    out
}

#[test]
fn plot_campaign_names_every_policy_with_its_success_rate() {
    let dir = tempfile::tempdir().unwrap();
    let out = tiny_campaign(dir.path());
    let path = dir.path().join("campaign.svg");
    plot(&["plot", "campaign", text(&out), "--out", text(&path)]);
    let drawn = svg(&path);
    for label in [
        "paper: success ",
        "cablecell: success ",
        "(95 % CI ",
        "regrasps per trial",
        "the paper&apos;s means: 4.0 mm, 0.32 rad at the trial grasp; 1.9 mm, 0.11 rad",
        "trial grasp",
        "regrasp 1",
    ] {
        assert!(drawn.contains(label), "no {label:?}");
    }
    // Every trial's point at the trial grasp, twice (|n| and |α|), per
    // policy.
    for policy in 0..2 {
        assert!(filled_circles(&drawn, colour::POLICIES[policy]) >= 6);
    }
    plot(&["plot", "campaign", text(&out)]);
    check_png(&out.join("campaign.png"));
}

#[test]
fn bad_input_is_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let recording = recorded_run(dir.path());
    let missing = dir.path().join("missing.mcap");
    let map = dir.path().join("map.txt");
    std::fs::write(&map, "1 2 3").unwrap();
    let not_a_campaign = dir.path().join("empty");
    std::fs::create_dir(&not_a_campaign).unwrap();
    let cases: Vec<(Vec<&str>, &Path)> = vec![
        (vec!["tactile", text(&missing)], &missing),
        (vec!["regrasp", text(&missing)], &missing),
        (
            vec!["tactile", text(&recording), "--grasp", "7"],
            &recording,
        ),
        (vec!["tactile", text(&map)], &map),
        (vec!["tactile", text(&map), "--grasp", "1"], &map),
        (vec!["campaign", text(&not_a_campaign)], &not_a_campaign),
        (vec!["campaign", text(&missing)], &missing),
        (vec!["campaign", text(&recording)], &recording),
    ];
    for (args, named) in cases {
        let out = common::cablecell(&[&["plot"][..], &args].concat());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
        assert!(stderr.contains(text(named)), "{args:?}: {stderr}");
    }
    // What was asked for is not there: grasp 7.
    let out = common::cablecell(&["plot", "tactile", text(&recording), "--grasp", "7"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("no tactile map of grasp 7 (recorded: 0, 1)"),
        "{stderr}"
    );
}
