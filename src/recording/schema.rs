//! The recording's channels and their messages: JSON, each channel with a
//! JSON schema, Foxglove's well-known `foxglove.*` schemas where one fits,
//! so that Foxglove opens a recording and plots it as it is.
//!
//! A new channel is one [`Topic`] variant, its row in [`Topic::ALL`] and
//! its schema text, plus a message struct and a `Recorder` method that
//! writes it.

use serde::{Deserialize, Serialize};

use crate::geometry::{LineInSensor, PoseError};
use crate::perception::tactile::{Estimator, TAXEL_COUNT};
use crate::record::GraspShapes;

/// Every channel a recording may hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Topic {
    /// The task, cell, seed and what a replay needs to fit again.
    Run,
    /// Each state transition.
    State,
    /// Transitions, grasps and the outcome as log lines.
    Log,
    /// Every tactile frame as the sensor sent it: 12-bit counts.
    TactileRaw,
    /// Every tactile frame read after the bias frames, bias removed.
    TactileDv,
    /// Each grasp's mean map, fit, error and (simulated cells) truth.
    TactileFit,
    /// The arm's measured pose at each grasp.
    GraspPose,
    /// Each pose the machine sends the arm to.
    ArmTarget,
    /// Each image the vision detector looked at, as PNG.
    CameraImage,
    /// Each grasp's cable shapes: seen, felt, fused and true.
    CableShapes,
}

impl Topic {
    pub const ALL: [Topic; 10] = [
        Topic::Run,
        Topic::State,
        Topic::Log,
        Topic::TactileRaw,
        Topic::TactileDv,
        Topic::TactileFit,
        Topic::GraspPose,
        Topic::ArmTarget,
        Topic::CameraImage,
        Topic::CableShapes,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Topic::Run => "/run",
            Topic::State => "/state",
            Topic::Log => "/log",
            Topic::TactileRaw => "/tactile/raw",
            Topic::TactileDv => "/tactile/dv",
            Topic::TactileFit => "/tactile/fit",
            Topic::GraspPose => "/arm/grasp_pose",
            Topic::ArmTarget => "/arm/target",
            Topic::CameraImage => "/camera/image",
            Topic::CableShapes => "/cable/shapes",
        }
    }

    /// The schema's name and its JSON schema.
    pub fn schema(self) -> (&'static str, &'static str) {
        match self {
            Topic::Run => ("cablecell.Run", RUN_SCHEMA),
            Topic::State => ("cablecell.Transition", TRANSITION_SCHEMA),
            Topic::Log => ("foxglove.Log", LOG_SCHEMA),
            Topic::TactileRaw => ("cablecell.TactileRaw", TACTILE_RAW_SCHEMA),
            Topic::TactileDv => ("cablecell.TactileDv", TACTILE_DV_SCHEMA),
            Topic::TactileFit => ("cablecell.TactileFit", TACTILE_FIT_SCHEMA),
            Topic::GraspPose | Topic::ArmTarget => ("foxglove.PoseInFrame", POSE_IN_FRAME_SCHEMA),
            Topic::CameraImage => ("foxglove.CompressedImage", COMPRESSED_IMAGE_SCHEMA),
            Topic::CableShapes => ("cablecell.CableShapes", CABLE_SHAPES_SCHEMA),
        }
    }
}

/// Foxglove's time: seconds and nanoseconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Timestamp {
    pub sec: u32,
    pub nsec: u32,
}

impl Timestamp {
    /// The cell's clock (seconds since the cell started; never negative).
    pub fn of(t_s: f64) -> Self {
        let ns = log_time_ns(t_s);
        Self {
            sec: u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX),
            nsec: (ns % 1_000_000_000) as u32,
        }
    }
}

/// MCAP's log time: nanoseconds on the cell's clock.
pub fn log_time_ns(t_s: f64) -> u64 {
    (t_s.max(0.0) * 1e9).round() as u64
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunMessage {
    pub timestamp: Timestamp,
    pub task: String,
    pub cell: String,
    pub seed: u64,
    pub target: LineInSensor,
    pub tolerance: PoseError,
    pub estimator: Estimator,
    pub pitch_mm: f64,
    pub contact_threshold_v: f64,
    pub bias_frames: usize,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TransitionMessage {
    pub timestamp: Timestamp,
    pub from: String,
    pub to: String,
    pub t_s: f64,
}

/// `foxglove.Log`; `level` 2 is INFO, 3 WARNING, 4 ERROR.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LogMessage {
    pub timestamp: Timestamp,
    pub level: u8,
    pub message: String,
    pub name: String,
    pub file: String,
    pub line: u32,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TactileRawMessage {
    pub timestamp: Timestamp,
    /// The state whose command read the frame: `prepare` for bias frames.
    pub state: String,
    /// Row-major c11..c55.
    pub counts: [u16; TAXEL_COUNT],
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TactileDvMessage {
    pub timestamp: Timestamp,
    pub state: String,
    /// Row-major c11..c55, volts.
    pub dv_v: [f64; TAXEL_COUNT],
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TactileFitMessage {
    pub timestamp: Timestamp,
    /// 0 for the trial grasp, k for the k-th regrasp.
    pub attempt: u32,
    pub estimator: Estimator,
    /// Mean Δv over the evaluated frames, row-major, volts.
    pub map_dv_v: [f64; TAXEL_COUNT],
    pub peak_dv_v: f64,
    /// The estimate; `None` if the fit failed.
    pub n_mm: Option<f64>,
    pub alpha_rad: Option<f64>,
    /// The estimate against the target.
    pub error_n_mm: Option<f64>,
    pub error_alpha_rad: Option<f64>,
    /// Where the cable really lay (simulated cells).
    pub true_n_mm: Option<f64>,
    pub true_alpha_rad: Option<f64>,
    /// The paper's centroids (x, y in mm), when that estimator ran.
    pub centroids_mm: Vec<[f64; 2]>,
}

/// A grasp's shapes of the cable (see [`GraspShapes`]), points in mm in
/// the base frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CableShapesMessage {
    pub timestamp: Timestamp,
    /// 0 for the trial grasp, k for the k-th regrasp.
    pub attempt: u32,
    #[serde(flatten)]
    pub shapes: GraspShapes,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub position: Vector3,
    pub orientation: Quaternion,
}

/// `foxglove.PoseInFrame`: positions in metres, as Foxglove expects.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseInFrameMessage {
    pub timestamp: Timestamp,
    pub frame_id: String,
    pub pose: Pose,
}

/// `foxglove.CompressedImage`: the image file's bytes (base64 in JSON, as
/// Foxglove reads bytes there) and its format.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompressedImageMessage {
    pub timestamp: Timestamp,
    pub frame_id: String,
    #[serde(with = "base64_bytes")]
    pub data: Vec<u8>,
    pub format: String,
}

mod base64_bytes {
    use base64::Engine;
    use base64::engine::general_purpose::STANDARD;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(bytes: &[u8], serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(&STANDARD.encode(bytes))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Vec<u8>, D::Error> {
        let text = String::deserialize(deserializer)?;
        STANDARD.decode(text).map_err(serde::de::Error::custom)
    }
}

macro_rules! schema {
    ($title:literal, $props:expr) => {
        concat!(
            r#"{"title":""#,
            $title,
            r#"","type":"object","properties":{"timestamp":{"type":"object","title":"time","properties":{"sec":{"type":"integer","minimum":0},"nsec":{"type":"integer","minimum":0,"maximum":999999999}}},"#,
            $props,
            "}}"
        )
    };
}

const RUN_SCHEMA: &str = schema!(
    "cablecell.Run",
    r#""task":{"type":"string"},"cell":{"type":"string"},"seed":{"type":"integer"},"target":{"type":"object","properties":{"alpha_rad":{"type":"number"},"n_mm":{"type":"number"}}},"tolerance":{"type":"object","properties":{"n_mm":{"type":"number"},"alpha_rad":{"type":"number"}}},"estimator":{"type":"string"},"pitch_mm":{"type":"number"},"contact_threshold_v":{"type":"number"},"bias_frames":{"type":"integer"}"#
);
const TRANSITION_SCHEMA: &str = schema!(
    "cablecell.Transition",
    r#""from":{"type":"string"},"to":{"type":"string"},"t_s":{"type":"number"}"#
);
const LOG_SCHEMA: &str = schema!(
    "foxglove.Log",
    r#""level":{"title":"foxglove.LogLevel","type":"integer","oneOf":[{"title":"UNKNOWN","const":0},{"title":"DEBUG","const":1},{"title":"INFO","const":2},{"title":"WARNING","const":3},{"title":"ERROR","const":4},{"title":"FATAL","const":5}]},"message":{"type":"string"},"name":{"type":"string"},"file":{"type":"string"},"line":{"type":"integer","minimum":0}"#
);
const TACTILE_RAW_SCHEMA: &str = schema!(
    "cablecell.TactileRaw",
    r#""state":{"type":"string"},"counts":{"type":"array","items":{"type":"integer","minimum":0,"maximum":4095},"minItems":25,"maxItems":25}"#
);
const TACTILE_DV_SCHEMA: &str = schema!(
    "cablecell.TactileDv",
    r#""state":{"type":"string"},"dv_v":{"type":"array","items":{"type":"number"},"minItems":25,"maxItems":25}"#
);
const TACTILE_FIT_SCHEMA: &str = schema!(
    "cablecell.TactileFit",
    r#""attempt":{"type":"integer"},"estimator":{"type":"string"},"map_dv_v":{"type":"array","items":{"type":"number"},"minItems":25,"maxItems":25},"peak_dv_v":{"type":"number"},"n_mm":{"type":["number","null"]},"alpha_rad":{"type":["number","null"]},"error_n_mm":{"type":["number","null"]},"error_alpha_rad":{"type":["number","null"]},"true_n_mm":{"type":["number","null"]},"true_alpha_rad":{"type":["number","null"]},"centroids_mm":{"type":"array","items":{"type":"array","items":{"type":"number"},"minItems":2,"maxItems":2}}"#
);
const POSE_IN_FRAME_SCHEMA: &str = schema!(
    "foxglove.PoseInFrame",
    r#""frame_id":{"type":"string"},"pose":{"title":"foxglove.Pose","type":"object","properties":{"position":{"title":"foxglove.Vector3","type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}},"orientation":{"title":"foxglove.Quaternion","type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"},"w":{"type":"number"}}}}}"#
);

const COMPRESSED_IMAGE_SCHEMA: &str = schema!(
    "foxglove.CompressedImage",
    r#""frame_id":{"type":"string"},"data":{"type":"string","contentEncoding":"base64"},"format":{"type":"string"}"#
);

/// A shape: points along the cable in the base frame (mm), each with its σ.
macro_rules! shape_schema {
    () => {
        r#"{"type":["array","null"],"items":{"type":"object","properties":{"in_base_mm":{"type":"array","items":{"type":"number"},"minItems":3,"maxItems":3},"sigma_mm":{"type":"number"}}}}"#
    };
}
/// A shape's distances to the true cable.
macro_rules! stretch_schema {
    () => {
        r#"{"type":["object","null"],"properties":{"grasped":{"type":["object","null"],"properties":{"mean_mm":{"type":"number"},"max_mm":{"type":"number"}}},"beyond":{"type":["object","null"],"properties":{"mean_mm":{"type":"number"},"max_mm":{"type":"number"}}}}}"#
    };
}
const CABLE_SHAPES_SCHEMA: &str = schema!(
    "cablecell.CableShapes",
    concat!(
        r#""attempt":{"type":"integer"},"base_from_sensor":{"type":"object","properties":{"translation_mm":{"type":"array","items":{"type":"number"},"minItems":3,"maxItems":3},"rotation_xyzw":{"type":"array","items":{"type":"number"},"minItems":4,"maxItems":4}}},"pad_half_side_mm":{"type":"number"},"vision":"#,
        shape_schema!(),
        r#","tactile_linear":"#,
        shape_schema!(),
        r#","tactile_quadratic":"#,
        shape_schema!(),
        r#","tactile_ridge":"#,
        shape_schema!(),
        r#","fused_from":{"type":["string","null"],"enum":["linear","quadratic","ridge",null]},"fused":"#,
        shape_schema!(),
        r#","truth_in_base_mm":{"type":["array","null"],"items":{"type":"array","items":{"type":"number"},"minItems":3,"maxItems":3}},"errors":{"type":["object","null"],"properties":{"beyond_mm":{"type":"number"},"vision":"#,
        stretch_schema!(),
        r#","tactile_linear":"#,
        stretch_schema!(),
        r#","tactile_quadratic":"#,
        stretch_schema!(),
        r#","tactile_ridge":"#,
        stretch_schema!(),
        r#","fused":"#,
        stretch_schema!(),
        "}}"
    )
);

#[cfg(test)]
mod tests {
    use super::*;

    const TIME: &str = r#"{"type":"object","title":"time","properties":{"sec":{"type":"integer","minimum":0},"nsec":{"type":"integer","minimum":0,"maximum":999999999}}}"#;

    #[test]
    fn every_schema_is_json_with_a_timestamp() {
        let time: serde_json::Value = serde_json::from_str(TIME).unwrap();
        for topic in Topic::ALL {
            let (name, text) = topic.schema();
            let schema: serde_json::Value =
                serde_json::from_str(text).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(schema["title"], name);
            assert_eq!(schema["properties"]["timestamp"], time, "{name}");
        }
    }

    #[test]
    fn topic_names_are_distinct() {
        let names: std::collections::BTreeSet<_> = Topic::ALL.iter().map(|t| t.name()).collect();
        assert_eq!(names.len(), Topic::ALL.len());
    }

    #[test]
    fn timestamps_split_seconds() {
        assert_eq!(
            Timestamp::of(3.25),
            Timestamp {
                sec: 3,
                nsec: 250_000_000
            }
        );
        assert_eq!(Timestamp::of(-1.0), Timestamp { sec: 0, nsec: 0 });
    }
}
