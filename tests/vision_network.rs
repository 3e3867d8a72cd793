//! The segmentation network end to end: the shipped model through ONNX
//! Runtime on images made here (a drawn cable on a plain and on a textured
//! background), its agreement with the float network it was quantized
//! from and with the mirrored network that wraps it, the busy scenes'
//! network taking the busy scenes alone, its errors (a missing
//! model, a model of another input type, a missing or invalid runtime
//! library, a wrong image), and its accuracy on the held-out real
//! photographs of cables-dev when that folder is beside the project.
//!
//! The ONNX Runtime library comes from `ORT_DYLIB_PATH`, else from
//! `.setup/onnxruntime/libonnxruntime.so.1.31.1` (put there by
//! `scripts/setup`).

mod common;

use std::path::{Path, PathBuf};

use cablecell::perception::vision::background::background_stats;
use cablecell::perception::vision::eval::{self, GroundTruth};
use cablecell::perception::vision::network::{
    BUSY_MODEL, DEFAULT_BUSY_THRESHOLD, DEFAULT_MODEL, DEFAULT_THRESHOLD, FLOAT_MODEL, InputScales,
    LazyNetwork, MIRRORED_MODEL, NetworkError, SegmentationNet,
};
use cablecell::perception::vision::{MaskNetwork, Pipeline, VisionConfig, VisionError};
use cablecell::sim::render::Background;
use opencv::core::{CV_8U, CV_8UC1, CV_8UC3, Mat, Point, Scalar, Vector};
use opencv::prelude::*;
use opencv::{imgcodecs, imgproc};

fn runtime_library() -> PathBuf {
    match std::env::var_os("ORT_DYLIB_PATH") {
        Some(path) if !path.is_empty() => PathBuf::from(path),
        _ => common::root().join(".setup/onnxruntime/libonnxruntime.so.1.31.1"),
    }
}

fn model() -> PathBuf {
    PathBuf::from(DEFAULT_MODEL)
}

/// The shipped (8-bit) network.
fn net() -> SegmentationNet {
    load(&model())
}

fn load(model: &Path) -> SegmentationNet {
    let library = runtime_library();
    assert!(
        library.is_file(),
        "ONNX Runtime library {} not found: run scripts/setup or set ORT_DYLIB_PATH",
        library.display()
    );
    match SegmentationNet::load(model, &library) {
        Ok(net) => net,
        Err(e) => panic!("loading {}: {e}", model.display()),
    }
}

/// A smooth S-shaped cable across a 640 × 480 image: its polyline.
fn cable_polyline() -> Vector<Point> {
    (0..=100)
        .map(|i| {
            let t = f64::from(i) / 100.0;
            let x = 80.0 + 480.0 * t;
            let y = 240.0 + 120.0 * (t * std::f64::consts::TAU).sin() + 40.0 * t;
            Point::new(x.round() as i32, y.round() as i32)
        })
        .collect()
}

/// Draws the cable (6 px wide, a darker rim and a lighter core, as a round
/// wire looks) on `background`; returns the image and the cable's exact mask.
fn draw_cable(background: Mat, colour: Scalar) -> (Mat, Mat) {
    let mut image = background;
    let line = Vector::<Vector<Point>>::from_iter([cable_polyline()]);
    let rim = colour * 0.75;
    imgproc::polylines(&mut image, &line, false, rim, 6, imgproc::LINE_AA, 0).unwrap();
    imgproc::polylines(&mut image, &line, false, colour, 3, imgproc::LINE_AA, 0).unwrap();
    let mut mask = Mat::new_rows_cols_with_default(480, 640, CV_8UC1, Scalar::all(0.0)).unwrap();
    imgproc::polylines(
        &mut mask,
        &line,
        false,
        Scalar::all(255.0),
        6,
        imgproc::LINE_8,
        0,
    )
    .unwrap();
    (image, mask)
}

/// Recall (share of the cable found) and false-positive rate (share of the
/// background marked) of `predicted` against `truth`.
fn recall_and_false_positives(predicted: &Mat, truth: &Mat) -> (f64, f64) {
    let p = predicted.data_bytes().unwrap();
    let t = truth.data_bytes().unwrap();
    let (mut hit, mut cable, mut false_pos, mut background) = (0u64, 0u64, 0u64, 0u64);
    for (&p, &t) in p.iter().zip(t) {
        if t > 127 {
            cable += 1;
            hit += u64::from(p > 127);
        } else {
            background += 1;
            false_pos += u64::from(p > 127);
        }
    }
    (
        hit as f64 / cable as f64,
        false_pos as f64 / background as f64,
    )
}

fn dice_and_iou(predicted: &Mat, truth: &Mat) -> (f64, f64) {
    let p = predicted.data_bytes().unwrap();
    let t = truth.data_bytes().unwrap();
    let (mut inter, mut np, mut nt) = (0u64, 0u64, 0u64);
    for (&p, &t) in p.iter().zip(t) {
        let (p, t) = (p > 127, t > 127);
        inter += u64::from(p && t);
        np += u64::from(p);
        nt += u64::from(t);
    }
    let dice = 2.0 * inter as f64 / (np + nt).max(1) as f64;
    let iou = inter as f64 / (np + nt - inter).max(1) as f64;
    (dice, iou)
}

fn check_mask(mask: &Mat) {
    assert_eq!((mask.cols(), mask.rows()), (640, 480));
    assert_eq!(mask.typ(), CV_8UC1);
    assert!(
        mask.data_bytes()
            .unwrap()
            .iter()
            .all(|&v| v == 0 || v == 255)
    );
}

#[test]
fn finds_a_drawn_cable_on_a_plain_background() {
    let mut net = net();
    let background =
        Mat::new_rows_cols_with_default(480, 640, CV_8UC3, Scalar::new(205.0, 215.0, 220.0, 0.0))
            .unwrap();
    let (image, truth) = draw_cable(background, Scalar::new(40.0, 40.0, 200.0, 0.0));
    let mask = net.mask(&image).unwrap();
    check_mask(&mask);
    let (recall, false_pos) = recall_and_false_positives(&mask, &truth);
    eprintln!("plain background: recall {recall:.3}, false positives {false_pos:.4}");
    // measured with the shipped model: recall 0.942, false positives 0.0008
    assert!(recall >= 0.9, "recall {recall}");
    assert!(false_pos <= 0.01, "false positives {false_pos}");
}

/// A wood-like texture: grain stripes warped by a slow wave, with noise.
fn wood(seed: u64) -> Mat {
    let mut image = Mat::new_rows_cols_with_default(480, 640, CV_8UC3, Scalar::all(0.0)).unwrap();
    let mut state = seed;
    let bytes = image.data_bytes_mut().unwrap();
    for y in 0..480usize {
        for x in 0..640usize {
            // xorshift noise, a few grey levels
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let noise = (state % 13) as f64 - 6.0;
            let (xf, yf) = (x as f64, y as f64);
            let grain = (0.5 + 0.5 * ((yf + 18.0 * (xf / 90.0).sin()) / 7.0).sin()).powi(3);
            let shade = 1.0 - 0.22 * grain;
            let i = 3 * (y * 640 + x);
            bytes[i] = (150.0 * shade + noise).clamp(0.0, 255.0) as u8;
            bytes[i + 1] = (200.0 * shade + noise).clamp(0.0, 255.0) as u8;
            bytes[i + 2] = (232.0 * shade + noise).clamp(0.0, 255.0) as u8;
        }
    }
    image
}

#[test]
fn finds_a_drawn_cable_on_a_textured_background() {
    let mut net = net();
    let (image, truth) = draw_cable(
        wood(0x9e37_79b9_7f4a_7c15),
        Scalar::new(170.0, 90.0, 30.0, 0.0),
    );
    let mask = net.mask(&image).unwrap();
    check_mask(&mask);
    let (recall, false_pos) = recall_and_false_positives(&mask, &truth);
    eprintln!("textured background: recall {recall:.3}, false positives {false_pos:.4}");
    // measured with the shipped model: recall 0.914, false positives 0.0006
    assert!(recall >= 0.9, "recall {recall}");
    assert!(false_pos <= 0.01, "false positives {false_pos}");
}

/// The shipped network is the float one quantized to 8 bits: their masks
/// of the same scenes must agree nearly pixel for pixel.
#[test]
fn the_8_bit_network_marks_what_the_float_one_marks() {
    let (mut quantized, mut float) = (net(), load(Path::new(FLOAT_MODEL)));
    let plain =
        Mat::new_rows_cols_with_default(480, 640, CV_8UC3, Scalar::new(205.0, 215.0, 220.0, 0.0))
            .unwrap();
    let scenes = [
        draw_cable(plain, Scalar::new(40.0, 40.0, 200.0, 0.0)).0,
        draw_cable(wood(7), Scalar::new(170.0, 90.0, 30.0, 0.0)).0,
        wood(11),
    ];
    for (i, image) in scenes.iter().enumerate() {
        let (a, b) = (quantized.mask(image).unwrap(), float.mask(image).unwrap());
        let differ = a
            .data_bytes()
            .unwrap()
            .iter()
            .zip(b.data_bytes().unwrap())
            .filter(|(a, b)| a != b)
            .count();
        let marked = usize::try_from(opencv::core::count_non_zero(&b).unwrap()).unwrap();
        eprintln!("scene {i}: {differ} pixels differ, the float network marks {marked}");
        // measured: 16 of 4895, 26 of 4675, and 0 of 0 (bare wood)
        assert!(
            differ * 50 <= marked,
            "scene {i}: {differ} pixels differ, more than 2 % of {marked}"
        );
    }
}

/// How far `network`'s looks at `image` and at its mirror images (OpenCV's
/// flip codes `mirrors`), each mirrored back, lie apart at most, and how
/// far `wrapped`'s probabilities lie from their mean at most; both at input
/// scale 0.5, where the network sees exact 2 × 2 averages, which mirror
/// with the image, so that a wrapper that averages those looks matches the
/// mean made here to float rounding.
fn looks_apart_and_wrapped_from_their_mean(
    network: &Path,
    wrapped: &Path,
    image: &Mat,
    mirrors: &[i32],
) -> (f32, f32) {
    let (mut plain, mut wrapped) = (load(network), load(wrapped));
    plain.input_scale = 0.5;
    wrapped.input_scale = 0.5;
    let flip = |m: &Mat, code: i32| {
        let mut out = Mat::default();
        opencv::core::flip(m, &mut out, code).unwrap();
        out
    };
    let seen = plain.probability(image).unwrap();
    let mut looks = vec![seen.data_typed::<f32>().unwrap().to_vec()];
    for &code in mirrors {
        let back = flip(&plain.probability(&flip(image, code)).unwrap(), code);
        looks.push(back.data_typed::<f32>().unwrap().to_vec());
    }
    let averaged = wrapped.probability(image).unwrap();
    let (mut most_apart, mut worst) = (0.0f32, 0.0f32);
    for (i, m) in averaged.data_typed::<f32>().unwrap().iter().enumerate() {
        let at_i = looks.iter().map(|look| look[i]);
        let (low, high) = at_i
            .clone()
            .fold((f32::MAX, f32::MIN), |(l, h), p| (l.min(p), h.max(p)));
        most_apart = most_apart.max(high - low);
        worst = worst.max((m - at_i.sum::<f32>() / looks.len() as f32).abs());
    }
    (most_apart, worst)
}

/// The mirrored network is the shipped one run on the image and on its
/// mirror image (left for right), the second probability map mirrored
/// back, and the two averaged.
#[test]
fn the_mirrored_network_averages_the_shipped_one_on_the_image_and_its_mirror() {
    let image = draw_cable(wood(3), Scalar::new(170.0, 90.0, 30.0, 0.0)).0;
    let (most_apart, worst) =
        looks_apart_and_wrapped_from_their_mean(&model(), Path::new(MIRRORED_MODEL), &image, &[1]);
    eprintln!("the two views differ by up to {most_apart}; the mirrored network by {worst}");
    assert!(
        most_apart > 0.01,
        "the network sees the mirror image as it sees the image: the test shows nothing"
    );
    assert!(
        worst < 1e-4,
        "the mirrored network is {worst} from the mean of the two views"
    );
}

/// The shipped network for painted scenes is the busy network run on a
/// painted scene, on its mirror image left for right, top for bottom and
/// both, each probability map mirrored back, and the four averaged.
#[test]
fn the_busy_scenes_network_averages_four_looks_at_a_painted_scene() {
    let paint = common::scenes::draw_scene(480, 640, Background::Pollock, 0.0, Vec::new(), 5)
        .expect("paint")
        .bgr;
    let image = draw_cable(paint, Scalar::new(40.0, 40.0, 200.0, 0.0)).0;
    let one_look = common::root().join("models/cable_segmentation_busy.onnx");
    let (most_apart, worst) = looks_apart_and_wrapped_from_their_mean(
        &one_look,
        Path::new(BUSY_MODEL),
        &image,
        &[1, 0, -1],
    );
    eprintln!("the four views differ by up to {most_apart}; the shipped busy network by {worst}");
    assert!(
        most_apart > 0.01,
        "the busy network sees each mirror image as it sees the image: the test shows nothing"
    );
    assert!(
        worst < 1e-4,
        "the shipped busy network is {worst} from the mean of the four views"
    );
}

/// Given a network for busy scenes, a scene on paint goes to it, and one
/// on a plain table or on wood (busy, but of one hue) to the first
/// network, each at the input scale its background asks for: the
/// probabilities must be those of the network chosen, run alone, and they
/// are cut at that network's threshold.
#[test]
fn a_painted_scene_goes_to_the_busy_network_and_wood_or_a_plain_one_to_the_first() {
    let mut routed = LazyNetwork::new(model(), runtime_library())
        .with_busy_model(Some(PathBuf::from(BUSY_MODEL)), DEFAULT_BUSY_THRESHOLD);
    let (mut first, mut busy) = (net(), load(Path::new(BUSY_MODEL)));
    let scales = InputScales::default();
    let paint = common::scenes::draw_scene(480, 640, Background::Pollock, 0.0, Vec::new(), 5)
        .expect("paint")
        .bgr;
    let table =
        Mat::new_rows_cols_with_default(480, 640, CV_8UC3, Scalar::new(205.0, 215.0, 220.0, 0.0))
            .unwrap();
    // Seed 1: a grain busy by its edges.
    let wood = common::scenes::draw_scene(480, 640, Background::Wood, 0.0, Vec::new(), 1)
        .expect("wood")
        .bgr;
    let red = Scalar::new(40.0, 40.0, 200.0, 0.0);
    for (name, background, busy_scene) in [
        ("paint", paint, true),
        ("table", table, false),
        ("wood", wood, false),
    ] {
        let image = draw_cable(background, red).0;
        let stats = background_stats(&image).unwrap();
        assert_eq!(stats.painted(), busy_scene, "{name}: {stats:?}");
        if name == "wood" {
            assert!(
                stats.busy(),
                "wood: not busy, so the test shows nothing: {stats:?}"
            );
        }
        let scale = if busy_scene {
            scales.busy
        } else if stats.closer_look() {
            scales.close
        } else {
            scales.normal
        };
        first.input_scale = scale;
        busy.input_scale = scale;
        let seen = routed.mask(&image, &stats).unwrap();
        let threshold = if busy_scene {
            DEFAULT_BUSY_THRESHOLD
        } else {
            DEFAULT_THRESHOLD
        };
        assert_eq!(
            routed.threshold(&stats),
            f64::from(threshold),
            "{name}: not the chosen network's threshold"
        );
        let (by_first, by_busy) = (
            first.probability(&image).unwrap(),
            busy.probability(&image).unwrap(),
        );
        let apart = |a: &Mat, b: &Mat| {
            a.data_typed::<f32>()
                .unwrap()
                .iter()
                .zip(b.data_typed::<f32>().unwrap())
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max)
        };
        let (chosen, other) = if busy_scene {
            (&by_busy, &by_first)
        } else {
            (&by_first, &by_busy)
        };
        eprintln!(
            "{name}: {} from the network chosen, {} from the other",
            apart(&seen, chosen),
            apart(&seen, other)
        );
        assert_eq!(
            apart(&seen, chosen),
            0.0,
            "{name}: not the chosen network's"
        );
        assert!(
            apart(&seen, other) > 0.01,
            "{name}: the two networks agree: the test shows nothing"
        );
    }
}

/// A busy scenes' network that is missing is found when the networks are
/// loaded, before any image, whatever the images.
#[test]
fn a_missing_busy_scenes_model_is_reported_on_loading() {
    let missing = common::root().join("models/no-such-busy-model.onnx");
    let mut routed = LazyNetwork::new(model(), runtime_library())
        .with_busy_model(Some(missing.clone()), DEFAULT_BUSY_THRESHOLD);
    match routed.load() {
        Err(VisionError::Network {
            source: NetworkError::ModelMissing { path, .. },
        }) => assert_eq!(path, missing),
        other => panic!("expected the busy model missing, got {other:?}"),
    }
}

#[test]
fn a_missing_model_is_reported() {
    let missing = common::root().join("models/no-such-model.onnx");
    match SegmentationNet::load(&missing, &runtime_library()) {
        Err(NetworkError::ModelMissing { path, source }) => {
            assert_eq!(path, missing);
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("expected ModelMissing, got {other:?}"),
    }
}

/// `tests/fixtures/int32_input.onnx` passes its int32 input through
/// (`onnx.helper`: one Identity node, opset 17, IR version 8): a model
/// that takes neither the image's bytes nor float32.
#[test]
fn a_model_that_takes_neither_bytes_nor_floats_is_reported() {
    let model = common::root().join("tests/fixtures/int32_input.onnx");
    match SegmentationNet::load(&model, &runtime_library()) {
        Err(e @ NetworkError::ModelInput { .. }) => {
            assert!(e.is_in_setup());
            let message = e.to_string();
            assert!(message.contains("int32_input.onnx"), "{message}");
            assert!(message.contains("Tensor<i32>"), "{message}");
            assert!(message.contains("expected uint8 or float32"), "{message}");
        }
        other => panic!("expected ModelInput, got {other:?}"),
    }
}

#[test]
fn a_missing_runtime_library_is_reported() {
    let missing = common::root().join(".setup/onnxruntime/libonnxruntime.so.0.0.0-missing");
    let err = SegmentationNet::load(&model(), &missing).unwrap_err();
    match &err {
        NetworkError::RuntimeMissing { library, source } => {
            assert_eq!(library, &missing);
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("expected RuntimeMissing, got {other:?}"),
    }
    assert!(err.to_string().contains("scripts/setup"), "{err}");
}

#[test]
fn an_invalid_runtime_library_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let fake = dir.path().join("libonnxruntime.so.1.31.1");
    std::fs::write(&fake, b"not a shared library").unwrap();
    match SegmentationNet::load(&model(), &fake) {
        // Not a library; or, when another test of this process loaded the
        // real one first, not the one already loaded.
        Err(
            NetworkError::RuntimeLoad { library, .. }
            | NetworkError::RuntimeConflict { library, .. },
        ) => assert_eq!(library, fake),
        other => panic!("expected RuntimeLoad or RuntimeConflict, got {other:?}"),
    }
    // the real library still loads afterwards in the same process
    let _ = net();
}

#[test]
fn a_wrong_image_is_reported() {
    let mut net = net();
    let gray = Mat::new_rows_cols_with_default(480, 640, CV_8U, Scalar::all(0.0)).unwrap();
    assert!(matches!(net.mask(&gray), Err(NetworkError::Image { .. })));
    assert!(matches!(
        net.mask(&Mat::default()),
        Err(NetworkError::Image { .. })
    ));
}

/// The held-out photographs 00030..00044 of cables-dev (not used in
/// training): mean union DICE at threshold 0.5 and the default input size.
/// Measured with the shipped model: DICE 0.6732, IoU 0.5093
/// (models/history.md says why the labels hold it there); this allows 0.02
/// less.
const HELD_OUT_MIN_DICE: f64 = 0.654;

#[test]
#[ignore = "needs the cables-dev photographs in ../shared/data; scripts/test runs it when they are there"]
fn held_out_real_photographs() {
    let data = common::cables_dev();
    let mut net = net();
    let (mut dice_sum, mut iou_sum, mut n) = (0.0, 0.0, 0);
    for i in 30..45 {
        let image = read(&data, &format!("{i:05}.jpg"), imgcodecs::IMREAD_COLOR);
        let truth = read(
            &data,
            &format!("{i:05}_mask_all.png"),
            imgcodecs::IMREAD_GRAYSCALE,
        );
        let mask = net.mask(&image).unwrap();
        let (dice, iou) = dice_and_iou(&mask, &truth);
        eprintln!("{i:05}: DICE {dice:.4}, IoU {iou:.4}");
        dice_sum += dice;
        iou_sum += iou;
        n += 1;
    }
    let (dice, iou) = (dice_sum / f64::from(n), iou_sum / f64::from(n));
    eprintln!("held-out mean: DICE {dice:.4}, IoU {iou:.4}");
    assert!(
        dice >= HELD_OUT_MIN_DICE,
        "mean DICE {dice} < {HELD_OUT_MIN_DICE}"
    );
}

/// The whole pipeline with the shipped model on the held-out photographs,
/// default settings (`eval-vision --from 00030 --to 00044`). Measured:
/// union DICE 0.692, the count right in 7 of 15, grasp points 4.85 px from
/// the labelled centre lines on average, most of it in three images where
/// a detection has no label: 00031, where the folder's punched edge is
/// taken for a cable (18.5 px), and 00037 and 00044, whose unlabelled wires
/// at the border are found (14.3 and 15.0 px). models/history.md says why the
/// first two are low. The bounds allow a little drift (a count one image
/// lower), keep the grasp point inside the 5 px goal, and fail on a worse
/// model or pipeline. Of the 95 labelled cables, 5 are not found, all
/// pieces of 56–76 px at the border, shorter than the 90 px under which a
/// cable running out of view is dropped; of the 94 found, 4 match no label.
/// Of the labelled centre lines' length, 91.1 % lies within 5 px of a found
/// one, and 90.0 % of the found length within 5 px of a labelled one. The
/// labels lie above the wires found: the found masks match them best moved
/// up by 1.07 px on average (by −1 to 3 px in each image), at a mean
/// union DICE of 0.713.
const HELD_OUT_PIPELINE_DICE: f64 = 0.68;
const HELD_OUT_PIPELINE_LENGTH_SHARE: f64 = 0.89;
const HELD_OUT_PIPELINE_COUNT_RIGHT: usize = 6;
const HELD_OUT_PIPELINE_GRASP_PX: f64 = 5.0;
const HELD_OUT_PIPELINE_MISSED: usize = 7;
const HELD_OUT_PIPELINE_UNLABELLED: usize = 5;
const HELD_OUT_PIPELINE_MEAN_UP_PX: f64 = 0.5;

#[test]
#[ignore = "needs the cables-dev photographs in ../shared/data; scripts/test runs it when they are there"]
fn held_out_real_photographs_through_the_pipeline() {
    let data = common::cables_dev();
    let mut net = net();
    let mut pipeline = Pipeline::new(VisionConfig::default());
    let mut scores = Vec::new();
    for i in 30..45 {
        let stem = format!("{i:05}");
        let image = read(&data, &format!("{stem}.jpg"), imgcodecs::IMREAD_COLOR);
        let truth = GroundTruth::load(&data, &stem).unwrap();
        let output = pipeline.detect(&image, Some(&mut net)).unwrap();
        let score = eval::score(&output, &truth).expect("the masks are drawn");
        eprintln!("{stem}: {score:?}");
        scores.push(score);
    }
    let summary = eval::summarize(&scores);
    eprintln!("held-out summary: {summary:?}");
    assert!(summary.union_dice >= HELD_OUT_PIPELINE_DICE, "{summary:?}");
    let right = scores.iter().filter(|s| s.count_right).count();
    assert!(right >= HELD_OUT_PIPELINE_COUNT_RIGHT, "{summary:?}");
    assert!(
        summary
            .grasp_error_px
            .is_some_and(|d| d <= HELD_OUT_PIPELINE_GRASP_PX),
        "{summary:?}"
    );
    // Every labelled cable wholly in view is found; those missed run out
    // of view, too little of them in it to grasp.
    let missed: Vec<_> = scores.iter().flat_map(|s| &s.missed).collect();
    assert!(missed.len() <= HELD_OUT_PIPELINE_MISSED, "{missed:?}");
    assert!(missed.iter().all(|m| m.at_border), "{missed:?}");
    let unlabelled = scores.iter().map(|s| s.unlabelled.len()).sum::<usize>();
    assert!(unlabelled <= HELD_OUT_PIPELINE_UNLABELLED, "{unlabelled}");
    let share = |length: fn(&eval::ImageScore) -> (f64, f64)| {
        let (all, near) = scores
            .iter()
            .map(length)
            .fold((0.0, 0.0), |(a, n), (l, m)| (a + l, n + m));
        near / all
    };
    let labelled_found = share(|s| (s.labelled_length_px, s.labelled_length_found_px));
    let found_labelled = share(|s| (s.found_length_px, s.found_length_labelled_px));
    assert!(
        labelled_found >= HELD_OUT_PIPELINE_LENGTH_SHARE,
        "{labelled_found}"
    );
    assert!(
        found_labelled >= HELD_OUT_PIPELINE_LENGTH_SHARE,
        "{found_labelled}"
    );
    let mean_up_px = -scores
        .iter()
        .map(|s| f64::from(s.mask_offset_px[1]))
        .sum::<f64>()
        / scores.len() as f64;
    assert!(mean_up_px >= HELD_OUT_PIPELINE_MEAN_UP_PX, "{mean_up_px}");
}

fn read(dir: &Path, name: &str, flags: i32) -> Mat {
    let path = dir.join(name);
    let image = imgcodecs::imread(&path, flags).unwrap();
    assert!(!image.empty(), "cannot read {}", path.display());
    image
}
