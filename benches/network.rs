//! The segmentation network on one 640 × 480 BGR image, pre- and
//! post-processing included (resize down, ONNX Runtime with 2 intra-op
//! threads, resize the probability up, threshold): what `SegmentationNet::
//! mask` costs the detector per camera frame, at three input sizes, and
//! the float network it was quantized from, and the network for painted
//! scenes at their scale, looking once and four times; and the whole
//! pipeline with it, on the image and on the image enlarged to 1280 × 960
//! and 1920 × 1440. Uses the
//! first held-out photograph of cables-dev when it lies beside the
//! project, else a drawn image. The ONNX Runtime library comes from
//! `ORT_DYLIB_PATH`, else from `.setup/onnxruntime/` (run `scripts/setup`).

use std::path::{Path, PathBuf};

use cablecell::perception::vision::network::{
    BUSY_MODEL, DEFAULT_BUSY_INPUT_SCALE, DEFAULT_INPUT_SCALE, DEFAULT_MODEL, FLOAT_MODEL,
    SegmentationNet,
};
use cablecell::perception::vision::{MaskMethod, MaskNetwork, Pipeline, VisionConfig};
use criterion::{Criterion, criterion_group, criterion_main};
use opencv::core::{CV_8UC3, Mat, Point, Scalar, Vector};
use opencv::prelude::*;
use opencv::{imgcodecs, imgproc};

fn image(root: &std::path::Path) -> Mat {
    let photo = root.join("../shared/data/cables-dev/00030.jpg");
    if photo.is_file()
        && let Ok(image) = imgcodecs::imread(&photo, imgcodecs::IMREAD_COLOR)
        && !image.empty()
    {
        return image;
    }
    // The figures in docs/ are on the photograph; say when these are not.
    eprintln!(
        "timing a drawn image: {} is absent or unreadable",
        photo.display()
    );
    let mut image =
        Mat::new_rows_cols_with_default(480, 640, CV_8UC3, Scalar::new(200.0, 210.0, 220.0, 0.0))
            .expect("allocating the bench image");
    let cable: Vector<Point> = (0..=60)
        .map(|i| {
            Point::new(
                60 + 9 * i,
                240 + ((f64::from(i) / 6.0).sin() * 100.0) as i32,
            )
        })
        .collect();
    imgproc::polylines(
        &mut image,
        &Vector::<Vector<Point>>::from_iter([cable]),
        false,
        Scalar::new(30.0, 30.0, 190.0, 0.0),
        6,
        imgproc::LINE_AA,
        0,
    )
    .expect("drawing the bench image");
    image
}

fn bench(c: &mut Criterion) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let library = std::env::var_os("ORT_DYLIB_PATH")
        .filter(|p| !p.is_empty())
        .map_or_else(
            || root.join(".setup/onnxruntime/libonnxruntime.so.1.31.1"),
            PathBuf::from,
        );
    let load = |model: &str| match SegmentationNet::load(Path::new(model), &library) {
        Ok(net) => net,
        Err(e) => panic!("{e}"),
    };
    let image = image(&root);
    // The network's input size against its cost (eval-vision --sweep gives
    // the error that goes with each).
    let mut net = load(DEFAULT_MODEL);
    for scale in [DEFAULT_INPUT_SCALE, 0.5, 0.75] {
        net.input_scale = scale;
        c.bench_function(
            &format!("network mask 640x480 at input scale {scale}"),
            |b| {
                b.iter(|| net.mask(std::hint::black_box(&image)).expect("inference"));
            },
        );
    }
    net.input_scale = DEFAULT_INPUT_SCALE;
    // The float network the shipped 8-bit one was quantized from.
    let mut float = load(FLOAT_MODEL);
    c.bench_function(
        &format!("float network mask 640x480 at input scale {DEFAULT_INPUT_SCALE}"),
        |b| {
            b.iter(|| float.mask(std::hint::black_box(&image)).expect("inference"));
        },
    );
    // The network for painted scenes, at the scale it sees them: the
    // busy network looking once, and the shipped one, which averages it
    // over the image and its three mirror images.
    let one_look = root.join("models/cable_segmentation_busy.onnx");
    for (looks, model) in [
        ("one look", one_look.to_str().expect("a UTF-8 path")),
        ("four looks", BUSY_MODEL),
    ] {
        let mut busy = load(model);
        busy.input_scale = DEFAULT_BUSY_INPUT_SCALE;
        c.bench_function(
            &format!(
                "busy network mask 640x480 at input scale {DEFAULT_BUSY_INPUT_SCALE}, {looks}"
            ),
            |b| {
                b.iter(|| busy.mask(std::hint::black_box(&image)).expect("inference"));
            },
        );
    }
    // Image in, grasp frames out, as the cell's detector runs it (no
    // cable masks); and from cameras two and three times as fine, whose
    // images are worked on shrunk to 640 px wide
    // (`VisionConfig::work_width_px`), what is found mapped back.
    let enlarged = |k: f64| {
        let mut fine = Mat::default();
        imgproc::resize(
            &image,
            &mut fine,
            Default::default(),
            k,
            k,
            imgproc::INTER_CUBIC,
        )
        .expect("enlarging the bench image");
        fine
    };
    let mut pipeline = Pipeline::new(VisionConfig {
        mask: MaskMethod::Network,
        cable_masks: false,
        ..VisionConfig::default()
    });
    for (name, input) in [
        (
            "whole pipeline 640x480 (network mask, skeleton)",
            image.clone(),
        ),
        (
            "whole pipeline 1280x960 (worked on at 640x480)",
            enlarged(2.0),
        ),
        (
            "whole pipeline 1920x1440 (worked on at 640x480)",
            enlarged(3.0),
        ),
    ] {
        c.bench_function(name, |b| {
            b.iter(|| {
                pipeline
                    .detect(
                        std::hint::black_box(&input),
                        Some(&mut net as &mut dyn MaskNetwork),
                    )
                    .expect("detect")
            });
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
