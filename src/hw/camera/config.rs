//! The camera's table of a cell file: its intrinsics, the marker on the
//! finger that calibrates it, its calibrated pose, and where its images
//! come from.

use std::path::PathBuf;

use opencv::aruco::PREDEFINED_DICTIONARY_NAME;
use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

use crate::perception::vision::calibration::{CameraModel, MarkerOnFinger};
use crate::schema::FrameConfig;
use crate::schema::validate::{non_negative, positive};
use crate::sim::render::{Appearance, Background};

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

impl MarkerDictionary {
    /// How many markers the dictionary holds: their ids run from 0.
    pub fn marker_count(self) -> i32 {
        match self {
            MarkerDictionary::Aruco4x4_50 => 50,
            MarkerDictionary::Aruco5x5_100 => 100,
            MarkerDictionary::Aruco6x6_250 => 250,
            MarkerDictionary::ArucoOriginal => 1024,
        }
    }
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
}

impl SimCameraConfig {
    /// How the simulated scene looks: this file's background, cable colour,
    /// noise and blur under the renderer's default light.
    pub fn appearance(&self) -> Appearance {
        Appearance {
            background: self.background.clone(),
            cable_bgr: self.cable_bgr,
            noise_sigma: self.noise_sigma,
            blur_sigma_px: self.blur_sigma_px,
            ..Appearance::default()
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
