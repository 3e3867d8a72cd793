//! The vision pipeline's scenarios through its public API: cables drawn
//! along known curves by the renderer (`sim::render::fixtures`), and what
//! `Pipeline::detect` makes of them: crossings, loops, cables touching,
//! the border, straight edges, the region of interest and the working
//! width, the choice between the classical mask and the network.

mod common;

use cablecell::perception::vision::curves::{arc_px, segment_px};
use cablecell::perception::vision::eval::distance_to_polylines;
use cablecell::perception::vision::{
    BackgroundStats, InstanceMethod, MaskMethod, MaskNetwork, PAINTED_MIN_CONFIDENCE_FACTOR,
    Pipeline, VisionConfig, VisionError, VisionOutput, background, mask,
};
use cablecell::sim::render::{Background, CableSpec, RenderedScene};
use common::scenes::{demo_scene, draw_scene, matte_cable, midpoint_px};
use opencv::core::{self, CV_32F, Mat, Point, Rect, Scalar, Vector};
use opencv::imgproc;
use opencv::prelude::*;

/// A matte cable 8 px across.
fn cable(centerline_px: Vec<[f64; 2]>, bgr: [u8; 3]) -> CableSpec {
    matte_cable(centerline_px, 8.0, bgr)
}

/// `cables` on a plain light gray 640 × 480 table, without noise.
fn on_gray_table(cables: Vec<CableSpec>) -> RenderedScene {
    draw_scene(
        480,
        640,
        Background::Plain { bgr: [210; 3] },
        0.0,
        cables,
        0,
    )
    .unwrap()
}

/// The defaults, but straight detections kept: most cables here are
/// straight segments.
fn keep_straight() -> VisionConfig {
    VisionConfig {
        straight_edge_radius_px: 0.0,
        ..VisionConfig::default()
    }
}

fn detect(image: &Mat, config: VisionConfig) -> VisionOutput {
    Pipeline::new(config).detect(image, None).expect("detect")
}

/// Each drawn cable is followed by its own instance: the instance whose
/// samples lie nearest the curve, all within `tol_px` of it.
fn assert_each_followed(out: &VisionOutput, curves: &[Vec<[f64; 2]>], tol_px: f64) {
    if let Err(why) = each_followed(out, curves, tol_px) {
        panic!("{why}");
    }
}

/// Whether each drawn cable is followed by its own instance (see
/// [`assert_each_followed`]), or why not.
fn each_followed(out: &VisionOutput, curves: &[Vec<[f64; 2]>], tol_px: f64) -> Result<(), String> {
    let ends: Vec<([f64; 2], [f64; 2])> = out
        .cables
        .iter()
        .map(|c| (c.spline.point(0.0), c.spline.point(1.0)))
        .collect();
    if out.cables.len() != curves.len() {
        return Err(format!(
            "{} instances for {} curves, from-to: {ends:.0?}",
            out.cables.len(),
            curves.len()
        ));
    }
    let mut used = vec![false; out.cables.len()];
    for curve in curves {
        let own = [curve.clone()];
        let (best, worst) = out
            .cables
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let worst = c
                    .samples_px
                    .iter()
                    .map(|&p| distance_to_polylines(p, &own))
                    .fold(0.0, f64::max);
                (i, worst)
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("an instance");
        if worst >= tol_px {
            return Err(format!("curve followed only within {worst:.1} px"));
        }
        if used[best] {
            return Err("two curves matched one instance".into());
        }
        used[best] = true;
    }
    Ok(())
}

fn angle_diff_rad(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}

#[test]
fn one_cable_gives_its_midpoint_and_direction() {
    let curve = arc_px([320.0, 600.0], 400.0, -2.2, -0.9);
    let scene = draw_scene(
        480,
        640,
        Background::Plain { bgr: [220; 3] },
        0.0,
        vec![cable(curve.clone(), [30; 3])],
        1,
    )
    .unwrap();
    let out = detect(&scene.bgr, keep_straight());
    assert!(out.plain_background);
    assert_eq!(out.mask_used, MaskMethod::Classical);
    assert_each_followed(&out, std::slice::from_ref(&curve), 2.0);
    let c = &out.cables[0];
    let mid = midpoint_px(&curve).unwrap();
    let err = (c.grasp_px[0] - mid[0]).hypot(c.grasp_px[1] - mid[1]);
    assert!(err < 4.0, "grasp {:?} vs midpoint {mid:?}", c.grasp_px);
    // The arc's tangent at its middle (angle -1.55 rad on the circle),
    // going from the left end (s = 0) to the right.
    let expected = -1.55 + std::f64::consts::FRAC_PI_2;
    assert!(
        angle_diff_rad(c.direction_rad, expected) < 3f64.to_radians(),
        "direction {} vs {expected}",
        c.direction_rad
    );
    let names: Vec<&str> = out.timings_ms.iter().map(|t| t.0).collect();
    assert_eq!(
        names,
        ["prepare", "mask", "instances", "spline", "instance_masks"]
    );
}

#[test]
fn two_crossing_cables_are_followed_through_the_crossing() {
    let a = segment_px([60.0, 100.0], [580.0, 380.0]);
    let b = arc_px([330.0, 560.0], 380.0, -2.4, -0.7);
    let scene = draw_scene(
        480,
        640,
        Background::Plain { bgr: [200; 3] },
        0.0,
        vec![
            cable(a.clone(), [40, 40, 160]),
            cable(b.clone(), [30, 30, 30]),
        ],
        2,
    )
    .unwrap();
    let out = detect(&scene.bgr, keep_straight());
    assert_each_followed(&out, &[a, b], 3.0);
    for c in &out.cables {
        let own = c.mask.as_ref().unwrap();
        assert_eq!(own.size().unwrap(), scene.bgr.size().unwrap());
        assert!(core::count_non_zero(own).unwrap() > 1000);
    }
    // Without the masks, the same grasp frames.
    let bare = detect(
        &scene.bgr,
        VisionConfig {
            cable_masks: false,
            ..keep_straight()
        },
    );
    assert!(bare.union_mask.is_none());
    assert!(
        bare.timings_ms
            .iter()
            .all(|(stage, _)| *stage != "instance_masks")
    );
    assert_eq!(bare.cables.len(), out.cables.len());
    for (b, c) in bare.cables.iter().zip(&out.cables) {
        assert!(b.mask.is_none());
        assert_eq!((b.grasp_px, b.direction_rad), (c.grasp_px, c.direction_rad));
    }
}

#[test]
fn three_cables_with_three_crossings_on_a_noisy_table() {
    let scene = demo_scene(3).unwrap();
    let out = detect(&scene.bgr, keep_straight());
    assert!(out.plain_background, "{:?}", out.background);
    assert_each_followed(&out, &scene.centerlines_px, 3.0);
}

#[test]
fn shallow_crossing_is_resolved() {
    let a = segment_px([40.0, 200.0], [600.0, 260.0]);
    let b = segment_px([40.0, 290.0], [600.0, 170.0]);
    let scene = draw_scene(
        480,
        640,
        Background::Plain { bgr: [230; 3] },
        0.0,
        vec![cable(a.clone(), [20; 3]), cable(b.clone(), [90, 30, 30])],
        4,
    )
    .unwrap();
    let out = detect(&scene.bgr, keep_straight());
    assert_each_followed(&out, &[a, b], 3.0);
}

/// Points a pixel apart along a curve through `through_px` with heading
/// `heading_rad` there, turning by `turn_rad_per_px` per pixel,
/// `half_length_px` either way.
fn curve_through(
    through_px: [f64; 2],
    heading_rad: f64,
    turn_rad_per_px: f64,
    half_length_px: usize,
) -> Vec<[f64; 2]> {
    let walk = |sign: f64| {
        let (mut p, mut heading) = (through_px, heading_rad);
        let mut points = Vec::new();
        for _ in 0..half_length_px {
            p = [p[0] + sign * heading.cos(), p[1] + sign * heading.sin()];
            heading += sign * turn_rad_per_px;
            points.push(p);
        }
        points
    };
    let mut back = walk(-1.0);
    back.reverse();
    back.push(through_px);
    back.extend(walk(1.0));
    back
}

/// Two 10 px cables crossing at the image's centre: one heading
/// `steep_rad` there and bending at `steep_radius_px`, the other
/// `crossing_rad` from it and bending at `other_radius_px` (negative:
/// the other way). Whether each is followed through the crossing.
fn bending_crossing_followed(
    steep_rad: f64,
    steep_radius_px: f64,
    crossing_rad: f64,
    other_radius_px: f64,
) -> Result<(), String> {
    let centre = [320.0, 240.0];
    let steep = curve_through(centre, steep_rad, -1.0 / steep_radius_px, 140);
    let other = curve_through(
        centre,
        steep_rad + crossing_rad,
        -1.0 / other_radius_px,
        200,
    );
    let scene = draw_scene(
        480,
        640,
        Background::Plain { bgr: [220; 3] },
        0.0,
        vec![
            matte_cable(steep.clone(), 10.0, [20; 3]),
            matte_cable(other.clone(), 10.0, [150, 60, 40]),
        ],
        4,
    )
    .unwrap();
    let out = detect(&scene.bgr, VisionConfig::default());
    each_followed(&out, &[steep, other], 3.0).map_err(|why| {
        format!(
            "crossing {crossing_rad} rad, steep {steep_rad} rad at {steep_radius_px} px, other at {other_radius_px} px: {why}"
        )
    })
}

fn assert_bending_crossing_resolved(
    steep_rad: f64,
    steep_radius_px: f64,
    crossing_rad: f64,
    other_radius_px: f64,
) {
    if let Err(why) =
        bending_crossing_followed(steep_rad, steep_radius_px, crossing_rad, other_radius_px)
    {
        panic!("{why}");
    }
}

#[test]
fn cables_bending_through_a_shallow_crossing_keep_to_themselves() {
    // Both bend the same way through the crossing, as cables lying
    // loose do. At 29°, radii 150 and 250 px: the skeleton between the
    // crossing's two junctions runs between the cables, far from the
    // sharper one's direction beyond. At 29°, radii 110 and 250 px:
    // the sharper cable's branch points, a width out, more towards the
    // other cable's far branch than its own, unless followed back
    // along its curve.
    assert_bending_crossing_resolved(-0.9, 150.0, 0.5, 250.0);
    assert_bending_crossing_resolved(-1.0, 110.0, 0.5, 250.0);
    // Bending opposite ways at 29° and 20°: the crossing's junctions lie
    // apart along the cables, and the branches are compared only once
    // each is followed along its curve to the crossing's centre.
    assert_bending_crossing_resolved(-0.9, 90.0, 0.5, -180.0);
    assert_bending_crossing_resolved(-1.3, 110.0, 0.35, -250.0);
    // At 29°, radii 110 and 250 px bending opposite ways, the junctions
    // lie 8.6 widths apart, and the steep cable's path, bridged between
    // them, was two pieces when the limit was 8 widths.
    assert_bending_crossing_resolved(-0.9, 110.0, 0.5, -250.0);
}

#[test]
fn crossings_between_cables_bending_opposite_ways_are_mostly_resolved() {
    // 90 crossings, 20° to 63°, the steeper cable as below, the other
    // bending the other way at 180 or 250 px. 82 are resolved; by
    // bending alone, 81; before paths were bridged across crossings and
    // junctions up to 10 widths apart merged, 62. The others are
    // ambiguous to the eye too: the cables run over each other for
    // several widths, and the paths cross inside that stretch.
    let mut failures = Vec::new();
    for crossing_rad in [0.35, 0.5, 0.7, 0.9, 1.1] {
        for steep_rad in [-0.9, -1.1, -1.3] {
            for steep_radius_px in [90.0, 110.0, 150.0] {
                for other_radius_px in [-180.0, -250.0] {
                    if let Err(why) = bending_crossing_followed(
                        steep_rad,
                        steep_radius_px,
                        crossing_rad,
                        other_radius_px,
                    ) {
                        failures.push(why);
                    }
                }
            }
        }
    }
    assert!(failures.len() <= 8, "{:#?}", failures);
}

#[test]
fn every_crossing_of_forty_degrees_or_more_between_bending_cables_is_resolved() {
    // 54 crossings: 40°, 52° and 63°; the steeper cable at three
    // headings and bending at radii of 90 to 150 px, the other bending
    // the same way at 180 or 250 px. At 20° and 29°, 19 of 36 such
    // crossings are resolved: the sharper cable curls along the other
    // for several widths.
    for crossing_rad in [0.7, 0.9, 1.1] {
        for steep_rad in [-0.9, -1.1, -1.3] {
            for steep_radius_px in [90.0, 110.0, 150.0] {
                for other_radius_px in [180.0, 250.0] {
                    assert_bending_crossing_resolved(
                        steep_rad,
                        steep_radius_px,
                        crossing_rad,
                        other_radius_px,
                    );
                }
            }
        }
    }
}

/// A cable that loops across itself, centred in a 640 × 480 image: it
/// comes in straight heading `heading_rad`, turns left at `radius_px`
/// through a full turn less `crossing_rad`, and leaves straight, its
/// two straight stretches crossing at `crossing_rad`, `lead_px` before
/// and after the crossing.
fn lasso(heading_rad: f64, crossing_rad: f64, radius_px: f64, lead_px: f64) -> Vec<[f64; 2]> {
    let to_tangent_px = radius_px / (crossing_rad / 2.0).tan();
    let straight_px = (lead_px + to_tangent_px).round() as usize;
    let turn_rad = std::f64::consts::TAU - crossing_rad;
    let arc_px = (turn_rad * radius_px).round() as usize;
    let (mut p, mut heading) = ([0.0, 0.0], heading_rad);
    let mut points = vec![p];
    for i in 0..2 * straight_px + arc_px {
        if (straight_px..straight_px + arc_px).contains(&i) {
            heading -= turn_rad / arc_px as f64;
        }
        p = [p[0] + heading.cos(), p[1] + heading.sin()];
        points.push(p);
    }
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    for p in &points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let shift = [320.0 - (lo[0] + hi[0]) / 2.0, 240.0 - (lo[1] + hi[1]) / 2.0];
    points
        .iter()
        .map(|p| [p[0] + shift[0], p[1] + shift[1]])
        .collect()
}

#[test]
fn a_cable_looping_across_itself_is_one_cable() {
    // 10 px cables, each looping across itself once: the loop 4 to 8
    // widths in radius, its two strands crossing at 15° to 120°, in
    // four orientations; 55 such loops fit the image. Before a loop's
    // two ends were kept from being paired, 6 of them were found as the
    // loop and the rest of the cable, all where the strands cross at
    // 20° to 45° and thin into two junctions. (At 3 widths, 3 of 25 are
    // still not followed; before, 15.)
    let mut tried = 0;
    for crossing_deg in [15.0f64, 20.0, 30.0, 45.0, 60.0, 90.0, 120.0] {
        for radius_px in [40.0, 60.0, 80.0] {
            for heading_deg in [0.0f64, 30.0, -60.0, 160.0] {
                let crossing_rad = crossing_deg.to_radians();
                let curve = lasso(heading_deg.to_radians(), crossing_rad, radius_px, 120.0);
                let inside = curve
                    .iter()
                    .all(|p| (15.0..625.0).contains(&p[0]) && (15.0..465.0).contains(&p[1]));
                if !inside {
                    continue;
                }
                tried += 1;
                let scene = draw_scene(
                    480,
                    640,
                    Background::Plain { bgr: [220; 3] },
                    0.0,
                    vec![matte_cable(curve.clone(), 10.0, [30; 3])],
                    4,
                )
                .unwrap();
                let out = detect(&scene.bgr, keep_straight());
                if let Err(why) = each_followed(&out, std::slice::from_ref(&curve), 3.0) {
                    panic!("{crossing_deg}° at {radius_px} px, heading {heading_deg}°: {why}");
                }
            }
        }
    }
    assert_eq!(tried, 55);
}

#[test]
fn cables_touching_side_by_side_keep_to_their_own_colour() {
    // Two 10 px cables come together, touch side by side for 60 or
    // 100 px, and part the way they came. Their shape alone reads as a
    // shallow crossing: bending least pairs each with the other's far
    // branch. Their colours tell them apart. Along the stretch they
    // share, one skeleton runs between them, 5 px from each.
    let polyline = |corners: &[[f64; 2]]| {
        let mut points = segment_px(corners[0], corners[1]);
        for w in corners[1..].windows(2) {
            points.extend(segment_px(w[0], w[1]).into_iter().skip(1));
        }
        points
    };
    for (run_px, part_px) in [(60.0, 100.0), (100.0, 60.0), (100.0, 100.0)] {
        let (x0, x1) = (320.0 - run_px / 2.0, 320.0 + run_px / 2.0);
        let upper = polyline(&[
            [40.0, 235.0 - part_px],
            [x0, 235.0],
            [x1, 235.0],
            [600.0, 235.0 - part_px],
        ]);
        let lower = polyline(&[
            [40.0, 245.0 + part_px],
            [x0, 245.0],
            [x1, 245.0],
            [600.0, 245.0 + part_px],
        ]);
        for (upper_bgr, lower_bgr) in [([20; 3], [150, 60, 40]), ([30, 30, 200], [40, 200, 40])] {
            let scene = on_gray_table(vec![
                matte_cable(upper.clone(), 10.0, upper_bgr),
                matte_cable(lower.clone(), 10.0, lower_bgr),
            ]);
            let out = detect(&scene.bgr, keep_straight());
            if let Err(why) = each_followed(&out, &[upper.clone(), lower.clone()], 10.0) {
                panic!("touching for {run_px} px, {upper_bgr:?} over {lower_bgr:?}: {why}");
            }
        }
    }
}

#[test]
fn no_cable_is_an_empty_result() {
    for (gray, noise_sigma) in [(128, 0.0), (180, 6.0)] {
        let background = Background::Plain { bgr: [gray; 3] };
        let scene = draw_scene(480, 640, background, noise_sigma, Vec::new(), 5).unwrap();
        let out = detect(&scene.bgr, keep_straight());
        assert!(
            out.cables.is_empty(),
            "gray {gray}, noise {noise_sigma}: {} cables",
            out.cables.len()
        );
    }
}

#[test]
fn degenerate_images_do_not_panic() {
    let mut cases: Vec<(&str, Mat)> = Vec::new();
    for (name, rows, cols, typ, v) in [
        ("1x1", 1, 1, core::CV_8UC3, 0.0),
        ("1 row", 1, 640, core::CV_8UC3, 90.0),
        ("black", 480, 640, core::CV_8UC3, 0.0),
        ("white", 480, 640, core::CV_8UC3, 255.0),
        ("gray", 48, 64, core::CV_8UC1, 77.0),
        ("bgra", 48, 64, core::CV_8UC4, 77.0),
        ("16-bit", 48, 64, core::CV_16UC3, 30000.0),
        ("large", 2000, 3000, core::CV_8UC3, 200.0),
    ] {
        cases.push((
            name,
            Mat::new_rows_cols_with_default(rows, cols, typ, Scalar::all(v)).unwrap(),
        ));
    }
    let mut noise =
        Mat::new_rows_cols_with_default(120, 160, core::CV_8UC3, Scalar::all(0.0)).unwrap();
    core::randu(&mut noise, &Scalar::all(0.0), &Scalar::all(255.0)).unwrap();
    cases.push(("noise", noise));
    let mut stripes =
        Mat::new_rows_cols_with_default(100, 100, core::CV_8UC3, Scalar::all(0.0)).unwrap();
    for x in (0..100).step_by(2) {
        imgproc::line(
            &mut stripes,
            Point::new(x, 0),
            Point::new(x, 99),
            Scalar::all(255.0),
            1,
            imgproc::LINE_8,
            0,
        )
        .unwrap();
    }
    cases.push(("1-px stripes", stripes));
    for (name, image) in cases {
        for instances in [InstanceMethod::Skeleton, InstanceMethod::Superpixels] {
            let config = VisionConfig {
                instances,
                ..keep_straight()
            };
            let out = Pipeline::new(config).detect(&image, None);
            assert!(out.is_ok(), "{name}: {out:?}");
        }
    }
    let mut p = Pipeline::new(keep_straight());
    assert!(matches!(
        p.detect(&Mat::default(), None),
        Err(VisionError::EmptyImage { .. })
    ));
    let float = Mat::new_rows_cols_with_default(4, 4, core::CV_32FC3, Scalar::all(0.0)).unwrap();
    assert!(matches!(
        p.detect(&float, None),
        Err(VisionError::UnsupportedImage { .. })
    ));
}

#[test]
fn region_of_interest_bounds_the_work_and_maps_back() {
    let inside = segment_px([300.0, 240.0], [560.0, 300.0]);
    let outside = segment_px([20.0, 40.0], [250.0, 60.0]);
    let scene = on_gray_table(vec![
        cable(inside.clone(), [20; 3]),
        cable(outside, [20; 3]),
    ]);
    let roi = Rect::new(280, 200, 320, 160);
    let out = detect(
        &scene.bgr,
        VisionConfig {
            roi_px: Some(roi),
            ..keep_straight()
        },
    );
    assert_each_followed(&out, std::slice::from_ref(&inside), 2.5);
    let mid = midpoint_px(&inside).unwrap();
    let g = out.cables[0].grasp_px;
    assert!(
        (g[0] - mid[0]).hypot(g[1] - mid[1]) < 4.0,
        "{g:?} vs {mid:?}"
    );
    let union_mask = out.union_mask.as_ref().unwrap();
    assert_eq!(union_mask.size().unwrap(), scene.bgr.size().unwrap());
    assert_eq!(*union_mask.at_2d::<u8>(50, 100).unwrap(), 0);
    let off = VisionConfig {
        roi_px: Some(Rect::new(700, 500, 10, 10)),
        ..keep_straight()
    };
    assert!(matches!(
        Pipeline::new(off).detect(&scene.bgr, None),
        Err(VisionError::RoiOutside { .. })
    ));
}

#[test]
fn finer_and_coarser_cameras_are_worked_on_at_the_working_width_and_mapped_back() {
    // The crossing scene of 640 × 480, and the same drawn `k` times as
    // fine (3) or as coarse (0.5).
    let a = segment_px([60.0, 100.0], [580.0, 380.0]);
    let b = arc_px([330.0, 560.0], 380.0, -2.4, -0.7);
    let scene = |k: f64| {
        let cables = [(&a, [40, 40, 160]), (&b, [30, 30, 30])]
            .map(|(c, bgr)| matte_cable(c.iter().map(|&p| at_scale(p, k)).collect(), 8.0 * k, bgr));
        let size = |side: f64| (side * k) as i32;
        draw_scene(
            size(480.0),
            size(640.0),
            Background::Plain { bgr: [200; 3] },
            0.0,
            cables.to_vec(),
            2,
        )
        .unwrap()
    };
    let working = scene(1.0);
    let at_640 = detect(&working.bgr, keep_straight());
    assert_eq!(at_640.work_scale, 1.0);
    let roi = Rect::new(280, 200, 320, 160);
    let bounded = |image: &Mat, roi: Rect| {
        let config = VisionConfig {
            roi_px: Some(roi),
            ..keep_straight()
        };
        detect(image, config)
    };
    let at_640_in_roi = bounded(&working.bgr, roi);
    assert!(!at_640_in_roi.cables.is_empty());

    for k in [3.0, 0.5] {
        let image = scene(k).bgr;
        let out = detect(&image, keep_straight());
        assert!(
            (out.work_scale - 1.0 / k).abs() < 1e-9,
            "{}",
            out.work_scale
        );
        let curves = [&a, &b].map(|c| c.iter().map(|&p| at_scale(p, k)).collect::<Vec<_>>());
        assert_each_followed(&out, &curves, 2.0 * k);
        assert_found_alike(&out, &at_640, k);
        assert!((out.cable_width_px / at_640.cable_width_px - k).abs() < 0.05 * k);
        for (found, working) in out.cables.iter().zip(&at_640.cables) {
            let (found, working) = (found.mask.as_ref(), working.mask.as_ref());
            let (found, working) = (found.unwrap(), working.unwrap());
            assert_eq!(found.size().unwrap(), image.size().unwrap());
            let area_ratio = f64::from(core::count_non_zero(found).unwrap())
                / f64::from(core::count_non_zero(working).unwrap());
            assert!(
                (area_ratio / (k * k) - 1.0).abs() < 0.12,
                "mask area ratio {area_ratio} at {k}"
            );
        }
        // A region of interest is given in the image's pixels.
        let scaled = |v: i32| (f64::from(v) * k) as i32;
        let roi_k = Rect::new(
            scaled(roi.x),
            scaled(roi.y),
            scaled(roi.width),
            scaled(roi.height),
        );
        assert_found_alike(&bounded(&image, roi_k), &at_640_in_roi, k);
    }
}

/// Point `p` of a 640 px wide image in the same image drawn `k` times
/// as fine: pixel centres lie at whole coordinates in both.
fn at_scale(p: [f64; 2], k: f64) -> [f64; 2] {
    p.map(|v| k * v + (k - 1.0) / 2.0)
}

/// `found`, in an image `k` times as fine as 640 px wide, is what
/// `working` found at 640 px wide, in that image's pixels.
fn assert_found_alike(found: &VisionOutput, working: &VisionOutput, k: f64) {
    assert_eq!(found.cables.len(), working.cables.len());
    for (f, w) in found.cables.iter().zip(&working.cables) {
        let [x, y] = at_scale(w.grasp_px, k);
        let off_px = (f.grasp_px[0] - x).hypot(f.grasp_px[1] - y);
        // Within a fifth of a working pixel; a coarser image holds less
        // than the working one, within half its own pixel.
        let tolerance_px = if k > 1.0 { 0.2 * k } else { 0.5 };
        assert!(
            off_px < tolerance_px,
            "{:?} vs {:?} at {k}",
            f.grasp_px,
            [x, y]
        );
        assert!(angle_diff_rad(f.direction_rad, w.direction_rad) < 0.01);
        assert!((f.length_px / w.length_px / k - 1.0).abs() < 0.02);
    }
}

#[test]
fn a_short_cable_running_out_of_view_is_dropped_a_short_loose_one_kept() {
    // Both 60 px long: one enters from the left border, one lies loose.
    let at_border = segment_px([0.0, 100.0], [60.0, 100.0]);
    let loose = segment_px([300.0, 300.0], [360.0, 300.0]);
    let scene = on_gray_table(vec![
        cable(at_border, [20; 3]),
        cable(loose.clone(), [20; 3]),
    ]);
    let keep_all = VisionConfig {
        min_border_cable_length_px: 0.0,
        ..keep_straight()
    };
    let all = detect(&scene.bgr, keep_all);
    assert_eq!(all.cables.len(), 2);
    assert!(all.notes.is_empty(), "{:?}", all.notes);
    let out = detect(
        &scene.bgr,
        VisionConfig {
            min_border_cable_length_px: 80.0,
            ..keep_straight()
        },
    );
    assert_each_followed(&out, std::slice::from_ref(&loose), 2.5);
    // And says so.
    assert_eq!(
        out.notes,
        [
            "dropped 1 cable(s) that run out of view shorter than 80 px: too little of them is in view to grasp (a minimum border length of 0 keeps them)"
        ]
    );
}

#[test]
fn a_border_piece_is_measured_by_its_cable_where_only_cables_are_in_the_mask() {
    // A cable 8 px across, its rounded end 90 px into view: its skeleton
    // stops about half a width short of that end, under the 90 px border
    // length.
    let piece = segment_px([0.0, 200.0], [86.0, 211.0]);
    let border = |out: &VisionOutput| {
        out.notes
            .iter()
            .any(|n| n.contains("run out of view shorter than 90 px"))
    };
    // A plain table's classical mask, and a labelled one, hold cables
    // alone: the cable's length in view is weighed.
    let plain = on_gray_table(vec![cable(piece.clone(), [20; 3])]);
    let out = detect(&plain.bgr, keep_straight());
    assert_eq!(out.mask_used, MaskMethod::Classical);
    assert_each_followed(&out, std::slice::from_ref(&piece), 2.5);
    let labelled = Pipeline::new(keep_straight())
        .instances_from_mask(&plain.union_mask, Some(&plain.bgr))
        .unwrap();
    assert_eq!(labelled.cables.len(), 1);
    // On paint and prints the skeleton's own length is weighed: its
    // shortfall keeps short scraps of paint at the border out.
    let (out, _) = by_known_network(Background::Mosaic, &piece, keep_straight());
    assert!(out.cables.is_empty() && border(&out), "{:?}", out.notes);
    // The piece is long enough for a cable there, but for the border.
    let keep_border = VisionConfig {
        min_border_cable_length_px: 0.0,
        ..keep_straight()
    };
    let (out, _) = by_known_network(Background::Mosaic, &piece, keep_border);
    assert_eq!(out.cables.len(), 1, "{:?}", out.notes);
    assert!(
        out.cables[0].length_px < 90.0,
        "{}",
        out.cables[0].length_px
    );
}

#[test]
fn a_thick_cable_is_long_by_its_length_in_view_where_only_cables_are_in_the_mask() {
    // A tube 16 px across and 110 px long, lying loose: a skeleton about
    // a width shorter than the tube, under the ten widths a cable's
    // confidence asks for.
    let tube = vec![matte_cable(
        segment_px([200.0, 240.0], [310.0, 250.0]),
        16.0,
        [40, 40, 220],
    )];
    let scene = |background| draw_scene(480, 640, background, 0.0, tube.clone(), 7).unwrap();
    let plain = scene(Background::Plain { bgr: [210; 3] });
    let labelled = Pipeline::new(keep_straight())
        .instances_from_mask(&plain.union_mask, Some(&plain.bgr))
        .unwrap();
    // The same mask, as a network would mark it on a mosaic, where paint
    // may pass for cable: the skeleton's own length is weighed.
    let mosaic = scene(Background::Mosaic);
    let mut net = KnownMask::new(plain.union_mask.clone());
    let on_paint = Pipeline::new(keep_straight())
        .detect(&mosaic.bgr, Some(&mut net))
        .unwrap();
    assert_eq!((labelled.cables.len(), on_paint.cables.len()), (1, 1));
    let (cable, on_paint) = (&labelled.cables[0], &on_paint.cables[0]);
    // On paint the tube's width is also weighed against the image's
    // typical width, a factor of 1 at most.
    let ratio = cable.confidence / on_paint.confidence;
    let expected = (cable.length_px + labelled.cable_width_px) / cable.length_px;
    assert!(
        ratio > 0.99 * expected,
        "{} / {} against {expected}",
        cable.confidence,
        on_paint.confidence
    );
}

#[test]
fn a_band_along_the_border_is_not_taken_for_cable() {
    // Two cables converge on the right border at about 20° and reach
    // it about 50 px apart; a dark band along the border (a shadow at
    // the frame's edge) continues one into the other. Each cable ends
    // where it leaves the view, without a hook along the band. (Each
    // turns onto the band by about 64°, so the corner cut parts them
    // as well as the border cut; the skeleton's unit tests check the
    // border cut alone.)
    let upper = curve_through([560.0, 170.0], 0.45, -1.0 / 1000.0, 150);
    let lower = curve_through([560.0, 290.0], -0.45, 1.0 / 1000.0, 150);
    let in_view = |curve: &[[f64; 2]]| -> Vec<[f64; 2]> {
        curve.iter().copied().take_while(|p| p[0] < 637.0).collect()
    };
    let (upper, lower) = (in_view(&upper), in_view(&lower));
    let (upper_end, lower_end) = (*upper.last().unwrap(), *lower.last().unwrap());
    assert!((30.0..60.0).contains(&(lower_end[1] - upper_end[1])));
    let mut joined = upper.clone();
    joined.extend(segment_px([637.0, upper_end[1]], [637.0, lower_end[1]]));
    joined.extend(lower.iter().rev());
    // Corners rounded, as the mask's are: a moving average over 21 px.
    let rounded: Vec<[f64; 2]> = (0..joined.len())
        .map(|i| {
            let near = &joined[i.saturating_sub(10)..(i + 11).min(joined.len())];
            let n = near.len() as f64;
            [
                near.iter().map(|p| p[0]).sum::<f64>() / n,
                near.iter().map(|p| p[1]).sum::<f64>() / n,
            ]
        })
        .collect();
    let scene = on_gray_table(vec![cable(rounded, [30; 3])]);
    let out = detect(&scene.bgr, VisionConfig::default());
    assert_each_followed(&out, &[upper, lower], 3.0);
}

#[test]
fn two_cables_meeting_end_to_end_at_an_angle_are_two() {
    // One cable ends where the other begins, meeting at about 105°
    // (00042 of cables-dev: two wires leaving the view side by side,
    // their masks merged short of the border). The mask is one V.
    let left = curve_through([240.0, 190.0], 0.7, 1.0 / 400.0, 90);
    let apex = *left.last().unwrap();
    let right: Vec<[f64; 2]> = left
        .iter()
        .rev()
        .map(|p| [2.0 * apex[0] - p[0], p[1]])
        .collect();
    let scene = on_gray_table(vec![
        cable(left.clone(), [30; 3]),
        cable(right.clone(), [30; 3]),
    ]);
    let out = detect(&scene.bgr, VisionConfig::default());
    assert_each_followed(&out, &[left, right], 3.0);
}

#[test]
fn a_straight_detection_is_dropped_as_an_edge_unless_its_sides_are_alike() {
    use std::f64::consts::FRAC_PI_2;
    // A ruler-straight 300 px line 30 px from the top; a 110 px piece
    // of cable bent like a 600 px arc (2.5 px from straight); a 420 px
    // cable bowed like a 3000 px arc (7 px from straight).
    let straight = segment_px([100.0, 30.0], [400.0, 30.0]);
    let short_bent = arc_px([450.0, 900.0], 600.0, -FRAC_PI_2 - 0.09, -FRAC_PI_2 + 0.09);
    let long_bowed = arc_px(
        [320.0, 3400.0],
        3000.0,
        -FRAC_PI_2 - 0.07,
        -FRAC_PI_2 + 0.07,
    );
    let lines = [straight, short_bent, long_bowed];

    // Drawn as a cable on an even table, the straight line is a taut
    // cable: the table is alike on its two sides.
    let drawn = on_gray_table(lines.iter().map(|c| cable(c.clone(), [20; 3])).collect());
    let out = detect(&drawn.bgr, VisionConfig::default());
    assert!(out.plain_background, "{:?}", out.background);
    assert_each_followed(&out, &lines, 2.5);
    assert!(out.notes.is_empty(), "{:?}", out.notes);

    // The edge of a white sheet along the straight line, which a
    // network took for a cable: the table differs on its two sides.
    let scene = on_gray_table(
        lines[1..]
            .iter()
            .map(|c| cable(c.clone(), [20; 3]))
            .collect(),
    );
    let mut sheet_edge = scene.bgr.clone();
    Mat::roi_mut(&mut sheet_edge, Rect::new(0, 0, 640, 30))
        .unwrap()
        .set_to_def(&Scalar::all(250.0))
        .unwrap();
    let mut known = scene.union_mask.clone();
    let band = drawn_line(&lines[0], 8);
    core::bitwise_or_def(&scene.union_mask, &band, &mut known).unwrap();
    let by_network = |image: &Mat, config: VisionConfig| {
        let mut net = KnownMask::new(known.clone());
        let config = VisionConfig {
            mask: MaskMethod::Network,
            ..config
        };
        Pipeline::new(config).detect(image, Some(&mut net)).unwrap()
    };
    let dropped = |out: &VisionOutput| out.notes.iter().any(|n| n.contains("1 straight detection"));
    let out = by_network(&sheet_edge, VisionConfig::default());
    assert!(out.plain_background, "{:?}", out.background);
    assert_each_followed(&out, &lines[1..], 2.5);
    assert!(dropped(&out), "{:?}", out.notes);
    assert_each_followed(&by_network(&sheet_edge, keep_straight()), &lines, 2.5);

    // Under a light that falls off to the corners the table is no
    // longer plain as a whole, but it is around each pixel: the cable
    // is kept and the sheet's edge dropped as before.
    let out = by_network(&falling_off(&drawn.bgr), VisionConfig::default());
    assert!(!out.plain_background, "{:?}", out.background);
    assert_each_followed(&out, &lines, 2.5);
    assert!(!dropped(&out), "{:?}", out.notes);
    let out = by_network(&falling_off(&sheet_edge), VisionConfig::default());
    assert_each_followed(&out, &lines[1..], 2.5);
    assert!(dropped(&out), "{:?}", out.notes);
}

/// A 640 × 480 0/255 mask of `points` drawn `thickness` px wide.
fn drawn_line(points: &[[f64; 2]], thickness: i32) -> Mat {
    let mut drawn =
        Mat::new_rows_cols_with_default(480, 640, core::CV_8UC1, Scalar::all(0.0)).unwrap();
    let line: Vector<Point> = points
        .iter()
        .map(|p| Point::new(p[0].round() as i32, p[1].round() as i32))
        .collect();
    imgproc::polylines(
        &mut drawn,
        &Vector::<Vector<Point>>::from_iter([line]),
        false,
        Scalar::all(255.0),
        thickness,
        imgproc::LINE_8,
        0,
    )
    .unwrap();
    drawn
}

/// `image` under a light that falls off from its middle: the corners
/// at half the brightness.
fn falling_off(image: &Mat) -> Mat {
    let mut lit = image.clone();
    let (rows, cols) = (lit.rows(), lit.cols());
    for y in 0..rows {
        for x in 0..cols {
            let r =
                (f64::from(x) / f64::from(cols) - 0.5).hypot(f64::from(y) / f64::from(rows) - 0.5);
            let gain = 1.0 - r * r;
            let px = lit.at_2d_mut::<core::Vec3b>(y, x).unwrap();
            *px = core::Vec3b::from(px.0.map(|v| (f64::from(v) * gain) as u8));
        }
    }
    lit
}

/// Stands in for the segmentation network: the mask of the drawn cables.
/// It keeps whether it was told to look closer at each image.
struct KnownMask {
    mask: Mat,
    closer: Vec<bool>,
}

impl KnownMask {
    fn new(mask: Mat) -> Self {
        Self {
            mask,
            closer: Vec::new(),
        }
    }
}

impl MaskNetwork for KnownMask {
    fn mask(&mut self, _bgr: &Mat, background: &BackgroundStats) -> Result<Mat, VisionError> {
        self.closer.push(background.closer_look());
        Ok(self.mask.try_clone().expect("copy the known mask"))
    }
}

/// A red cable along `curve` drawn on `background` (then `lit`), found
/// with a network that marks exactly it: what the pipeline made of it,
/// and whether the network was told, each time it was asked, to look
/// closer.
fn by_known_network_lit(
    background: Background,
    lit: fn(&Mat) -> Mat,
    curve: &[[f64; 2]],
    config: VisionConfig,
) -> (VisionOutput, Vec<bool>) {
    let scene = draw_scene(
        480,
        640,
        background,
        0.0,
        vec![cable(curve.to_vec(), [40, 40, 220])],
        7,
    )
    .unwrap();
    let mut net = KnownMask::new(scene.union_mask.clone());
    let config = VisionConfig {
        mask: MaskMethod::Network,
        ..config
    };
    let out = Pipeline::new(config)
        .detect(&lit(&scene.bgr), Some(&mut net))
        .unwrap();
    assert_eq!(out.mask_used, MaskMethod::Network);
    (out, net.closer)
}

/// [`by_known_network_lit`] under an even light.
fn by_known_network(
    background: Background,
    curve: &[[f64; 2]],
    config: VisionConfig,
) -> (VisionOutput, Vec<bool>) {
    by_known_network_lit(background, |image| image.clone(), curve, config)
}

#[test]
fn the_network_looks_closer_at_a_mosaic_and_dark_cloth_and_not_at_wood() {
    let curve = arc_px([320.0, 560.0], 380.0, -2.3, -0.8);
    let mut seen = Vec::new();
    for background in [
        Background::Mosaic,
        Background::Plain { bgr: [25; 3] },
        Background::Wood,
    ] {
        let (out, closer) = by_known_network(background, &curve, keep_straight());
        seen.push((out.background, closer));
    }
    let [mosaic, dark, wood] = &seen[..] else {
        unreachable!()
    };
    assert!(mosaic.0.busy(), "{seen:?}");
    assert!(!dark.0.busy() && !wood.0.busy(), "{seen:?}");
    assert!(
        wood.0.near_fraction >= background::CLOSE_MAX_NEAR_FRACTION,
        "{seen:?}"
    );
    assert!(
        dark.0.background_lab[0] < background::DARK_MAX_LIGHTNESS,
        "{seen:?}"
    );
    assert!(
        wood.0.background_lab[0] >= background::DARK_MAX_LIGHTNESS,
        "{seen:?}"
    );
    assert_eq!(
        seen.iter()
            .map(|(_, closer)| closer.clone())
            .collect::<Vec<_>>(),
        [vec![true], vec![true], vec![false]]
    );
}

#[test]
fn a_gray_table_under_a_light_that_falls_off_is_looked_at_closer_but_not_taken_for_busy() {
    let curve = arc_px([320.0, 560.0], 380.0, -2.3, -0.8);
    let (out, closer) = by_known_network_lit(
        Background::Plain { bgr: [210; 3] },
        falling_off,
        &curve,
        VisionConfig::default(),
    );
    let near = out.background.near_fraction;
    assert!(
        (background::BUSY_MAX_NEAR_FRACTION..background::CLOSE_MAX_NEAR_FRACTION).contains(&near),
        "{:?}",
        out.background
    );
    assert!(!out.background.busy());
    assert_eq!(closer, [true]);
}

#[test]
fn a_straight_cable_on_a_busy_background_is_kept_and_on_wood_dropped_as_an_edge() {
    // A ruler-straight 400 px cable, as a network would mark it.
    let line = segment_px([120.0, 240.0], [520.0, 240.0]);
    let mut kept = Vec::new();
    for background in [Background::Mosaic, Background::Wood] {
        let (out, _) = by_known_network(background, &line, VisionConfig::default());
        let followed = each_followed(&out, std::slice::from_ref(&line), 2.5).is_ok();
        kept.push((out.background.near_fraction, followed, out.notes));
    }
    // Paint and prints are busy: a straight line there is as likely a
    // cable as an edge. Wood is not: its straight lines are a table's
    // or a sheet's edges.
    assert!(kept[0].0 < background::BUSY_MAX_NEAR_FRACTION, "{kept:?}");
    assert!(kept[0].1 && kept[0].2.is_empty(), "{kept:?}");
    assert!(kept[1].0 >= background::BUSY_MAX_NEAR_FRACTION, "{kept:?}");
    assert!(!kept[1].1, "{kept:?}");
    assert!(
        kept[1].2.iter().any(|n| n.contains("1 straight detection")),
        "{kept:?}"
    );
}

#[test]
fn a_short_piece_on_a_busy_background_is_dropped_as_paint_and_on_wood_kept() {
    // A 60 px arc: longer than a scrap of mask, as short as the paint
    // scraps the network marks on paint and prints.
    let piece = arc_px([320.0, 340.0], 100.0, -1.87, -1.27);
    let mut found = Vec::new();
    for background in [Background::Mosaic, Background::Wood] {
        let (out, _) = by_known_network(background, &piece, VisionConfig::default());
        found.push((out.background.near_fraction, out.cables.len()));
    }
    assert!(found[0].0 < background::BUSY_MAX_NEAR_FRACTION, "{found:?}");
    assert_eq!(found[0].1, 0, "{found:?}");
    assert!(
        found[1].0 >= background::BUSY_MAX_NEAR_FRACTION,
        "{found:?}"
    );
    assert_eq!(found[1].1, 1, "{found:?}");
    // The limit is a multiple of the configured one: 0 keeps everything.
    let keep_all = VisionConfig {
        min_cable_length_px: 0.0,
        ..VisionConfig::default()
    };
    let (out, _) = by_known_network(Background::Mosaic, &piece, keep_all);
    assert_eq!(out.cables.len(), 1);
}

#[test]
fn on_paint_a_detection_must_be_more_confident_than_on_wood() {
    let curve = arc_px([320.0, 560.0], 380.0, -2.3, -0.8);
    for (background, painted) in [(Background::Pollock, true), (Background::Wood, false)] {
        let with_floor = |min_confidence: f64| {
            let config = VisionConfig {
                min_confidence,
                ..keep_straight()
            };
            by_known_network(background.clone(), &curve, config).0
        };
        let all = with_floor(0.0);
        assert_eq!(all.background.painted(), painted, "{:?}", all.background);
        let [found] = &all.cables[..] else {
            panic!("{background:?}: {:?}", all.cables)
        };
        // A floor just under the cable's confidence, which the painted
        // background's factor lifts over it.
        let floor = found.confidence / (1.0 + (PAINTED_MIN_CONFIDENCE_FACTOR - 1.0) / 2.0);
        let out = with_floor(floor);
        if painted {
            assert!(out.cables.is_empty(), "{:?}", out.cables);
            let raised = format!(
                "less confident than {:.3} (the floor times {PAINTED_MIN_CONFIDENCE_FACTOR} on a painted background)",
                PAINTED_MIN_CONFIDENCE_FACTOR * floor
            );
            assert!(
                out.notes.iter().any(|n| n.contains(&raised)),
                "{raised}: {:?}",
                out.notes
            );
        } else {
            assert_eq!(out.cables.len(), 1, "{:?}", out.notes);
        }
    }
}

/// A 640 × 480 scene of `background` (seed 7) with one red cable along
/// `curve`.
fn red_cable_on(background: Background, curve: &[[f64; 2]]) -> RenderedScene {
    draw_scene(
        480,
        640,
        background,
        0.0,
        vec![cable(curve.to_vec(), [40, 40, 220])],
        7,
    )
    .unwrap()
}

#[test]
fn on_paint_a_cable_is_joined_across_a_longer_gap_in_its_mask() {
    // Two straight runs that meet at a bend of 0.35 rad, too sharp for
    // the long gap's rule. The network's mask loses the cable for 36 px
    // around the bend: the skeleton's ends lie about 44 px apart, over
    // the short gap on wood (four widths and 4 px) and within it on paint.
    let bend_px = [320.0, 260.0];
    let onward_px = [
        bend_px[0] + 220.0 * 0.35_f64.cos(),
        bend_px[1] - 220.0 * 0.35_f64.sin(),
    ];
    let mut curve = segment_px([90.0, 260.0], bend_px);
    curve.extend(segment_px(bend_px, onward_px).into_iter().skip(1));
    let keep_all = VisionConfig {
        min_confidence: 0.0,
        ..keep_straight()
    };
    for (background, pieces) in [(Background::Pollock, 1), (Background::Wood, 2)] {
        let scene = red_cable_on(background.clone(), &curve);
        let mut mask = scene.union_mask.clone();
        let centre = Point::new(bend_px[0] as i32, bend_px[1] as i32);
        imgproc::circle(
            &mut mask,
            centre,
            18,
            Scalar::all(0.0),
            -1,
            imgproc::LINE_8,
            0,
        )
        .unwrap();
        let config = VisionConfig {
            mask: MaskMethod::Network,
            ..keep_all.clone()
        };
        let out = Pipeline::new(config)
            .detect(&scene.bgr, Some(&mut KnownMask::new(mask)))
            .unwrap();
        assert_eq!(
            out.background.painted(),
            pieces == 1,
            "{:?}",
            out.background
        );
        assert_eq!(out.cables.len(), pieces, "{background:?}: {:?}", out.notes);
    }
}

/// A network whose probability on the cable is 0.45, and which cuts a
/// painted scene's probabilities at 0.4 and others' at 0.5, as the shipped
/// pair does: the mean of four looks is a smoother map.
struct FaintOnPaint {
    cable_mask: Mat,
}

impl MaskNetwork for FaintOnPaint {
    fn mask(&mut self, _bgr: &Mat, _background: &BackgroundStats) -> Result<Mat, VisionError> {
        let mut probability = Mat::default();
        self.cable_mask
            .convert_to(&mut probability, CV_32F, 0.45 / 255.0, 0.0)
            .expect("the cable's probability");
        Ok(probability)
    }

    fn threshold(&self, background: &BackgroundStats) -> f64 {
        if background.painted() { 0.4 } else { 0.5 }
    }
}

#[test]
fn a_painted_scene_is_cut_at_its_own_networks_threshold() {
    let curve = arc_px([320.0, 560.0], 380.0, -2.3, -0.8);
    let keep_all = VisionConfig {
        mask: MaskMethod::Network,
        min_confidence: 0.0,
        ..keep_straight()
    };
    for (background, found) in [(Background::Pollock, 1), (Background::Wood, 0)] {
        let scene = red_cable_on(background.clone(), &curve);
        let mut net = FaintOnPaint {
            cable_mask: scene.union_mask.clone(),
        };
        let out = Pipeline::new(keep_all.clone())
            .detect(&scene.bgr, Some(&mut net))
            .unwrap();
        assert_eq!(out.background.painted(), found == 1, "{:?}", out.background);
        assert_eq!(out.cables.len(), found, "{background:?}: {:?}", out.notes);
    }
}

#[test]
fn paint_as_flat_as_a_stroke_is_dropped_and_a_shaded_cable_kept() {
    // On Pollock-like paint the network (a stand-in) marks a rendered
    // cable and, below it, a stroke of one flat green as long and as wide.
    let cable_curve = arc_px([320.0, 560.0], 380.0, -2.3, -0.8);
    let stroke_curve = arc_px([320.0, 40.0], 380.0, 0.8, 2.3);
    let mut scene = draw_scene(
        480,
        640,
        Background::Pollock,
        0.0,
        vec![cable(cable_curve.clone(), [40, 40, 220])],
        7,
    )
    .unwrap();
    let stroke: Vector<Vector<Point>> = Vector::from_iter([stroke_curve
        .iter()
        .map(|p| Point::new(p[0].round() as i32, p[1].round() as i32))
        .collect()]);
    let mut mask = scene.union_mask.clone();
    for (image, colour) in [
        (&mut scene.bgr, Scalar::new(60.0, 160.0, 60.0, 0.0)),
        (&mut mask, Scalar::all(255.0)),
    ] {
        imgproc::polylines(image, &stroke, false, colour, 8, imgproc::LINE_8, 0).unwrap();
    }
    let detect = |min_confidence: f64| {
        let config = VisionConfig {
            mask: MaskMethod::Network,
            min_confidence,
            ..VisionConfig::default()
        };
        Pipeline::new(config)
            .detect(&scene.bgr, Some(&mut KnownMask::new(mask.clone())))
            .unwrap()
    };

    let out = detect(VisionConfig::default().min_confidence);
    assert!(out.background.near_fraction < 0.8, "{:?}", out.background);
    assert_each_followed(&out, std::slice::from_ref(&cable_curve), 2.0);
    assert!(
        out.notes.iter().any(|n| n.contains("flat as paint")),
        "{:?}",
        out.notes
    );
    // With no floor both are reported: the stroke is as long, as even
    // and as wide as the cable, and only its flat colour tells it apart.
    let all = detect(0.0);
    assert_each_followed(&all, &[cable_curve.clone(), stroke_curve.clone()], 2.0);
    let confidence_along = |curve: &[[f64; 2]]| {
        all.cables
            .iter()
            .find(|c| distance_to_polylines(c.grasp_px, &[curve.to_vec()]) < 3.0)
            .map(|c| c.confidence)
            .unwrap()
    };
    let (of_cable, of_stroke) = (
        confidence_along(&cable_curve),
        confidence_along(&stroke_curve),
    );
    assert!(of_cable > 0.8, "{of_cable}");
    assert!(of_stroke < 0.2 * of_cable, "{of_stroke} against {of_cable}");
}

#[test]
fn a_busy_background_takes_the_network_or_says_it_fell_back() {
    let curve = arc_px([320.0, 560.0], 380.0, -2.3, -0.8);
    let scene = red_cable_on(Background::Wood, &curve);

    let mut net = KnownMask::new(scene.union_mask.clone());
    let mut auto = Pipeline::new(keep_straight());
    let out = auto.detect(&scene.bgr, Some(&mut net)).unwrap();
    assert!(!out.plain_background, "{:?}", out.background);
    assert_eq!(out.mask_used, MaskMethod::Network);
    assert_each_followed(&out, &[curve], 2.0);

    let out = auto.detect(&scene.bgr, None).unwrap();
    assert_eq!(out.mask_used, MaskMethod::Classical);
    assert!(
        out.notes.iter().any(|n| n.contains("no network")),
        "{:?}",
        out.notes
    );
    // The classical mask is in doubt on wood, but the note that says
    // so is for plain tables.
    assert!(out.background.ambiguous_ratio > mask::MAX_AMBIGUOUS_RATIO);
    assert!(
        !out.notes.iter().any(|n| n.contains("plain background")),
        "{:?}",
        out.notes
    );

    let mut network_only = Pipeline::new(VisionConfig {
        mask: MaskMethod::Network,
        ..keep_straight()
    });
    assert!(matches!(
        network_only.detect(&scene.bgr, None),
        Err(VisionError::NoNetwork)
    ));
}

/// Stands in for a convolutional network near its input's border: it
/// finds the red cable by its colour, and also marks a band along the top
/// edge of whatever it is shown.
struct RedAndTopEdge;

impl MaskNetwork for RedAndTopEdge {
    fn mask(&mut self, bgr: &Mat, _background: &BackgroundStats) -> Result<Mat, VisionError> {
        let mut red = Mat::default();
        core::in_range(
            bgr,
            &Scalar::new(0.0, 0.0, 150.0, 0.0),
            &Scalar::new(120.0, 120.0, 255.0, 0.0),
            &mut red,
        )
        .expect("threshold the red cable");
        let band = Rect::new(20, 2, bgr.cols() - 40, 8);
        Mat::roi_mut(&mut red, band)
            .and_then(|mut top| {
                top.set_to(&Scalar::all(255.0), &core::no_array())
                    .map(|_| ())
            })
            .expect("mark the band");
        Ok(red)
    }
}

#[test]
fn the_network_sees_the_region_of_interest_with_the_image_around_it() {
    // A red arc on a plain table, and a region of interest around its
    // middle with the image above and below it.
    let curve = arc_px([320.0, 700.0], 480.0, -2.0, -1.1);
    let scene = on_gray_table(vec![cable(curve.clone(), [40, 40, 220])]);
    let roi = Rect::new(100, 150, 440, 160);
    let network_on = |roi_px| {
        Pipeline::new(VisionConfig {
            mask: MaskMethod::Network,
            roi_px,
            ..keep_straight()
        })
        .detect(&scene.bgr, Some(&mut RedAndTopEdge))
        .expect("detect")
    };
    // The band along the top of what the network saw lies above the
    // region: only the cable is found.
    let out = network_on(Some(roi));
    assert_eq!(out.cables.len(), 1, "{:?}", out.notes);
    let off_drawn: Vec<f64> = out.cables[0]
        .samples_px
        .iter()
        .map(|p| distance_to_polylines(*p, std::slice::from_ref(&curve)))
        .collect();
    assert!(off_drawn.iter().all(|&d| d < 2.5), "{off_drawn:?}");
    // Shown the whole image, the network's band lies along the image's
    // own top, outside the region, and is found as a cable there; the
    // cable is found where the region's view found it: the region was
    // cut from the network's view pixel for pixel.
    let whole = network_on(None);
    assert_eq!(whole.cables.len(), 2, "the band and the cable");
    let along_whole: Vec<Vec<[f64; 2]>> =
        whole.cables.iter().map(|c| c.samples_px.clone()).collect();
    let off_whole: Vec<f64> = out.cables[0]
        .samples_px
        .iter()
        .map(|p| distance_to_polylines(*p, &along_whole))
        .collect();
    let mean_px = off_whole.iter().sum::<f64>() / off_whole.len() as f64;
    assert!(
        mean_px < 0.3,
        "{mean_px} px from the whole image's cable: {off_whole:?}"
    );
}

#[test]
fn a_doubtful_classical_mask_on_a_plain_table_gives_way_to_the_network() {
    let curve = arc_px([320.0, 560.0], 380.0, -2.3, -0.8);
    let scene_with = |bgr: [u8; 3], gloss: f64, diameter_px: f64| {
        let spec = CableSpec {
            centerline_px: curve.clone(),
            diameter_px,
            bgr,
            gloss,
            metal_end_px: 0.0,
        };
        draw_scene(
            480,
            640,
            Background::Plain { bgr: [200; 3] },
            2.0,
            vec![spec],
            7,
        )
        .unwrap()
    };
    let mut auto = Pipeline::new(keep_straight());
    // A glossy cable a little darker than the table: its highlight is
    // the table's colour, and many pixels lie near the threshold. A
    // thick glossy white one: its shading passes through the table's
    // colour in a thin band, which leaves the mask hollow.
    for (scene, why) in [
        (scene_with([185, 175, 165], 1.0, 10.0), "ambiguous"),
        (scene_with([240; 3], 1.0, 16.0), "hollow"),
    ] {
        let mut net = KnownMask::new(scene.union_mask.clone());
        let out = auto.detect(&scene.bgr, Some(&mut net)).unwrap();
        assert!(out.plain_background, "{:?}", out.background);
        assert_eq!(out.mask_used, MaskMethod::Network, "{:?}", out.background);
        assert!(out.notes.iter().any(|n| n.contains(why)), "{:?}", out.notes);
        assert_each_followed(&out, std::slice::from_ref(&curve), 2.0);

        // Without a network the classical mask runs, says so, and
        // finds the cable's flanks as two or more cables.
        let out = auto.detect(&scene.bgr, None).unwrap();
        assert_eq!(out.mask_used, MaskMethod::Classical);
        assert!(
            out.notes
                .iter()
                .any(|n| n.contains(why) && n.contains("no network"))
        );
        assert!(out.cables.len() >= 2, "{} cables", out.cables.len());
    }

    // A dark matte cable on the same table is cut cleanly: the network
    // is skipped.
    let dark = scene_with([30; 3], 0.0, 10.0);
    let mut net = KnownMask::new(dark.union_mask.clone());
    let out = auto.detect(&dark.bgr, Some(&mut net)).unwrap();
    assert_eq!(out.mask_used, MaskMethod::Classical, "{:?}", out.notes);
    assert_each_followed(&out, &[curve], 2.0);
}

#[test]
fn superpixel_walks_follow_crossing_cables() {
    let a = segment_px([80.0, 80.0], [560.0, 400.0]);
    let b = segment_px([100.0, 420.0], [540.0, 60.0]);
    // With the simulated camera's sensor noise: without any, the
    // shaded black tube over the red one leaves the walk of the red
    // one split at the crossing, one piece ending on a superpixel
    // centred off its line.
    let scene = draw_scene(
        480,
        640,
        Background::Plain { bgr: [200; 3] },
        2.0,
        vec![
            cable(a.clone(), [40, 40, 160]),
            cable(b.clone(), [30, 30, 30]),
        ],
        8,
    )
    .unwrap();
    let out = detect(
        &scene.bgr,
        VisionConfig {
            instances: InstanceMethod::Superpixels,
            ..keep_straight()
        },
    );
    // Each cable is walked through the crossing from superpixel to
    // superpixel; slivers of superpixels beside a cable are no nodes, so
    // the walk and its spline keep to the cable.
    assert_each_followed(&out, &[a.clone(), b.clone()], 4.0);
    for c in &out.cables {
        let mean = c
            .samples_px
            .iter()
            .map(|&p| distance_to_polylines(p, &[a.clone(), b.clone()]))
            .sum::<f64>()
            / c.samples_px.len() as f64;
        assert!(mean < 1.5, "mean distance {mean:.1} px");
    }
}
