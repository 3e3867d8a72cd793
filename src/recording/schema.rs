//! The recording's channels and their messages, each channel with
//! Foxglove's well-known `foxglove.*` schema where one fits, so that
//! Foxglove opens a recording, plots it and shows it in 3D as it is.
//! cablecell's own channels are JSON with a JSON schema written here; the
//! well-known schemas that only Foxglove reads (the frames, the 3D scene,
//! the images drawn for it) are protobuf, encoded and described by the
//! `foxglove` crate's types, so their schemas are Foxglove's to the byte.
//!
//! A new channel is one [`Topic`] variant, its row in [`Topic::ALL`] and
//! its schema, plus a message and a `Recorder` method that writes it.

use std::borrow::Cow;

use foxglove::Encode;
use serde::{Deserialize, Serialize};

use crate::geometry::{LineInSensor, PoseError};
use crate::perception::tactile::{Estimator, FitConfig, TAXEL_COUNT};
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
    /// The cell's frames (base, tcp, sensor, marker, camera, cable) after
    /// every step.
    Tf,
    /// The 3D scene: the pad, its taxels, the cable's shapes.
    Scene,
    /// Every Δv frame drawn as an image, a cell a taxel.
    TactileImage,
    /// The paper's wire_params node for each grasp: m, n, a, b, c, the
    /// direction, h and v.
    WireParams,
    /// What the detector found, drawn over the camera image.
    CameraAnnotations,
    /// The camera's intrinsics, with each image.
    CameraCalibration,
}

impl Topic {
    pub const ALL: [Topic; 16] = [
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
        Topic::Tf,
        Topic::Scene,
        Topic::TactileImage,
        Topic::WireParams,
        Topic::CameraAnnotations,
        Topic::CameraCalibration,
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
            Topic::Tf => "/tf",
            Topic::Scene => "/scene",
            Topic::TactileImage => "/tactile/image",
            Topic::WireParams => "/tactile/wire_params",
            Topic::CameraAnnotations => "/camera/annotations",
            Topic::CameraCalibration => "/camera/calibration",
        }
    }

    /// The channel's schema and message encoding.
    pub fn schema(self) -> ChannelSchema {
        fn protobuf<T: Encode>() -> ChannelSchema {
            // Every `foxglove::messages` type has its schema.
            let schema = T::get_schema().unwrap_or_else(|| foxglove::Schema::new("", "", &[]));
            ChannelSchema {
                name: Cow::Owned(schema.name),
                encoding: "protobuf",
                data: schema.data,
                message_encoding: "protobuf",
            }
        }
        let json = |name: &'static str, text: &'static str| ChannelSchema {
            name: Cow::Borrowed(name),
            encoding: "jsonschema",
            data: Cow::Borrowed(text.as_bytes()),
            message_encoding: "json",
        };
        match self {
            Topic::Run => json("cablecell.Run", RUN_SCHEMA),
            Topic::State => json("cablecell.Transition", TRANSITION_SCHEMA),
            Topic::Log => json("foxglove.Log", LOG_SCHEMA),
            Topic::TactileRaw => json("cablecell.TactileRaw", TACTILE_RAW_SCHEMA),
            Topic::TactileDv => json("cablecell.TactileDv", TACTILE_DV_SCHEMA),
            Topic::TactileFit => json("cablecell.TactileFit", TACTILE_FIT_SCHEMA),
            Topic::GraspPose | Topic::ArmTarget => {
                json("foxglove.PoseInFrame", POSE_IN_FRAME_SCHEMA)
            }
            Topic::CameraImage => json("foxglove.CompressedImage", COMPRESSED_IMAGE_SCHEMA),
            Topic::CableShapes => json("cablecell.CableShapes", CABLE_SHAPES_SCHEMA),
            Topic::WireParams => json("cablecell.WireParams", WIRE_PARAMS_SCHEMA),
            Topic::Tf => protobuf::<foxglove::messages::FrameTransforms>(),
            Topic::Scene => protobuf::<foxglove::messages::SceneUpdate>(),
            Topic::TactileImage => protobuf::<foxglove::messages::RawImage>(),
            Topic::CameraAnnotations => protobuf::<foxglove::messages::ImageAnnotations>(),
            Topic::CameraCalibration => protobuf::<foxglove::messages::CameraCalibration>(),
        }
    }
}

/// A channel's schema as MCAP and Foxglove's WebSocket protocol take it.
#[derive(Debug, Clone)]
pub struct ChannelSchema {
    /// `foxglove.FrameTransforms`, `cablecell.Run`, …
    pub name: Cow<'static, str>,
    /// `jsonschema` or `protobuf` (a serialized `FileDescriptorSet`).
    pub encoding: &'static str,
    pub data: Cow<'static, [u8]>,
    /// `json` or `protobuf`.
    pub message_encoding: &'static str,
}

/// Foxglove's time: seconds and nanoseconds since the Unix epoch (UTC).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Timestamp {
    pub sec: u32,
    pub nsec: u32,
}

impl Timestamp {
    /// The time `ns` nanoseconds after the epoch.
    pub fn of_ns(ns: u64) -> Self {
        Self {
            sec: u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX),
            nsec: (ns % 1_000_000_000) as u32,
        }
    }

    /// Nanoseconds since the epoch.
    pub fn ns(self) -> u64 {
        u64::from(self.sec) * 1_000_000_000 + u64::from(self.nsec)
    }
}

impl From<Timestamp> for foxglove::messages::Timestamp {
    fn from(t: Timestamp) -> Self {
        // `of_ns` keeps `nsec` below a second.
        foxglove::messages::Timestamp::new_checked(t.sec, t.nsec).unwrap_or_default()
    }
}

/// Where a recording's times start: the wall clock (UTC) when the cell's
/// clock read 0, so that log times are dates, on a simulated cell too,
/// and the cell's seconds are kept exactly as offsets from it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WallClock {
    pub cell_zero_ns: u64,
}

impl WallClock {
    /// The wall clock now, when the cell's clock reads `cell_now_s`.
    pub fn now(cell_now_s: f64) -> Self {
        let now_ns = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
        Self {
            cell_zero_ns: now_ns.saturating_sub(cell_offset_ns(cell_now_s)),
        }
    }

    /// MCAP's log time of the cell's `t_s`: nanoseconds since the epoch.
    pub fn log_time_ns(self, t_s: f64) -> u64 {
        self.cell_zero_ns.saturating_add(cell_offset_ns(t_s))
    }

    pub fn timestamp(self, t_s: f64) -> Timestamp {
        Timestamp::of_ns(self.log_time_ns(t_s))
    }
}

/// The cell's seconds as nanoseconds (never negative).
fn cell_offset_ns(t_s: f64) -> u64 {
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

impl RunMessage {
    /// The paper's fit as this plan configured it.
    pub fn fit_config(&self) -> FitConfig {
        FitConfig {
            pitch_mm: self.pitch_mm,
            contact_threshold_v: self.contact_threshold_v,
        }
    }
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
    /// The condition number of the estimate's least squares (see
    /// [`Estimate::condition`](crate::perception::tactile::Estimate::condition));
    /// absent from recordings made before it was recorded.
    #[serde(default)]
    pub condition: Option<f64>,
}

impl TactileFitMessage {
    /// The estimated line; `None` if the fit failed.
    pub fn estimate(&self) -> Option<LineInSensor> {
        self.alpha_rad
            .zip(self.n_mm)
            .map(|(a, n)| LineInSensor::new(a, n))
    }

    /// Where the cable really lay (simulated cells).
    pub fn truth(&self) -> Option<LineInSensor> {
        self.true_alpha_rad
            .zip(self.true_n_mm)
            .map(|(a, n)| LineInSensor::new(a, n))
    }
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

/// The paper's wire_params node (Section III.2) for one grasp, from the
/// grasp's mean Δv map, whichever estimator judged it; `None` where the
/// fit has no such number (no contact, a cable along y has no m and n,
/// fewer than 3 centroids no quadratic).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WireParamsMessage {
    pub timestamp: Timestamp,
    /// 0 for the trial grasp, k for the k-th regrasp.
    pub attempt: u32,
    /// `horizontal` (`y = m x + n`, `y = a x² + b x + c`) or `vertical`
    /// (`x = a y² + b y + c`).
    pub direction: Option<String>,
    /// eq. 2's slope and intercept (mm).
    pub m: Option<f64>,
    pub n_mm: Option<f64>,
    /// eq. 3 / 4's coefficients: `a` in 1/mm, `b` none, `c` in mm.
    pub a_per_mm: Option<f64>,
    pub b: Option<f64>,
    pub c_mm: Option<f64>,
    /// The smallest column and row sums of Δv (V).
    pub h_v: Option<f64>,
    pub v_v: Option<f64>,
    /// Why there are none, when the fit failed.
    pub error: Option<String>,
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
    r#""attempt":{"type":"integer"},"estimator":{"type":"string"},"map_dv_v":{"type":"array","items":{"type":"number"},"minItems":25,"maxItems":25},"peak_dv_v":{"type":"number"},"n_mm":{"type":["number","null"]},"alpha_rad":{"type":["number","null"]},"error_n_mm":{"type":["number","null"]},"error_alpha_rad":{"type":["number","null"]},"true_n_mm":{"type":["number","null"]},"true_alpha_rad":{"type":["number","null"]},"centroids_mm":{"type":"array","items":{"type":"array","items":{"type":"number"},"minItems":2,"maxItems":2}},"condition":{"type":["number","null"]}"#
);
const POSE_IN_FRAME_SCHEMA: &str = schema!(
    "foxglove.PoseInFrame",
    r#""frame_id":{"type":"string"},"pose":{"title":"foxglove.Pose","type":"object","properties":{"position":{"title":"foxglove.Vector3","type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}},"orientation":{"title":"foxglove.Quaternion","type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"},"w":{"type":"number"}}}}}"#
);

const COMPRESSED_IMAGE_SCHEMA: &str = schema!(
    "foxglove.CompressedImage",
    r#""frame_id":{"type":"string"},"data":{"type":"string","contentEncoding":"base64"},"format":{"type":"string"}"#
);

const WIRE_PARAMS_SCHEMA: &str = schema!(
    "cablecell.WireParams",
    r#""attempt":{"type":"integer"},"direction":{"type":["string","null"],"enum":["horizontal","vertical",null]},"m":{"type":["number","null"]},"n_mm":{"type":["number","null"]},"a_per_mm":{"type":["number","null"]},"b":{"type":["number","null"]},"c_mm":{"type":["number","null"]},"h_v":{"type":["number","null"]},"v_v":{"type":["number","null"]},"error":{"type":["string","null"]}"#
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
            let channel = topic.schema();
            let name = &channel.name;
            if channel.encoding == "protobuf" {
                assert!(name.starts_with("foxglove."), "{name}");
                assert!(!channel.data.is_empty(), "{name}");
                continue;
            }
            let schema: serde_json::Value =
                serde_json::from_slice(&channel.data).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(schema["title"], name.as_ref());
            assert_eq!(schema["properties"]["timestamp"], time, "{name}");
        }
    }

    #[test]
    fn a_fit_recorded_before_its_condition_number_reads_without_it() {
        let old = r#"{"timestamp":{"sec":1,"nsec":0},"attempt":0,"estimator":"ridge",
            "map_dv_v":[0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0],"peak_dv_v":0,
            "n_mm":null,"alpha_rad":null,"error_n_mm":null,"error_alpha_rad":null,
            "true_n_mm":null,"true_alpha_rad":null,"centroids_mm":[]}"#;
        let message: TactileFitMessage = serde_json::from_str(old).unwrap();
        assert_eq!(message.condition, None);
    }

    #[test]
    fn topic_names_are_distinct() {
        let names: std::collections::BTreeSet<_> = Topic::ALL.iter().map(|t| t.name()).collect();
        assert_eq!(names.len(), Topic::ALL.len());
    }

    #[test]
    fn timestamps_are_the_wall_clock_plus_the_cell_clock() {
        let clock = WallClock {
            cell_zero_ns: 1_700_000_000_000_000_000,
        };
        assert_eq!(
            clock.timestamp(3.25),
            Timestamp {
                sec: 1_700_000_003,
                nsec: 250_000_000
            }
        );
        assert_eq!(clock.timestamp(3.25).ns(), clock.log_time_ns(3.25));
        assert_eq!(clock.log_time_ns(-1.0), clock.cell_zero_ns);
        let now = WallClock::now(10.0);
        assert!(now.timestamp(10.0).sec > 1_600_000_000, "{now:?}");
    }
}
