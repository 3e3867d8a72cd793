//! The cell file: which backend each device uses, with its limits and
//! calibration. `config/cell.sim.toml` is the simulated cell. Each table's
//! type lives beside the device that reads it; this file gathers them.

use std::path::Path;

use serde::Deserialize;

use crate::detector::config::{DetectorBackend, DetectorConfig};
use crate::hw::arm::config::ArmConfig;
use crate::hw::camera::config::{CameraBackend, CameraConfig, CameraSource};
use crate::hw::gripper::config::GripperConfig;
use crate::hw::tactile::config::TactileConfig;
use crate::sim::world::WorldConfig;

/// A cell file, e.g. `config/cell.sim.toml`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CellFile {
    pub cell: CellSection,
    pub arm: ArmConfig,
    pub gripper: GripperConfig,
    pub tactile: TactileConfig,
    /// The 2D camera that watches the cable, and the marker on the finger
    /// that calibrates it.
    pub camera: CameraConfig,
    pub detector: DetectorConfig,
    /// The simulated scene that the simulated devices share.
    pub world: WorldConfig,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CellSection {
    pub name: String,
    #[serde(default)]
    pub description: String,
}

impl CellFile {
    /// Makes the file's paths relative to `dir`, the cell file's folder.
    pub fn resolve_paths(&mut self, dir: &Path) {
        if let DetectorBackend::Vision(vision) = &mut self.detector.backend {
            vision.model = dir.join(&vision.model);
            if let Some(busy_model) = &mut vision.busy_model {
                *busy_model = dir.join(&*busy_model);
            }
            if let Some(library) = &mut vision.onnxruntime {
                *library = dir.join(&*library);
            }
        }
        if let CameraBackend::Opencv(camera) = &mut self.camera.backend {
            match &mut camera.source {
                CameraSource::Video(path) | CameraSource::Folder(path) => *path = dir.join(&*path),
                CameraSource::Device(_) => {}
            }
        }
    }
}
