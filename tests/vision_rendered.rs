//! The vision pipeline on rendered scenes whose answer is known exactly:
//! one cable, several, a crossing, loops, plain and cluttered backgrounds.

mod common;

use cablecell::perception::vision::network::{LazyNetwork, runtime_library};
use cablecell::perception::vision::{
    GroundTruth, ImageScore, MaskMethod, Pipeline, VisionConfig, VisionOutput, score,
};
use cablecell::sim::render::{
    Background, BackgroundChoice, CableSpec, Light, RenderedScene, SceneOptions, SceneSpec,
    dataset_scene, random_scene, render,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn network() -> LazyNetwork {
    let model = common::root().join("models/cable_segmentation.onnx");
    LazyNetwork::new(model, runtime_library(None))
}

fn detect(scene: &RenderedScene, mask: MaskMethod) -> (VisionOutput, ImageScore) {
    let mut pipeline = Pipeline::new(VisionConfig {
        mask,
        ..VisionConfig::default()
    });
    let output = pipeline
        .detect(&scene.bgr, Some(&mut network()))
        .expect("the pipeline runs");
    let truth = GroundTruth {
        masks: scene.masks.clone(),
        union_mask: scene.union_mask.clone(),
        polylines_px: scene.centerlines_px.clone(),
    };
    let score = score(&output, &truth).expect("the masks are drawn");
    (output, score)
}

fn scene(background: Background, cables: Vec<CableSpec>) -> SceneSpec {
    SceneSpec {
        width_px: 640,
        height_px: 480,
        background,
        cables,
        light: Light::default(),
        noise_sigma: 2.0,
        blur_sigma_px: 0.5,
        occluders: Vec::new(),
        marker: None,
    }
}

/// A gently bent cable from `from` to `to`, bowed by `bow_px` at its middle.
fn cable(from: [f64; 2], to: [f64; 2], bow_px: f64, bgr: [u8; 3]) -> CableSpec {
    let (dx, dy) = (to[0] - from[0], to[1] - from[1]);
    let length = dx.hypot(dy);
    let normal = [-dy / length, dx / length];
    let steps = length.ceil() as usize;
    let centerline_px = (0..=steps)
        .map(|i| {
            let t = i as f64 / steps as f64;
            let bow = bow_px * 4.0 * t * (1.0 - t);
            [
                from[0] + t * dx + bow * normal[0],
                from[1] + t * dy + bow * normal[1],
            ]
        })
        .collect();
    CableSpec {
        centerline_px,
        diameter_px: 8.0,
        bgr,
        gloss: 0.3,
        metal_end_px: 0.0,
    }
}

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

#[test]
fn one_cable_on_a_plain_background_needs_no_network() {
    let spec = scene(
        Background::Plain {
            bgr: [200, 200, 200],
        },
        vec![cable([60.0, 300.0], [580.0, 200.0], 40.0, [40, 40, 170])],
    );
    let rendered = render(&spec, &mut rng(1)).expect("render");
    let (output, score) = detect(&rendered, MaskMethod::Auto);
    assert_eq!(output.mask_used, MaskMethod::Classical);
    assert!(output.plain_background);
    assert!(score.count_right, "{score:?}");
    assert!(score.union_dice > 0.85, "{score:?}");
    assert!(score.grasp_error_px.expect("a cable") < 1.0, "{score:?}");
    assert!(score.centerline_px.expect("a cable") < 1.0, "{score:?}");
}

#[test]
fn two_crossing_cables_are_told_apart() {
    let spec = scene(
        Background::Plain {
            bgr: [210, 210, 210],
        },
        vec![
            cable([50.0, 80.0], [590.0, 420.0], 20.0, [30, 30, 30]),
            cable([60.0, 400.0], [600.0, 60.0], -20.0, [170, 80, 30]),
        ],
    );
    let rendered = render(&spec, &mut rng(2)).expect("render");
    let (output, score) = detect(&rendered, MaskMethod::Auto);
    assert_eq!(output.cables.len(), 2, "{score:?}");
    // Each cable's path follows one true cable, not a turn at the crossing:
    // its samples lie near a true centre line all along.
    assert!(score.centerline_px.expect("cables") < 1.5, "{score:?}");
    assert!(score.instance_dice > 0.8, "{score:?}");
}

#[test]
fn several_cables_on_plain_backgrounds_are_counted() {
    let options = SceneOptions {
        min_cables: 3,
        max_cables: 3,
        backgrounds: BackgroundChoice::Plain,
        crossings: false,
        ..SceneOptions::default()
    };
    let mut right = 0;
    for seed in 0..6 {
        let mut rng = rng(seed);
        let spec = random_scene(&mut rng, &options);
        let rendered = render(&spec, &mut rng).expect("render");
        let (_, score) = detect(&rendered, MaskMethod::Auto);
        eprintln!("seed {seed}: {score:?}");
        right += usize::from(score.count_right);
        // Cables 6 to 16 px wide: a spline's ends may stray a little where
        // a thick cable's skeleton forks.
        assert!(
            score.centerline_px.expect("cables") < 3.5,
            "seed {seed}: {score:?}"
        );
        assert!(
            score.grasp_error_px.expect("cables") < 3.0,
            "seed {seed}: {score:?}"
        );
    }
    assert!(right >= 5, "{right} of 6 counted right");
}

#[test]
fn a_cable_on_clutter_is_found_by_the_network() {
    for (seed, background) in [(3, Background::Wood), (4, Background::Noise)] {
        let spec = scene(
            background,
            vec![cable([80.0, 260.0], [560.0, 220.0], 30.0, [40, 40, 190])],
        );
        let rendered = render(&spec, &mut rng(seed)).expect("render");
        let (output, score) = detect(&rendered, MaskMethod::Auto);
        eprintln!("seed {seed}: {score:?}");
        assert_eq!(output.mask_used, MaskMethod::Network, "seed {seed}");
        // Clutter may add scraps; the longest instance is the cable.
        let longest = output
            .cables
            .iter()
            .max_by(|a, b| a.length_px.total_cmp(&b.length_px))
            .expect("a cable");
        let distance = cablecell::perception::vision::eval::distance_to_polylines(
            longest.grasp_px,
            &rendered.centerlines_px,
        );
        assert!(distance < 3.0, "seed {seed}: grasp point {distance} px off");
        assert!(score.union_dice > 0.6, "seed {seed}: {score:?}");
    }
}

#[test]
fn loops_in_rendered_scenes_are_counted_right() {
    // 00087 of seed 21: a cable looping across itself at a shallow angle,
    // found as its loop and the rest before the loop's overlap merged its
    // two junctions. 00169 of seed 61: a loop through a crossing with
    // another cable, which merging an overlap whose junctions belong to
    // another crossing got wrong. (00053 of seed 21, eight branches of
    // three cables at one junction, checked that a loop's ends are kept
    // apart only at four branches; the network shipped then marks that
    // image's crossings otherwise, and it is miscounted at its top border
    // whatever that rule does, so it no longer checks the rule.)
    for (seed, index) in [(21, 87), (61, 169)] {
        // Image `index` of `cablecell render-dataset --seed SEED`.
        let scene = dataset_scene(seed, index, &SceneOptions::default()).expect("render");
        let (output, score) = detect(&scene, MaskMethod::Auto);
        assert!(
            score.count_right,
            "seed {seed}, image {index}: {} found, {score:?}",
            output.cables.len()
        );
    }
}
