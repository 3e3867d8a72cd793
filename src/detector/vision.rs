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
use crate::perception::vision::pipeline::grasp_order;

/// σ of the pipeline's centre line against the true one, in pixels: on
/// rendered scenes its grasp point lies 0.4 px from the truth in the
/// median, 2.4 px in the mean (docs/vision-record.md, "The same sweep on
/// rendered scenes"; docs/fusion.md).
const CENTRE_LINE_SIGMA_PX: f64 = 1.0;

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
    /// The cables in the camera's image, the most confident first (the one
    /// most like a cable: long, evenly wide), the longer of two alike.
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
            .map_err(|error| DeviceError::Vision {
                device: DeviceKind::Detector,
                source: error.into(),
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
                let centre_line =
                    to_base.centre_line(&cable.spline, cable.length_px, CENTRE_LINE_SIGMA_PX);
                let detection = CableDetection {
                    base_from_cable,
                    centre_line,
                    confidence: cable.confidence,
                };
                Some((cable.length_px, detection))
            })
            .collect();
        found.sort_by(|a, b| grasp_order(a.1.confidence, a.0, b.1.confidence, b.0));
        Ok(Detections {
            cables: found.into_iter().map(|(_, detection)| detection).collect(),
            image: Some(CameraImage(Arc::new(image))),
            skipped: output.skipped,
        })
    }
}

#[cfg(test)]
mod tests {
    use std::error::Error;
    use std::path::PathBuf;

    use nalgebra::{Isometry3, Point3, Vector3};
    use opencv::core::{CV_8UC3, Mat, Scalar};

    use super::*;
    use crate::perception::vision::calibration::CameraModel;
    use crate::perception::vision::grasp_frame::PlaneInBase;
    use crate::perception::vision::network::{NetworkError, runtime_library};
    use crate::perception::vision::{MaskMethod, VisionConfig, VisionError};

    /// A camera that sees a plain gray table.
    struct GrayCamera;

    impl Camera for GrayCamera {
        fn capture(&mut self) -> Result<Mat, DeviceError> {
            Ok(Mat::new_rows_cols_with_default(48, 64, CV_8UC3, Scalar::all(128.0)).unwrap())
        }
    }

    #[test]
    fn a_vision_failure_reaches_the_device_layer_with_its_cause() {
        let missing = PathBuf::from("/nonexistent/cable_segmentation.onnx");
        let pipeline = Pipeline::new(VisionConfig {
            mask: MaskMethod::Network,
            ..VisionConfig::default()
        });
        let network = LazyNetwork::new(missing.clone(), runtime_library(None));
        let to_base = ImageToBase {
            intrinsics: CameraModel::centred(64, 48, 1.0),
            base_from_camera: Isometry3::identity(),
            cable_plane: PlaneInBase {
                point_mm: Point3::new(0.0, 0.0, 500.0),
                normal: Vector3::z_axis(),
            },
            approach_from: Vector3::y_axis(),
            reprojection_error_px: 0.0,
        };
        let mut detector = VisionDetector::new(pipeline, network, Some(to_base));
        let error = detector.detect(&mut GrayCamera).unwrap_err();
        // The message is the vision error's, after the device's name.
        assert!(
            error
                .to_string()
                .starts_with("detector: segmentation network failed: segmentation model"),
            "{error}"
        );
        assert_eq!(error.device(), DeviceKind::Detector);
        assert_eq!(error, error.clone());
        let DeviceError::Vision { source, .. } = &error else {
            panic!("{error:?}");
        };
        match &**source {
            VisionError::Network {
                source: NetworkError::ModelMissing { path, source },
            } => {
                assert_eq!(path, &missing);
                assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
            }
            other => panic!("{other:?}"),
        }
        // The I/O error is in the chain of sources, for a reporter to walk.
        let mut cause: Option<&dyn Error> = error.source();
        let mut io_found = false;
        while let Some(c) = cause {
            io_found |= c.downcast_ref::<std::io::Error>().is_some();
            cause = c.source();
        }
        assert!(io_found, "{error:?}");
    }
}
