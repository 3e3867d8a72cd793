//! The detector's table of a cell file: the vision pipeline's settings and
//! the cable's plane, or the oracle's noise.

use std::path::PathBuf;

use nalgebra::{Point3, Unit, Vector3};
use opencv::core::Rect;
use serde::{Deserialize, Deserializer};

use crate::hw::camera::config::CalibrationConfig;
use crate::perception::vision::calibration::CameraModel;
use crate::perception::vision::grasp_frame::{ImageToBase, PlaneInBase};
use crate::perception::vision::network::{
    DEFAULT_BUSY_THRESHOLD, DEFAULT_INPUT_SCALE, DEFAULT_THRESHOLD, InputScales, LazyNetwork,
    MAX_INPUT_SCALE, input_scale_is_valid, runtime_library,
};
use crate::perception::vision::{InstanceMethod, MaskMethod, Pipeline, VisionConfig};
use crate::schema::validate::{finite, fraction, non_negative, unit_vector3, vector3};

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DetectorConfig {
    pub backend: DetectorBackend,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum DetectorBackend {
    /// Reads the simulated cable's true pose and adds noise: a stand-in
    /// for the vision pipeline, named as such.
    Oracle(OracleConfig),
    /// The vision pipeline on the camera's image (the paper's Section II);
    /// boxed, as its settings are many times the oracle's.
    Vision(Box<VisionDetectorConfig>),
}

fn default_straight_edge_radius_px() -> f64 {
    VisionConfig::default().straight_edge_radius_px
}

fn default_work_width_px() -> u32 {
    VisionConfig::default().work_width_px
}

fn default_min_confidence() -> f64 {
    VisionConfig::default().min_confidence
}

fn default_busy_threshold() -> f64 {
    f64::from(DEFAULT_BUSY_THRESHOLD)
}

fn default_net_scale() -> f64 {
    DEFAULT_INPUT_SCALE
}

fn net_scale<'de, D: Deserializer<'de>>(deserializer: D) -> Result<f64, D::Error> {
    scale_in_range("net_scale", f64::deserialize(deserializer)?)
}

fn close_net_scale<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<f64>, D::Error> {
    scale_in_range("close_net_scale", f64::deserialize(deserializer)?).map(Some)
}

fn busy_net_scale<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<f64>, D::Error> {
    scale_in_range("busy_net_scale", f64::deserialize(deserializer)?).map(Some)
}

fn scale_in_range<E: serde::de::Error>(field: &str, scale: f64) -> Result<f64, E> {
    if input_scale_is_valid(scale) {
        Ok(scale)
    } else {
        Err(E::custom(format!(
            "{field} {scale} is outside (0, {MAX_INPUT_SCALE}]"
        )))
    }
}

/// The vision detector: the pipeline's settings, and what turns a grasp
/// point in the image into a grasp frame in the base frame.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VisionDetectorConfig {
    /// `network`; `classical`; or `auto`: the classical mask on a plain
    /// background unless that mask is in doubt, else the network (faster
    /// there, less accurate).
    pub mask: MaskMethod,
    /// `skeleton` or `superpixels` (the paper's).
    pub instances: InstanceMethod,
    /// The segmentation network, relative to the cell file.
    pub model: PathBuf,
    /// A second network for the scenes whose background is painted (busy
    /// and of many colours: paint, prints, mosaics), relative to the cell
    /// file; without it `model` sees every scene.
    #[serde(default)]
    pub busy_model: Option<PathBuf>,
    /// The probability above which a pixel is cable in a painted scene,
    /// for `busy_model` (default [`DEFAULT_BUSY_THRESHOLD`], which says
    /// why).
    #[serde(default = "default_busy_threshold", deserialize_with = "fraction")]
    pub busy_threshold: f64,
    /// The ONNX Runtime library, relative to the cell file (default:
    /// `$ORT_DYLIB_PATH`, else where the set-up puts it).
    #[serde(default)]
    pub onnxruntime: Option<PathBuf>,
    /// Where the cable is expected in the image, `[x, y, width, height]`:
    /// all work is bounded to it.
    #[serde(default)]
    pub roi_px: Option<[i32; 4]>,
    /// The network's input side over the image's (default
    /// [`DEFAULT_INPUT_SCALE`]): smaller is faster, larger keeps thin
    /// cables in a small region whole.
    #[serde(default = "default_net_scale", deserialize_with = "net_scale")]
    pub net_scale: f64,
    /// The same where the background is far from one colour (paint,
    /// prints) or dark (default
    /// [`crate::perception::vision::network::DEFAULT_CLOSE_INPUT_SCALE`], or
    /// `net_scale` where that is larger;
    /// see [`InputScales`]).
    #[serde(default, deserialize_with = "close_net_scale")]
    pub close_net_scale: Option<f64>,
    /// The same for `busy_model` in a painted scene (default
    /// [`crate::perception::vision::network::DEFAULT_BUSY_INPUT_SCALE`], or
    /// `close_net_scale` where that is larger; see [`InputScales`]).
    #[serde(default, deserialize_with = "busy_net_scale")]
    pub busy_net_scale: Option<f64>,
    /// Images are worked on at this width (px), shrunk or enlarged
    /// (default [`VisionConfig::work_width_px`]; 0: at their own size).
    #[serde(default = "default_work_width_px")]
    pub work_width_px: u32,
    /// Detections straighter than an arc of this radius (px), or within
    /// 1.5 px of straight, are dropped as edges of paper and tables, on a
    /// plain background (a light's falloff aside) only when their two
    /// sides differ (default
    /// [`VisionConfig::straight_edge_radius_px`]); 0 keeps them: a cable
    /// held taut between supports is straight.
    #[serde(
        default = "default_straight_edge_radius_px",
        deserialize_with = "non_negative"
    )]
    pub straight_edge_radius_px: f64,
    /// Detections less confident than this, 0 to 1, are dropped as
    /// probably not cables (default
    /// [`crate::perception::vision::DEFAULT_MIN_CONFIDENCE`]); 0 keeps
    /// them all; 1.35 times this on a painted background. A cell that holds
    /// its one cable in a fixture may trust a fainter detection than a
    /// busy scene can.
    #[serde(default = "default_min_confidence", deserialize_with = "fraction")]
    pub min_confidence: f64,
    /// The plane the cable lies in, known from the fixture (the paper's
    /// "known distance" of the cable from the camera): a grasp point's ray
    /// from the camera meets it at the grasp point in the base frame.
    pub cable_plane: PlaneConfig,
    /// The direction, in the base frame, the hand comes from: the grasp
    /// frame's y points to this side.
    #[serde(deserialize_with = "unit_vector3")]
    pub approach_from: [f64; 3],
}

impl VisionDetectorConfig {
    /// The pipeline as the cell's detect state runs it; `cable_masks`:
    /// whether to keep each cable's mask too (the cell needs grasp frames
    /// only; a command may write the masks). `detect --cell` and `replay
    /// --vision --cell` run this, so that they find what the task found.
    pub fn pipeline(&self, cable_masks: bool) -> Pipeline {
        Pipeline::new(VisionConfig {
            mask: self.mask,
            instances: self.instances,
            roi_px: self
                .roi_px
                .map(|[x, y, width, height]| Rect::new(x, y, width, height)),
            work_width_px: self.work_width_px,
            straight_edge_radius_px: self.straight_edge_radius_px,
            min_confidence: self.min_confidence,
            cable_masks,
            ..VisionConfig::default()
        })
    }

    /// The network as the cell's detect state runs it, loaded when a scene
    /// first needs it.
    pub fn network(&self) -> LazyNetwork {
        LazyNetwork::new(
            self.model.clone(),
            runtime_library(self.onnxruntime.as_deref()),
        )
        .tuned(
            DEFAULT_THRESHOLD,
            InputScales::new(self.net_scale, self.close_net_scale, self.busy_net_scale),
        )
        .with_busy_model(self.busy_model.clone(), self.busy_threshold as f32)
    }

    /// How image points become base-frame points for a camera at
    /// `calibration`.
    pub fn image_to_base(
        &self,
        intrinsics: CameraModel,
        calibration: &CalibrationConfig,
    ) -> ImageToBase {
        ImageToBase {
            intrinsics,
            base_from_camera: calibration.base_from_camera.isometry(),
            cable_plane: PlaneInBase {
                point_mm: Point3::from(self.cable_plane.point_mm),
                normal: Unit::new_normalize(Vector3::from(self.cable_plane.normal)),
            },
            approach_from: Unit::new_normalize(Vector3::from(self.approach_from)),
            reprojection_error_px: calibration.reprojection_error_px,
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneConfig {
    #[serde(deserialize_with = "vector3")]
    pub point_mm: [f64; 3],
    #[serde(deserialize_with = "unit_vector3")]
    pub normal: [f64; 3],
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OracleConfig {
    /// σ of the grasp point's error across the cable, in the pad's plane.
    #[serde(deserialize_with = "non_negative")]
    pub position_noise_mm: f64,
    /// σ of the cable direction's error about the pad's normal.
    #[serde(deserialize_with = "non_negative")]
    pub angle_noise_rad: f64,
    /// A fixed error across the cable added to every detection: a
    /// campaign sets each trial's start offset with it.
    #[serde(default, deserialize_with = "finite")]
    pub offset_across_mm: f64,
    /// A fixed error of the cable's direction, likewise.
    #[serde(default, deserialize_with = "finite")]
    pub offset_angle_rad: f64,
}
