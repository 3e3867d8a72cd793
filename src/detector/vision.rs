//! The vision detector: the paper's Section II on the cell's camera. The
//! pipeline finds every cable in the image; each cable's grasp frame at
//! s = 0.5 is placed in the base frame through the calibrated camera pose
//! and the cable's known plane.

use std::sync::Arc;

use super::{CableDetection, CableDetector, Detections};
use crate::hw::camera::{Camera, CameraImage};
use crate::hw::{DeviceError, DeviceKind};
use crate::perception::vision::Pipeline;
use crate::perception::vision::grasp_frame::ImageToBase;
use crate::perception::vision::network::LazyNetwork;

pub struct VisionDetector {
    pipeline: Pipeline,
    network: LazyNetwork,
    /// `None` until the camera is calibrated.
    to_base: Option<ImageToBase>,
}

impl VisionDetector {
    pub fn new(pipeline: Pipeline, network: LazyNetwork, to_base: Option<ImageToBase>) -> Self {
        Self {
            pipeline,
            network,
            to_base,
        }
    }
}

impl CableDetector for VisionDetector {
    /// The cables in the camera's image, the longest in view first (the
    /// one least likely to be a scrap of clutter).
    fn detect(&mut self, camera: &mut dyn Camera) -> Result<Detections, DeviceError> {
        let Some(to_base) = self.to_base else {
            return Err(DeviceError::Unusable {
                device: DeviceKind::Detector,
                reason: "the camera is not calibrated: run `cablecell calibrate-camera`".to_owned(),
            });
        };
        let image = camera.capture()?;
        let output = self
            .pipeline
            .detect(&image, Some(&mut self.network))
            .map_err(|error| DeviceError::Unusable {
                device: DeviceKind::Detector,
                reason: error.to_string(),
            })?;
        tracing::debug!(
            mask = ?output.mask_used,
            cables = output.cables.len(),
            timings_ms = ?output.timings_ms,
            "vision"
        );
        for note in &output.notes {
            tracing::warn!(note = note.as_str(), "vision");
        }
        let mut found: Vec<(f64, CableDetection)> = output
            .cables
            .iter()
            .filter_map(|cable| {
                let base_from_cable = to_base.base_from_cable(&cable.spline)?;
                Some((cable.length_px, CableDetection { base_from_cable }))
            })
            .collect();
        found.sort_by(|a, b| b.0.total_cmp(&a.0));
        Ok(Detections {
            cables: found.into_iter().map(|(_, detection)| detection).collect(),
            image: Some(CameraImage(Arc::new(image))),
        })
    }
}
