//! The camera's table of a cell file: its intrinsics, the marker on the
//! finger that calibrates it, its calibrated pose, and where its images
//! come from.

use std::path::PathBuf;

use opencv::aruco::PREDEFINED_DICTIONARY_NAME;
use rand::{Rng, RngExt};
use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

use crate::perception::vision::calibration::{CameraModel, MarkerOnFinger};
use crate::schema::FrameConfig;
use crate::schema::validate::{fraction, non_negative, positive, some_fraction};
use crate::sim::render::{Appearance, Background, Board, Occlusion};

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraConfig {
    /// The camera's intrinsics (pinhole, no distortion; pixel centres at
    /// integer coordinates).
    #[serde(deserialize_with = "camera_model")]
    pub intrinsics: CameraModel,
    pub marker: MarkerConfig,
    /// Where `cablecell calibrate-camera` puts the arm to show the marker
    /// to the camera: poses of the TCP in the base frame, spread in
    /// position, depth and angle (more than one pin down the marker's
    /// tilt).
    pub calibration_poses: Vec<FrameConfig>,
    /// The camera's pose as `cablecell calibrate-camera` estimated it; the
    /// vision detector needs it.
    #[serde(default)]
    pub calibration: Option<CalibrationConfig>,
    pub backend: CameraBackend,
}

/// A camera's intrinsics: a positive image size and focal lengths, a
/// finite principal point.
fn camera_model<'de, D: Deserializer<'de>>(d: D) -> Result<CameraModel, D::Error> {
    let model = CameraModel::deserialize(d)?;
    if model.is_valid() {
        Ok(model)
    } else {
        Err(D::Error::custom(
            "expected a positive image size and focal lengths and a finite principal point",
        ))
    }
}

/// The ArUco marker fixed on one finger.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MarkerConfig {
    pub dictionary: MarkerDictionary,
    pub id: i32,
    /// The side of the marker's black square.
    #[serde(deserialize_with = "positive")]
    pub side_mm: f64,
    /// Where the marker sits on the hand (its centre, z out of its face).
    pub tcp_from_marker: FrameConfig,
}

impl MarkerConfig {
    pub fn on_finger(&self) -> MarkerOnFinger {
        MarkerOnFinger {
            dictionary: match self.dictionary {
                MarkerDictionary::Aruco4x4_50 => PREDEFINED_DICTIONARY_NAME::DICT_4X4_50,
                MarkerDictionary::Aruco5x5_100 => PREDEFINED_DICTIONARY_NAME::DICT_5X5_100,
                MarkerDictionary::Aruco6x6_250 => PREDEFINED_DICTIONARY_NAME::DICT_6X6_250,
                MarkerDictionary::ArucoOriginal => PREDEFINED_DICTIONARY_NAME::DICT_ARUCO_ORIGINAL,
            },
            id: self.id,
            side_mm: self.side_mm,
            tcp_from_marker: self.tcp_from_marker.isometry(),
        }
    }
}

/// The ArUco dictionaries a marker may come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum MarkerDictionary {
    #[serde(rename = "4x4_50")]
    Aruco4x4_50,
    #[serde(rename = "5x5_100")]
    Aruco5x5_100,
    #[serde(rename = "6x6_250")]
    Aruco6x6_250,
    #[serde(rename = "original")]
    ArucoOriginal,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationConfig {
    pub base_from_camera: FrameConfig,
    /// How well the marker's corners fitted the pose (RMS, pixels).
    #[serde(deserialize_with = "non_negative")]
    pub reprojection_error_px: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum CameraBackend {
    /// Renders the simulated world (see `sim::render`).
    Sim(SimCameraConfig),
    /// A real camera, a video file or a folder of images, read through
    /// OpenCV.
    Opencv(OpencvCameraConfig),
}

/// The simulated camera: where it really is, and how the scene looks.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimCameraConfig {
    /// The camera's true pose, which calibration has to find.
    pub base_from_camera: FrameConfig,
    /// What the cable hangs in front of: `"gradient"`, `"noise"`,
    /// `"stripes"`, `"checker"`, `"wood"`, `"printed"` or
    /// `{ plain = { bgr = [b, g, r] } }`.
    pub background: Background,
    pub cable_bgr: [u8; 3],
    /// Sensor noise, gray levels (σ).
    #[serde(deserialize_with = "non_negative")]
    pub noise_sigma: f64,
    /// Optical blur, pixels (σ).
    #[serde(deserialize_with = "non_negative")]
    pub blur_sigma_px: f64,
    /// What hides the cable from the camera; none when absent.
    #[serde(default)]
    pub occlusion: Option<OcclusionConfig>,
}

impl SimCameraConfig {
    /// How the simulated scene looks: this file's background, cable colour,
    /// noise, blur and occlusion under the renderer's default light. A
    /// board's position along the cable, when the file does not fix it, and
    /// its texture are drawn from `camera_stream` (the cell's camera
    /// stream, so a seed places it, the same for every policy of a
    /// campaign's trial); nothing is drawn when nothing is hidden.
    pub fn appearance(&self, camera_stream: &mut impl Rng) -> Appearance {
        Appearance {
            background: self.background.clone(),
            cable_bgr: self.cable_bgr,
            noise_sigma: self.noise_sigma,
            blur_sigma_px: self.blur_sigma_px,
            occlusion: self
                .occlusion
                .as_ref()
                .map_or_else(Occlusion::default, |o| o.placed(camera_stream)),
            ..Appearance::default()
        }
    }
}

/// `[camera.backend.sim.occlusion]`: a board lying over a stretch of the
/// cable, and the arm's hand in view.
#[derive(Debug, Clone, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OcclusionConfig {
    /// The share of the cable's length in the image the board hides, 0
    /// (no board) to 1 (all of it).
    #[serde(deserialize_with = "fraction")]
    pub hidden_fraction: f64,
    /// Where along the cable the hidden stretch lies, 0 (from its start,
    /// the left end in the image) to 1 (up to its end); drawn per seed
    /// when absent.
    #[serde(deserialize_with = "some_fraction")]
    pub position: Option<f64>,
    /// The board's colour.
    pub bgr: [u8; 3],
    /// The arm's hand (fingers, the gripper's housing, the wrist) drawn
    /// where the TCP is, covering the cable as it comes down over it.
    pub arm_in_view: bool,
}

impl Default for OcclusionConfig {
    /// Nothing hidden: a pale cardboard board, were it given a share.
    fn default() -> Self {
        Self {
            hidden_fraction: 0.0,
            position: None,
            bgr: [150, 175, 195],
            arm_in_view: false,
        }
    }
}

impl OcclusionConfig {
    /// The occlusion with its board placed: its position drawn from `rng`
    /// unless fixed, then its texture's seed; no board, and nothing drawn,
    /// when it hides nothing.
    fn placed(&self, rng: &mut impl Rng) -> Occlusion {
        let board = (self.hidden_fraction > 0.0).then(|| Board {
            hidden_fraction: self.hidden_fraction,
            position: self.position.unwrap_or_else(|| rng.random_range(0.0..=1.0)),
            bgr: self.bgr,
            texture_seed: rng.random(),
        });
        Occlusion {
            board,
            arm_in_view: self.arm_in_view,
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpencvCameraConfig {
    pub source: CameraSource,
}

/// Where a real camera's images come from.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum CameraSource {
    /// A capture device, e.g. 0 for /dev/video0.
    Device(i32),
    /// A video file, read frame by frame.
    Video(PathBuf),
    /// A folder of images, read in name order, one per capture.
    Folder(PathBuf),
}
