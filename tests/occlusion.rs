//! The simulated camera's occlusion (`[camera.backend.sim.occlusion]`): a
//! board over a stretch of the cable hides its share of it and no more,
//! where the seed puts it whatever the share; the arm's hand hides the
//! cable only as it comes down over it; the vision detector finds what is
//! left in view and nothing when all is hidden; a table that hides nothing
//! leaves every image as it was; a bad share, in a cell file or a
//! campaign's policy, is refused at its line.

mod common;

use std::path::PathBuf;

use cablecell::cell::{CellDevices, CellFile, load_cell};
use cablecell::hw::camera::config::{CameraBackend, SimCameraConfig};
use cablecell::perception::vision::paths::polyline_length;
use cablecell::sim::render::{Appearance, RenderedScene, render_world};
use cablecell::sim::world::SimWorld;
use cablecell::sim::{Stream, rng};
use common::{cablecell, sim_cell_copy};
use nalgebra::Point3;
use opencv::core::{self, Mat};
use opencv::prelude::*;

/// The shipped simulated cell with `occlusion` (the table's keys) added
/// under its camera, written into a temporary folder.
fn cell_with(occlusion: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = sim_cell_copy(dir.path(), |text| {
        let end = text.find("blur_sigma_px = 0.5").expect("the camera's blur");
        let end = end + text[end..].find('\n').expect("line end") + 1;
        format!(
            "{}\n[camera.backend.sim.occlusion]\n{occlusion}\n{}",
            &text[..end],
            &text[end..]
        )
    });
    (dir, path)
}

fn loaded(occlusion: &str) -> CellFile {
    let (_dir, path) = cell_with(occlusion);
    load_cell(&path).expect("the occluded cell loads")
}

fn sim_camera(file: &CellFile) -> &SimCameraConfig {
    match &file.camera.backend {
        CameraBackend::Sim(sim) => sim,
        CameraBackend::Opencv(_) => panic!("the shipped cell's camera is simulated"),
    }
}

/// The world of a freshly built cell: the hand parked above the cable.
fn world(file: &CellFile) -> SimWorld {
    SimWorld::new(&file.world, file.tactile.tcp_from_sensor.isometry())
}

/// What the cell's simulated camera shows first with `seed`, with the
/// truth: its appearance and its image drawn from the camera's stream as
/// the cell draws them.
fn first_view(file: &CellFile, world: &SimWorld, seed: u64) -> (Appearance, RenderedScene) {
    let sim = sim_camera(file);
    let mut stream = rng(seed, Stream::Camera);
    let appearance = sim.appearance(&mut stream);
    let scene = render_world(
        world,
        &file.camera.intrinsics,
        &sim.base_from_camera.isometry(),
        Some(&file.camera.marker.on_finger()),
        &appearance,
        &mut stream,
    )
    .expect("render");
    (appearance, scene)
}

fn count(mask: &Mat) -> f64 {
    f64::from(core::count_non_zero(mask).expect("count"))
}

fn visible_length(scene: &RenderedScene) -> f64 {
    scene.visible_centerlines_px[0]
        .iter()
        .map(|stretch| polyline_length(stretch))
        .sum()
}

/// The distance from `point` to the nearest visible point of the cable.
fn to_visible_px(scene: &RenderedScene, point: [f64; 2]) -> f64 {
    scene.visible_centerlines_px[0]
        .iter()
        .flatten()
        .map(|p| (p[0] - point[0]).hypot(p[1] - point[1]))
        .fold(f64::INFINITY, f64::min)
}

fn bytes(image: &Mat) -> Vec<u8> {
    image.data_bytes().expect("continuous image").to_vec()
}

#[test]
fn a_board_hides_its_share_of_the_cable_and_no_more() {
    let file = loaded("hidden_fraction = 0.3");
    let world = world(&file);
    let mut positions = Vec::new();
    for seed in 0..6 {
        let (appearance, scene) = first_view(&file, &world, seed);
        let board = appearance.occlusion.board.expect("a board");
        positions.push(board.position);
        let mask_share = count(&scene.visible_masks[0]) / count(&scene.masks[0]);
        let length_share = visible_length(&scene) / polyline_length(&scene.centerlines_px[0]);
        eprintln!(
            "seed {seed}: board at {:.3}, {:.3} of the mask and {:.3} of the centre line visible",
            board.position, mask_share, length_share
        );
        assert!((mask_share - 0.7).abs() < 0.02, "seed {seed}: {mask_share}");
        assert!(
            (length_share - 0.7).abs() < 0.01,
            "seed {seed}: {length_share}"
        );
    }
    // The seed moves the board along the cable.
    let spread = positions.iter().fold(0.0_f64, |m, p| m.max(*p))
        - positions.iter().fold(1.0_f64, |m, p| m.min(*p));
    assert!(spread > 0.3, "{positions:?}");

    let file = loaded("hidden_fraction = 1.0");
    let (_, scene) = first_view(&file, &world, 0);
    assert!(count(&scene.masks[0]) > 1000.0);
    assert_eq!(count(&scene.visible_masks[0]), 0.0);
    assert!(scene.visible_centerlines_px[0].is_empty());

    let file = loaded("hidden_fraction = 0.0");
    let (appearance, scene) = first_view(&file, &world, 0);
    assert!(appearance.occlusion.board.is_none());
    assert_eq!(count(&scene.visible_masks[0]), count(&scene.masks[0]));
}

#[test]
fn a_fixed_position_puts_the_hidden_stretch_there() {
    // At 1 the stretch runs to the cable's end in the image: its right.
    let file = loaded("hidden_fraction = 0.3\nposition = 1.0");
    let (_, scene) = first_view(&file, &world(&file), 3);
    let line = &scene.centerlines_px[0];
    let visible = &scene.visible_centerlines_px[0];
    assert_eq!(visible.len(), 1);
    assert_eq!(visible[0][0], line[0]);
    let cut = polyline_length(&visible[0]) / polyline_length(line);
    assert!((cut - 0.7).abs() < 0.01, "{cut}");
}

#[test]
fn the_same_seed_hides_the_same_stretch_whatever_the_share() {
    let light = loaded("hidden_fraction = 0.2");
    let heavy = loaded("hidden_fraction = 0.6");
    for seed in 0..5 {
        let at = |file: &CellFile| {
            let appearance = sim_camera(file).appearance(&mut rng(seed, Stream::Camera));
            appearance.occlusion.board.expect("a board").position
        };
        assert_eq!(at(&light), at(&heavy), "seed {seed}");
    }
}

#[test]
fn a_table_that_hides_nothing_leaves_every_image_as_it_was() {
    let plain = load_cell(&common::root().join("config/cell.sim.toml")).expect("cell");
    let empty = loaded("hidden_fraction = 0.0\narm_in_view = false\nbgr = [10, 200, 30]");
    for seed in [1, 4] {
        let mut a = CellDevices::build(&plain, seed).expect("the shipped cell builds");
        let mut b = CellDevices::build(&empty, seed).expect("the occluded cell builds");
        for capture in 0..2 {
            let (image_a, image_b) = (
                a.camera.capture().expect("capture"),
                b.camera.capture().expect("capture"),
            );
            assert!(
                bytes(&image_a) == bytes(&image_b),
                "seed {seed}, capture {capture}"
            );
        }
    }
}

#[test]
fn the_hand_hides_the_cable_only_as_it_comes_down_over_it() {
    let file = loaded("arm_in_view = true");
    let mut world = world(&file);
    // Parked 150 mm above the cable: the cable is all in view.
    let (_, parked) = first_view(&file, &world, 2);
    assert_eq!(count(&parked.visible_masks[0]), count(&parked.masks[0]));
    // Around the cable, the jaws open: the fingers and the marker on
    // one of them hide the middle of the cable, and only that.
    world.base_from_tcp = world.base_from_cable * file.tactile.tcp_from_sensor.isometry().inverse();
    world.opening_mm = 20.0;
    let (_, grasping) = first_view(&file, &world, 2);
    let share = count(&grasping.visible_masks[0]) / count(&grasping.masks[0]);
    eprintln!("the hand at the cable leaves {share:.3} of it visible");
    assert!((0.6..0.9).contains(&share), "{share}");
    let sim = sim_camera(&file);
    let middle =
        (sim.base_from_camera.isometry().inverse() * world.base_from_cable) * Point3::origin();
    let middle_px = file.camera.intrinsics.project(&middle).expect("in view");
    assert!(to_visible_px(&grasping, middle_px) > 20.0);
    // The hand is drawn: the image differs from the parked one around it.
    let differs = |a: &Mat, b: &Mat| {
        let mut diff = Mat::default();
        core::absdiff(a, b, &mut diff).expect("diff");
        let gray = diff.reshape(1, 0).expect("channels");
        core::count_non_zero(&gray).expect("count")
    };
    assert!(differs(&parked.bgr, &grasping.bgr) > 2000);
}

#[test]
fn the_vision_detector_finds_the_visible_part_and_nothing_when_all_is_hidden() {
    let file = loaded("hidden_fraction = 0.3");
    let sim = sim_camera(&file);
    let camera_from_base = sim.base_from_camera.isometry().inverse();
    for seed in 0..4 {
        let mut cell = CellDevices::build(&file, seed).expect("the occluded cell builds");
        let found = cell.detector.detect(cell.camera.as_mut()).expect("detect");
        // The image the detector saw is the one the truth is for.
        let (appearance, truth) = first_view(&file, &world(&file), seed);
        let image = found.image.expect("the vision detector keeps its image");
        assert!(bytes(&image.0) == bytes(&truth.bgr), "seed {seed}");
        let position = appearance.occlusion.board.expect("a board").position;
        assert!(!found.cables.is_empty(), "seed {seed}: board at {position}");
        for (i, cable) in found.cables.iter().enumerate() {
            let grasp = camera_from_base * cable.base_from_cable * Point3::origin();
            let grasp_px = file.camera.intrinsics.project(&grasp).expect("in view");
            let off_px = to_visible_px(&truth, grasp_px);
            eprintln!(
                "seed {seed}: board at {position:.3}, cable {i} grasped {off_px:.2} px from the visible cable"
            );
            assert!(off_px < 2.0, "seed {seed}, cable {i}: {off_px} px");
        }
    }

    let file = loaded("hidden_fraction = 1.0");
    for seed in 0..2 {
        let mut cell = CellDevices::build(&file, seed).expect("the occluded cell builds");
        let found = cell.detector.detect(cell.camera.as_mut()).expect("detect");
        assert!(found.cables.is_empty(), "seed {seed}: {:?}", found.cables);
    }
}

#[test]
fn a_bad_share_is_refused_at_its_line() {
    for (bad, message) in [
        (
            "hidden_fraction = 1.5",
            "expected a fraction in [0, 1], found 1.5",
        ),
        (
            "position = -0.1",
            "expected a fraction in [0, 1], found -0.1",
        ),
        ("hidden_share = 0.3", "unknown field `hidden_share`"),
    ] {
        let (_dir, path) = cell_with(bad);
        let out = cablecell(&["check", path.to_str().expect("utf-8")]);
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        let text = std::fs::read_to_string(&path).expect("read");
        let line = text.lines().position(|l| l == bad).expect("the key") + 1;
        assert!(
            err.contains(&format!("cell.toml:{line}:"))
                && err.contains("camera.backend.sim.occlusion")
                && err.contains(message),
            "{err}"
        );
    }
}

#[test]
fn a_campaign_policy_s_bad_share_is_refused_at_its_line() {
    let text = std::fs::read_to_string(common::root().join("tasks/paper-regrasp-campaign.toml"))
        .expect("the shipped campaign");
    let absolute = |relative: &str| format!("{:?}", common::root().join(relative));
    let text = text
        .replace("\"regrasp.toml\"", &absolute("tasks/regrasp.toml"))
        .replace(
            "\"../config/cell.sim.toml\"",
            &absolute("config/cell.sim.toml"),
        );
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("campaign.toml");
    let check = |share: &str| {
        let edited = text.replacen(
            "max_regrasps = 1",
            &format!("max_regrasps = 1\nocclusion_fraction = {share}"),
            1,
        );
        std::fs::write(&path, edited).expect("write");
        cablecell(&["check", path.to_str().expect("utf-8")])
    };
    assert_eq!(check("0.3").status.code(), Some(0));
    let out = check("1.2");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    let line = std::fs::read_to_string(&path)
        .expect("read")
        .lines()
        .position(|l| l.starts_with("occlusion_fraction"))
        .expect("the key")
        + 1;
    assert!(
        err.contains(&format!(
            "campaign.toml:{line}:22: policy[0].occlusion_fraction: expected a fraction in [0, 1], found 1.2"
        )),
        "{err}"
    );
}
