//! The synthetic camera end to end: its ground truth agrees with its
//! images, a seed fixes them, crossings overlap, data sets come out in the
//! cables-dev layout, and the camera calibrated from the rendered finger
//! marker lands where the camera was put.

use std::path::Path;

use cablecell::perception::vision::calibration::{
    CalibrationError, CameraModel, MarkerOnFinger, MarkerView, calibrate, calibrate_views,
};
use cablecell::perception::vision::paths::polyline_length;
use cablecell::sim::render::{
    Appearance, Background, BackgroundChoice, CableSpec, Cables, Light, RenderedScene,
    SceneOptions, SceneSpec, random_scene, render, render_world, write_dataset,
};
use cablecell::sim::world::SimWorld;
use cablecell::sim::world::WorldConfig;
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use opencv::aruco::PREDEFINED_DICTIONARY_NAME;
use opencv::core::{self, Mat, Vec3b};
use opencv::imgcodecs;
use opencv::imgproc;
use opencv::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn at(mask: &Mat, x: f64, y: f64) -> u8 {
    *mask
        .at_2d::<u8>(y.round() as i32, x.round() as i32)
        .expect("inside the mask")
}

fn count(mask: &Mat) -> f64 {
    f64::from(core::count_non_zero(mask).expect("count"))
}

fn pixel(image: &Mat, x: i32, y: i32) -> [f64; 3] {
    let p = image.at_2d::<Vec3b>(y, x).expect("inside the image");
    [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]
}

fn distance(a: [f64; 3], b: [u8; 3]) -> f64 {
    (0..3)
        .map(|i| (a[i] - f64::from(b[i])).powi(2))
        .sum::<f64>()
        .sqrt()
}

fn plain(width_px: i32, height_px: i32, cables: Vec<CableSpec>) -> SceneSpec {
    SceneSpec {
        width_px,
        height_px,
        background: Background::Plain {
            bgr: [200, 200, 200],
        },
        cables,
        light: Light::default(),
        noise_sigma: 0.0,
        blur_sigma_px: 0.0,
        occluders: Vec::new(),
        marker: None,
    }
}

fn straight(from: [f64; 2], to: [f64; 2], diameter_px: f64, bgr: [u8; 3]) -> CableSpec {
    let steps = 200;
    CableSpec {
        centerline_px: (0..=steps)
            .map(|i| {
                let t = f64::from(i) / f64::from(steps);
                [
                    from[0] + t * (to[0] - from[0]),
                    from[1] + t * (to[1] - from[1]),
                ]
            })
            .collect(),
        diameter_px,
        bgr,
        gloss: 0.3,
        metal_end_px: 0.0,
    }
}

#[test]
fn a_cables_metal_ends_are_silver_and_in_its_mask() {
    let mut cable = straight([100.5, 60.5], [300.5, 60.5], 12.0, [40, 40, 200]);
    cable.metal_end_px = 20.0;
    let out = render(&plain(400, 120, vec![cable]), &mut rng(1)).unwrap();
    for x in [105, 295] {
        assert_eq!(at(&out.masks[0], f64::from(x), 60.0), 255);
        let p = pixel(&out.bgr, x, 60);
        // Grey, not the red insulation: its channels alike.
        assert!((p[0] - p[2]).abs() < 25.0 && p[1] > 100.0, "{p:?} at x {x}");
    }
    let p = pixel(&out.bgr, 200, 60);
    assert!(p[2] > p[0] + 60.0, "{p:?}: the insulation in the middle");
}

#[test]
fn busy_scenes_are_drip_paintings_mosaics_or_print_with_metal_ended_cables() {
    let options = SceneOptions {
        backgrounds: BackgroundChoice::Busy,
        min_diameter_px: 8.0,
        max_diameter_px: 16.0,
        ..SceneOptions::default()
    };
    let scenes: Vec<SceneSpec> = (0..40)
        .map(|seed| random_scene(&mut rng(seed), &options))
        .collect();
    for kind in [Background::Pollock, Background::Mosaic, Background::Printed] {
        assert!(scenes.iter().any(|s| s.background == kind), "{kind:?}");
    }
    let cables: Vec<&CableSpec> = scenes.iter().flat_map(|s| &s.cables).collect();
    let metal = cables.iter().filter(|c| c.metal_end_px > 0.0).count();
    assert!(
        metal > 0 && metal < cables.len(),
        "{metal} of {}",
        cables.len()
    );
    assert!(cables.iter().all(|c| (8.0..=16.0).contains(&c.diameter_px)));
    // Each renders, its busy background far from one colour.
    for scene in scenes.iter().take(6) {
        let out = render(scene, &mut rng(2)).unwrap();
        let mut mean = Mat::default();
        let mut sigma = Mat::default();
        core::mean_std_dev(&out.bgr, &mut mean, &mut sigma, &core::no_array()).unwrap();
        let spread = *sigma.at::<f64>(0).unwrap();
        assert!(spread > 20.0, "{:?}: σ {spread}", scene.background);
    }
    // Other choices draw no metal, and their scenes are as before.
    let any = random_scene(&mut rng(3), &SceneOptions::default());
    assert!(any.cables.iter().all(|c| c.metal_end_px == 0.0));
}

#[test]
fn workbench_scenes_are_wood_with_a_board_over_a_cable_in_about_half() {
    let options = SceneOptions {
        backgrounds: BackgroundChoice::Workbench,
        min_cables: 1,
        max_cables: 2,
        min_diameter_px: 3.0,
        max_diameter_px: 8.0,
        ..SceneOptions::default()
    };
    let scenes: Vec<SceneSpec> = (0..40)
        .map(|seed| random_scene(&mut rng(seed), &options))
        .collect();
    assert!(scenes.iter().all(|s| s.background == Background::Wood));
    let boarded: Vec<&SceneSpec> = scenes.iter().filter(|s| !s.occluders.is_empty()).collect();
    assert!((10..=30).contains(&boarded.len()), "{}", boarded.len());
    // The board hides a stretch of a cable, not all of it: its visible
    // mask is smaller than its tube and not empty (another cable may pass
    // under the board too).
    for scene in boarded.iter().take(4) {
        let out = render(scene, &mut rng(2)).unwrap();
        let shares: Vec<f64> = out
            .masks
            .iter()
            .zip(&out.visible_masks)
            .map(|(whole, seen)| count(seen) / count(whole))
            .collect();
        assert!(
            shares.iter().any(|&s| (0.2..0.99).contains(&s)),
            "{shares:?}"
        );
    }
    // Other choices put nothing in front of their cables.
    let any = random_scene(&mut rng(3), &SceneOptions::default());
    assert!(any.occluders.is_empty());
}

#[test]
fn a_straight_cables_mask_is_its_tube() {
    let cable = straight([100.5, 60.5], [300.5, 60.5], 10.0, [30, 30, 30]);
    let out = render(&plain(400, 120, vec![cable]), &mut rng(1)).unwrap();
    // 200 px long, 10 px wide, with half-disc caps.
    let expected = 200.0 * 10.0 + std::f64::consts::PI * 25.0;
    let area = count(&out.masks[0]);
    assert!(
        (area - expected).abs() < 0.02 * expected,
        "{area} vs {expected}"
    );
    assert_eq!(count(&out.union_mask), area);
    // Dark on the axis, background well off it.
    assert!(distance(pixel(&out.bgr, 200, 60), [30, 30, 30]) < 60.0);
    assert_eq!(pixel(&out.bgr, 200, 20), [200.0; 3]);
}

#[test]
fn masks_and_centerlines_agree_in_random_scenes() {
    let options = SceneOptions::default();
    for seed in 0..6 {
        let scene = random_scene(&mut rng(seed), &options);
        let out = render(&scene, &mut rng(seed + 100)).unwrap();
        assert_eq!(out.masks.len(), scene.cables.len());
        assert_eq!(out.centerlines_px.len(), scene.cables.len());
        assert!(!scene.cables.is_empty(), "seed {seed}");
        for (k, (cable, line)) in scene.cables.iter().zip(&out.centerlines_px).enumerate() {
            assert!(line.len() >= 2, "seed {seed} cable {k}");
            for &[x, y] in line {
                assert!((0.0..=639.0).contains(&x) && (0.0..=479.0).contains(&y));
                assert_eq!(
                    at(&out.masks[k], x, y),
                    255,
                    "seed {seed} cable {k} ({x}, {y})"
                );
            }
            // Length × diameter, give or take the ends (caps, or cuts at
            // the border at a slant).
            let nominal = polyline_length(line) * cable.diameter_px;
            let area = count(&out.masks[k]);
            assert!(
                (area - nominal).abs() < 0.15 * nominal + 2.0 * cable.diameter_px.powi(2),
                "seed {seed} cable {k}: area {area} vs {nominal}"
            );
        }
    }
}

#[test]
fn a_seed_fixes_the_image() {
    let options = SceneOptions::default();
    let draw = |seed| {
        let mut rng = rng(seed);
        let scene = random_scene(&mut rng, &options);
        render(&scene, &mut rng).unwrap()
    };
    let (a, b, c) = (draw(7), draw(7), draw(8));
    let bytes = |out: &RenderedScene| out.bgr.data_bytes().unwrap().to_vec();
    assert_eq!(bytes(&a), bytes(&b));
    assert_eq!(a.centerlines_px, b.centerlines_px);
    assert_ne!(bytes(&a), bytes(&c));
}

#[test]
fn at_a_crossing_masks_overlap_and_the_later_cable_is_on_top() {
    let under = straight([50.5, 100.5], [350.5, 100.5], 12.0, [40, 40, 200]);
    let over = straight([200.5, 10.5], [200.5, 190.5], 12.0, [170, 80, 30]);
    let out = render(&plain(400, 200, vec![under, over]), &mut rng(2)).unwrap();
    let mut both = Mat::default();
    core::bitwise_and(&out.masks[0], &out.masks[1], &mut both, &core::no_array()).unwrap();
    // The overlap is the square where the tubes cross.
    assert!((count(&both) - 144.0).abs() < 30.0, "{}", count(&both));
    assert!(count(&out.union_mask) < count(&out.masks[0]) + count(&out.masks[1]));
    let crossing = pixel(&out.bgr, 200, 100);
    assert!(distance(crossing, [170, 80, 30]) < distance(crossing, [40, 40, 200]));
}

#[test]
fn without_crossings_masks_never_overlap() {
    let options = SceneOptions {
        min_cables: 3,
        max_cables: 3,
        crossings: false,
        ..SceneOptions::default()
    };
    for seed in 0..4 {
        let scene = random_scene(&mut rng(seed), &options);
        let out = render(&scene, &mut rng(seed)).unwrap();
        assert!(!out.masks.is_empty());
        let total: f64 = out.masks.iter().map(count).sum();
        assert_eq!(count(&out.union_mask), total, "seed {seed}");
    }
}

#[test]
fn dark_scenes_are_tubes_that_stand_out_from_a_plain_dark_background() {
    let options = SceneOptions {
        backgrounds: BackgroundChoice::Dark,
        ..SceneOptions::default()
    };
    for seed in 0..20 {
        let scene = random_scene(&mut rng(seed), &options);
        let Background::Plain { bgr: cloth } = scene.background else {
            panic!("seed {seed}: {:?}", scene.background);
        };
        // Darker than any plain background of the other choices (80 and up).
        assert!(cloth.iter().all(|&c| c < 70), "seed {seed}: {cloth:?}");
        for cable in &scene.cables {
            let contrast = distance(cable.bgr.map(f64::from), cloth);
            assert!(
                contrast >= 70.0,
                "seed {seed}: {:?} on {cloth:?}",
                cable.bgr
            );
            assert_eq!(cable.metal_end_px, 0.0);
        }
        assert!(scene.occluders.is_empty());
    }
}

#[test]
fn every_background_kind_renders() {
    let kinds = [
        Background::Plain { bgr: [90, 160, 30] },
        Background::Gradient,
        Background::Noise,
        Background::Stripes,
        Background::Checker,
        Background::Wood,
        Background::Printed,
        Background::Sheets,
    ];
    for kind in kinds {
        let mut scene = plain(
            320,
            240,
            vec![straight([20.0, 30.0], [300.0, 200.0], 8.0, [30, 30, 30])],
        );
        scene.background = kind.clone();
        let out = render(&scene, &mut rng(3)).unwrap();
        assert_eq!((out.bgr.cols(), out.bgr.rows()), (320, 240));
        assert_eq!(out.bgr.typ(), core::CV_8UC3);
        // Away from the cable: flat for a plain background, varied for
        // the others.
        let mut off_cable = Mat::default();
        core::bitwise_not(&out.union_mask, &mut off_cable, &core::no_array()).unwrap();
        let mut mean = core::Scalar::default();
        let mut deviation = core::Scalar::default();
        core::mean_std_dev(&out.bgr, &mut mean, &mut deviation, &off_cable).unwrap();
        let spread = deviation[0].max(deviation[1]).max(deviation[2]);
        match kind {
            Background::Plain { bgr } => {
                assert!(spread < 3.0, "{kind:?}: {spread}");
                assert!(distance([mean[0], mean[1], mean[2]], bgr) < 3.0, "{kind:?}");
            }
            _ => assert!(spread > 3.0, "{kind:?}: {spread}"),
        }
    }
}

#[test]
fn light_noise_and_blur_change_the_image_not_the_truth() {
    let cable = straight([40.5, 60.5], [280.5, 60.5], 8.0, [30, 30, 200]);
    let sharp = render(&plain(320, 120, vec![cable.clone()]), &mut rng(4)).unwrap();
    let mut scene = plain(320, 120, vec![cable]);
    scene.light.gain = 0.6;
    scene.light.gradient = 0.3;
    scene.noise_sigma = 5.0;
    scene.blur_sigma_px = 1.0;
    let dim = render(&scene, &mut rng(4)).unwrap();
    let mut difference = Mat::default();
    core::bitwise_xor(
        &sharp.masks[0],
        &dim.masks[0],
        &mut difference,
        &core::no_array(),
    )
    .unwrap();
    assert_eq!(count(&difference), 0.0);
    assert!(pixel(&dim.bgr, 160, 10)[1] < 160.0, "dimmed");
}

/// Reads a data set's `STEM.txt`: one polyline a line, `N x0 y0 ...`.
fn polylines(path: &Path) -> Vec<Vec<[f64; 2]>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|line| {
            let numbers: Vec<f64> = line
                .split_whitespace()
                .map(|w| w.parse().expect("a number"))
                .collect();
            let (&n, coords) = numbers.split_first().expect("a count");
            assert_eq!(coords.len(), 2 * n as usize, "{line}");
            assert!(coords.iter().all(|c| c.fract() == 0.0), "integer pixels");
            coords.chunks(2).map(|c| [c[0], c[1]]).collect()
        })
        .collect()
}

#[test]
fn a_data_set_has_the_cables_dev_layout() {
    let dir = tempfile::tempdir().unwrap();
    let options = SceneOptions {
        width_px: 320,
        height_px: 240,
        min_diameter_px: 4.0,
        max_diameter_px: 9.0,
        ..SceneOptions::default()
    };
    let mut ticks = 0;
    write_dataset(dir.path(), 3, 11, &options, Cables::Rendered, || ticks += 1).unwrap();
    assert_eq!(ticks, 3);
    let mut expected = Vec::new();
    for i in 0..3 {
        let stem = format!("{i:05}");
        let lines = polylines(&dir.path().join(format!("{stem}.txt")));
        assert!(!lines.is_empty());
        let image = imgcodecs::imread(
            dir.path().join(format!("{stem}.jpg")).to_str().unwrap(),
            imgcodecs::IMREAD_COLOR,
        )
        .unwrap();
        assert_eq!((image.cols(), image.rows()), (320, 240));
        expected.push(format!("{stem}.jpg"));
        expected.push(format!("{stem}.txt"));
        expected.push(format!("{stem}_mask_all.png"));
        let all = read_mask(&dir.path().join(format!("{stem}_mask_all.png")));
        for (k, line) in lines.iter().enumerate() {
            let name = format!("{stem}_mask_{k}.png");
            let mask = read_mask(&dir.path().join(&name));
            expected.push(name);
            for &[x, y] in line {
                assert_eq!(at(&mask, x, y), 255, "{stem} cable {k} ({x}, {y})");
                assert_eq!(at(&all, x, y), 255);
            }
        }
    }
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    expected.sort();
    assert_eq!(names, expected);

    // Image i does not depend on how many are written.
    let again = tempfile::tempdir().unwrap();
    write_dataset(again.path(), 2, 11, &options, Cables::Rendered, || {}).unwrap();
    for name in ["00001.txt", "00001_mask_all.png"] {
        assert_eq!(
            std::fs::read(dir.path().join(name)).unwrap(),
            std::fs::read(again.path().join(name)).unwrap()
        );
    }
}

/// A 0/255 single-channel PNG.
fn read_mask(path: &Path) -> Mat {
    let mask = imgcodecs::imread(path.to_str().unwrap(), imgcodecs::IMREAD_UNCHANGED).unwrap();
    assert_eq!(mask.typ(), core::CV_8UC1, "{}", path.display());
    let mut binary = Mat::default();
    imgproc::threshold(&mask, &mut binary, 0.0, 255.0, imgproc::THRESH_BINARY).unwrap();
    let mut changed = Mat::default();
    core::compare(&mask, &binary, &mut changed, core::CMP_NE).unwrap();
    assert_eq!(
        count(&changed),
        0.0,
        "{} holds only 0 and 255",
        path.display()
    );
    mask
}

// The simulated world seen by the simulated camera.

fn world() -> SimWorld {
    let config = WorldConfig {
        cable_diameter_mm: 2.5,
        cable_center_mm: [450.0, 0.0, 250.0],
        cable_yaw_rad: 0.0,
        cable_tilt_rad: 0.05,
        capture_half_height_mm: 12.0,
        support_span_mm: 150.0,
        cable_weight_n_mm: 1e-4,
        bending_stiffness_n_mm2: 60.0,
        jaw_drag_stiffness_n_mm: 1e-3,
        hold_stiffness_n_mm: 2e-4,
        settle_fraction: 0.55,
        spring_back_fraction: 0.9,
    };
    let tcp_from_sensor = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, -10.0),
        UnitQuaternion::from_euler_angles(-std::f64::consts::FRAC_PI_2, 0.0, 0.0),
    );
    let mut world = SimWorld::new(&config, tcp_from_sensor);
    world.base_from_tcp = hand_over_cable(0.0, 0.0, [0.0; 3]);
    world
}

/// The hand 80 mm above the cable's midpoint pointing down, turned by
/// `yaw_rad` about the vertical, tilted by `tilt_rad` about base x, and
/// moved by `shift_mm`.
fn hand_over_cable(yaw_rad: f64, tilt_rad: f64, shift_mm: [f64; 3]) -> Isometry3<f64> {
    let down = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
    Isometry3::from_parts(
        Translation3::new(450.0 + shift_mm[0], shift_mm[1], 330.0 + shift_mm[2]),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw_rad)
            * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), tilt_rad)
            * down,
    )
}

/// The camera 400 mm in front of the cable (along base −y), 50 mm above
/// it, looking along base +y, image x along base x.
fn base_from_camera() -> Isometry3<f64> {
    let rotation = Matrix3::from_columns(&[
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 0.0, -1.0),
        Vector3::new(0.0, 1.0, 0.0),
    ]);
    Isometry3::from_parts(
        Translation3::new(450.0, -400.0, 300.0),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rotation)),
    )
}

fn camera() -> CameraModel {
    CameraModel::centred(640, 480, 45f64.to_radians())
}

/// A 30 mm marker on the finger's outer face, facing the camera when the
/// hand is square over the cable: 15 mm towards the camera and 25 mm up
/// from the TCP.
fn marker() -> MarkerOnFinger {
    let facing_camera = Matrix3::from_columns(&[
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::new(0.0, -1.0, 0.0),
    ]);
    let base_from_marker = Isometry3::from_parts(
        Translation3::new(450.0, -15.0, 355.0),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(facing_camera)),
    );
    MarkerOnFinger {
        dictionary: PREDEFINED_DICTIONARY_NAME::DICT_4X4_50,
        id: 3,
        side_mm: 30.0,
        tcp_from_marker: hand_over_cable(0.0, 0.0, [0.0; 3]).inverse() * base_from_marker,
    }
}

#[test]
fn the_world_s_cable_appears_where_the_camera_sees_it() {
    let world = world();
    let camera = camera();
    let out = render_world(
        &world,
        &camera,
        &base_from_camera(),
        None,
        &Appearance::default(),
        &mut rng(5),
    )
    .unwrap();
    assert_eq!(out.masks.len(), 1);
    let line = &out.centerlines_px[0];
    // The cable's midpoint, 400 mm away and 50 mm below the optical axis.
    let mid = camera
        .project(&(base_from_camera().inverse() * nalgebra::Point3::new(450.0, 0.0, 250.0)))
        .unwrap();
    let nearest = line
        .iter()
        .map(|p| (p[0] - mid[0]).hypot(p[1] - mid[1]))
        .fold(f64::INFINITY, f64::min);
    assert!(nearest < 1.0, "{nearest}");
    assert!((mid[1] - (239.5 + camera.fy_px * 50.0 / 400.0)).abs() < 1e-9);
    // The tube is the cable's 2.5 mm at about 400 mm across.
    let width_px = count(&out.masks[0]) / polyline_length(line);
    let expected_px = camera.fx_px * 2.5 / 400.0;
    assert!(
        (width_px - expected_px).abs() < 0.15 * expected_px,
        "{width_px} vs {expected_px}"
    );
}

/// Rotation angle (degrees) and translation distance (mm) between two poses.
fn pose_error(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let angle = (a.rotation.inverse() * b.rotation).angle().to_degrees();
    (angle, (a.translation.vector - b.translation.vector).norm())
}

/// Arm poses that show the marker to the camera from different sides and
/// depths.
const POSES: [(f64, f64, [f64; 3]); 4] = [
    (0.0, 0.0, [0.0, 0.0, 0.0]),
    (0.3, 0.0, [-50.0, 40.0, -20.0]),
    (-0.4, 0.2, [50.0, -40.0, 10.0]),
    (0.2, -0.3, [20.0, 60.0, 30.0]),
];

/// Renders the marker with the arm at each of `POSES`.
fn views(appearance: &Appearance) -> Vec<(Mat, Isometry3<f64>)> {
    POSES
        .iter()
        .enumerate()
        .map(|(i, &(yaw_rad, tilt_rad, shift_mm))| {
            let mut world = world();
            world.base_from_tcp = hand_over_cable(yaw_rad, tilt_rad, shift_mm);
            let out = render_world(
                &world,
                &camera(),
                &base_from_camera(),
                Some(&marker()),
                appearance,
                &mut rng(i as u64),
            )
            .unwrap();
            (out.bgr, world.base_from_tcp)
        })
        .collect()
}

#[test]
fn the_camera_calibrated_from_one_view_is_where_it_was_put() {
    let appearance = Appearance {
        noise_sigma: 2.0,
        blur_sigma_px: 0.5,
        ..Appearance::default()
    };
    for (i, (bgr, base_from_tcp)) in views(&appearance).iter().enumerate() {
        let calibration = calibrate(bgr, &camera(), &marker(), base_from_tcp).unwrap();
        let (angle_deg, distance_mm) =
            pose_error(&calibration.base_from_camera, &base_from_camera());
        eprintln!(
            "one view, pose {i}: {angle_deg:.3}° {distance_mm:.2} mm, reprojection {:.3} px",
            calibration.reprojection_error_px
        );
        // A 30 mm marker 60 px wide: its tilt is the weak part (see
        // `calibrate`).
        assert!(
            angle_deg < 0.4 && distance_mm < 3.0,
            "pose {i}: {angle_deg}° {distance_mm} mm"
        );
        assert!(calibration.reprojection_error_px < 0.2);
    }
}

#[test]
fn the_camera_calibrated_from_several_views_is_within_a_millimetre() {
    let appearance = Appearance {
        noise_sigma: 2.0,
        blur_sigma_px: 0.5,
        ..Appearance::default()
    };
    let views = views(&appearance);
    let views: Vec<MarkerView<'_>> = views
        .iter()
        .map(|(bgr, base_from_tcp)| MarkerView {
            bgr,
            base_from_tcp: *base_from_tcp,
        })
        .collect();
    let calibration = calibrate_views(&views, &camera(), &marker()).unwrap();
    let (angle_deg, distance_mm) = pose_error(&calibration.base_from_camera, &base_from_camera());
    eprintln!(
        "four views: {angle_deg:.3}° {distance_mm:.3} mm, reprojection {:.3} px",
        calibration.reprojection_error_px
    );
    assert!(
        angle_deg < 0.05 && distance_mm < 0.5,
        "{angle_deg}° {distance_mm} mm"
    );
    assert!(calibration.reprojection_error_px < 0.2);
}

#[test]
fn a_blurred_noisy_view_still_calibrates_within_a_looser_bound() {
    let camera = camera();
    let marker = marker();
    let world = world();
    let appearance = Appearance {
        background: Background::Wood,
        noise_sigma: 6.0,
        blur_sigma_px: 1.2,
        light: Light {
            gain: 0.7,
            gradient: 0.3,
            ..Light::default()
        },
        ..Appearance::default()
    };
    let out = render_world(
        &world,
        &camera,
        &base_from_camera(),
        Some(&marker),
        &appearance,
        &mut rng(9),
    )
    .unwrap();
    let calibration = calibrate(&out.bgr, &camera, &marker, &world.base_from_tcp).unwrap();
    let (angle_deg, distance_mm) = pose_error(&calibration.base_from_camera, &base_from_camera());
    eprintln!(
        "blurred: {angle_deg:.3}° {distance_mm:.3} mm, reprojection {:.3} px",
        calibration.reprojection_error_px
    );
    assert!(
        angle_deg < 0.8 && distance_mm < 6.0,
        "{angle_deg}° {distance_mm} mm"
    );
}

#[test]
fn no_marker_in_view_is_no_marker() {
    let camera = camera();
    let marker = marker();
    let mut world = world();
    // Turned away from the camera: the marker's back shows nothing.
    world.base_from_tcp = hand_over_cable(std::f64::consts::PI, 0.0, [0.0; 3]);
    let out = render_world(
        &world,
        &camera,
        &base_from_camera(),
        Some(&marker),
        &Appearance::default(),
        &mut rng(1),
    )
    .unwrap();
    let err = calibrate(&out.bgr, &camera, &marker, &world.base_from_tcp).unwrap_err();
    assert!(
        matches!(err, CalibrationError::NoMarker { id: 3, .. }),
        "{err}"
    );

    // Another marker than the finger's is not the finger's.
    let other = MarkerOnFinger { id: 4, ..marker };
    let world = self::world();
    let out = render_world(
        &world,
        &camera,
        &base_from_camera(),
        Some(&other),
        &Appearance::default(),
        &mut rng(1),
    )
    .unwrap();
    match calibrate(&out.bgr, &camera, &marker, &world.base_from_tcp) {
        Err(CalibrationError::NoMarker {
            id: 3,
            view: 0,
            found,
        }) => assert_eq!(found, vec![4]),
        other => panic!("{other:?}"),
    }
}
