//! The vision pipeline's stages, per stage and whole, on a synthetic
//! 640×480 scene (three cables on a noisy table) and, when the cables-dev
//! photographs lie beside the project, on one of them (network-free: the
//! classical mask, and the instance stages on its true mask).

// The tests' scenes with known answers; the benchmark draws one of them.
#[path = "../tests/common/scenes.rs"]
#[allow(dead_code)]
mod scenes;

use std::hint::black_box;
use std::path::PathBuf;

use cablecell::perception::vision::paths::JOIN_GAP_WIDTHS;
use cablecell::perception::vision::skeleton;
use cablecell::perception::vision::spline::{BSpline, control_points_for_length};
use cablecell::perception::vision::{GroundTruth, InstanceMethod, Pipeline, VisionConfig};
use cablecell::perception::vision::{background, mask};
use criterion::{Criterion, criterion_group, criterion_main};
use opencv::imgcodecs;
use opencv::prelude::*;
use scenes::demo_scene;

fn stages(c: &mut Criterion, name: &str, image: &Mat, truth_mask: Option<&Mat>) {
    let config = VisionConfig::default();
    let background = background::background_stats(image).expect("background statistics");
    let (m, _) =
        mask::classical_mask(image, &background, config.min_blob_area_px).expect("classical mask");
    let instance_mask = truth_mask.unwrap_or(&m);
    let found = skeleton::paths_from_mask(
        instance_mask,
        None,
        false,
        config.min_cable_length_px,
        JOIN_GAP_WIDTHS,
    )
    .expect("paths");
    let mut group = c.benchmark_group(format!("vision/{name}"));
    group.bench_function("plain-background test", |b| {
        b.iter(|| background::background_stats(black_box(image)))
    });
    // Asked only for an image with a straight detection whose sides are
    // alike; off the cables' mask and a width around it.
    group.bench_function("plain-around-each-pixel test", |b| {
        b.iter(|| mask::plain_locally(black_box(image), instance_mask, found.width_px))
    });
    group.bench_function("mask (classical)", |b| {
        b.iter(|| {
            let background = background::background_stats(black_box(image))?;
            mask::classical_mask(image, &background, config.min_blob_area_px)
        })
    });
    group.bench_function("instances (skeleton)", |b| {
        b.iter(|| {
            skeleton::paths_from_mask(
                black_box(instance_mask),
                None,
                false,
                config.min_cable_length_px,
                JOIN_GAP_WIDTHS,
            )
        })
    });
    // As the pipeline runs it: crossings also pair branches by colour.
    group.bench_function("instances (skeleton, with colour)", |b| {
        b.iter(|| {
            skeleton::paths_from_mask(
                black_box(instance_mask),
                Some(image),
                false,
                config.min_cable_length_px,
                JOIN_GAP_WIDTHS,
            )
        })
    });
    group.bench_function("spline", |b| {
        b.iter(|| {
            found
                .paths
                .iter()
                .filter_map(|p| BSpline::fit(&p.points_px, control_points_for_length(p.length_px)))
                .map(|s| s.point(0.5))
                .collect::<Vec<_>>()
        })
    });
    let mut pipeline = Pipeline::new(config.clone());
    group.bench_function("instances+spline+masks (skeleton)", |b| {
        b.iter(|| pipeline.instances_from_mask(black_box(instance_mask), None))
    });
    let mut sp = Pipeline::new(VisionConfig {
        instances: InstanceMethod::Superpixels,
        ..config.clone()
    });
    group.bench_function("instances+spline+masks (superpixels)", |b| {
        b.iter(|| sp.instances_from_mask(black_box(instance_mask), None))
    });
    group.bench_function("whole pipeline (classical mask)", |b| {
        b.iter(|| pipeline.detect(black_box(image), None))
    });
    group.finish();
}

fn vision(c: &mut Criterion) {
    let scene = demo_scene(1).expect("synthetic scene");
    stages(c, "synthetic", &scene.bgr, None);

    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data/cables-dev");
    let photo = dir.join("00016.jpg");
    let Some(path) = photo.to_str().filter(|_| photo.exists()) else {
        eprintln!("skipping the photograph: {} is absent", dir.display());
        return;
    };
    let image = imgcodecs::imread(path, imgcodecs::IMREAD_COLOR).expect("photograph reads");
    let truth = GroundTruth::load(&dir, "00016").expect("ground truth loads");
    stages(c, "cables-dev-00016", &image, Some(&truth.union_mask));
}

criterion_group!(benches, vision);
criterion_main!(benches);
