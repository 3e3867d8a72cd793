//! The cell the orchestrator's unit tests run on: the shipped simulated
//! cell with an oracle detector that misses by σ = 3 mm and 0.2 rad, so
//! that trial grasps land a few millimetres off, as in the paper, and
//! regrasps happen (the vision detector rarely leaves one to do).

use crate::cell::CellFile;
use crate::cell::load_cell;
use crate::detector::config::{DetectorBackend, OracleConfig};

pub fn sim_cell_with_oracle() -> CellFile {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut cell = load_cell(&root.join("config/cell.sim.toml")).expect("the shipped cell");
    cell.detector.backend = DetectorBackend::Oracle(OracleConfig {
        position_noise_mm: 3.0,
        angle_noise_rad: 0.2,
        offset_across_mm: 0.0,
        offset_angle_rad: 0.0,
    });
    cell
}
