//! The detect state on the simulated cell: the camera's capture (rendering
//! the scene), the vision pipeline with the network in the cable's region
//! of interest, and the grasp frame placed in the base frame; and the
//! capture alone, to tell the renderer's share from the pipeline's.

use std::hint::black_box;
use std::path::Path;

use cablecell::cell::CellDevices;
use cablecell::cell::load_cell;
use criterion::{Criterion, criterion_group, criterion_main};

fn detector(c: &mut Criterion) {
    let file = load_cell(&Path::new(env!("CARGO_MANIFEST_DIR")).join("config/cell.sim.toml"))
        .expect("the shipped simulated cell");
    let mut cell = CellDevices::build(&file, 1).expect("the simulated cell builds");
    // The first detection loads the network.
    cell.detector
        .detect(cell.camera.as_mut())
        .expect("the vision detector runs");
    let mut group = c.benchmark_group("detector/simulated cell");
    group.sample_size(20);
    group.bench_function("capture (render 640×480)", |b| {
        b.iter(|| black_box(cell.camera.capture().expect("capture")))
    });
    group.bench_function("detect (capture + pipeline + base frame)", |b| {
        b.iter(|| black_box(cell.detector.detect(cell.camera.as_mut()).expect("detect")))
    });
    group.finish();
}

criterion_group!(benches, detector);
criterion_main!(benches);
