//! The cell file: which backend each device uses, with its limits and
//! calibration. `config/cell.sim.toml` is the simulated cell.

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use opencv::aruco::PREDEFINED_DICTIONARY_NAME;
use opencv::core::Rect;
use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

use crate::hw::arm::WorkspaceBox;
use crate::hw::emulator::Fault;
use crate::hw::gripper::pg70_emulator as pg70;
use crate::hw::tactile::remodel_emulator as tactile;
use crate::perception::tactile::TAXEL_COUNT;
use crate::perception::vision::network::{
    DEFAULT_INPUT_SCALE, MAX_INPUT_SCALE, input_scale_is_valid,
};

use crate::perception::vision::calibration::{CameraModel, MarkerOnFinger};
use crate::perception::vision::grasp_frame::{ImageToBase, PlaneInBase};
use crate::perception::vision::{InstanceMethod, MaskMethod, VisionConfig};
use crate::sim::render::{Appearance, Background};
use crate::task::validate::{
    camera_model, finite, fraction, non_negative, positive, unit_vector3, vector3, voltage_range,
};

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

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmConfig {
    /// No Cartesian motion may be faster.
    #[serde(deserialize_with = "positive")]
    pub max_speed_mm_s: f64,
    /// No move may end outside this box (the TCP in the base frame),
    /// whatever asks for it.
    #[serde(deserialize_with = "workspace_box")]
    pub workspace: WorkspaceBox,
    pub backend: ArmBackend,
}

/// A box whose every `min_mm` is finite and below its `max_mm`.
fn workspace_box<'de, D: Deserializer<'de>>(d: D) -> Result<WorkspaceBox, D::Error> {
    let workspace = WorkspaceBox::deserialize(d)?;
    let ordered = (0..3).all(|axis| {
        let (min, max) = (workspace.min_mm[axis], workspace.max_mm[axis]);
        min.is_finite() && max.is_finite() && min < max
    });
    if ordered {
        Ok(workspace)
    } else {
        Err(D::Error::custom(format!(
            "expected finite min_mm below max_mm on every axis, found {:?}..{:?}",
            workspace.min_mm, workspace.max_mm
        )))
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum ArmBackend {
    Sim(SimArmConfig),
    /// A Franka Panda through `franka_rust` (the `panda` cargo feature).
    #[cfg(feature = "panda")]
    Panda(PandaArmConfig),
    /// Refused while loading: this build has no Panda driver.
    #[cfg(not(feature = "panda"))]
    Panda(PandaNotBuilt),
}

/// A real Franka Panda, reached over its FCI network link.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PandaArmConfig {
    /// The controller's host name or IP address (the FCI link, e.g.
    /// 172.16.0.2); the ports are the protocol's.
    #[serde(deserialize_with = "host")]
    pub address: String,
    /// The cell's TCP (between the fingertips) in the end-effector frame
    /// the controller reports (`EE`, as configured in Desk for the hand).
    pub ee_from_tcp: FrameConfig,
    /// The fraction of the Panda's Cartesian acceleration and jerk limits
    /// (13 m/s², 6500 m/s³; 25 rad/s², 12500 rad/s³) and of its angular
    /// speed (2.5 rad/s) that moves may use: 0.1 is gentle.
    #[serde(deserialize_with = "positive_fraction")]
    pub dynamics_fraction: f64,
}

/// A host name or IP address: not empty, no port, no spaces.
fn host<'de, D: serde::Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    let v = String::deserialize(d)?;
    if v.is_empty() || v.contains([':', ' ', '/']) {
        Err(serde::de::Error::custom(format!(
            "expected a host name or IPv4 address without a port, found {v:?}"
        )))
    } else {
        Ok(v)
    }
}

/// A fraction in (0, 1].
fn positive_fraction<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v = f64::deserialize(d)?;
    if v > 0.0 && v <= 1.0 {
        Ok(v)
    } else {
        Err(serde::de::Error::custom(format!(
            "expected a fraction in (0, 1], found {v}"
        )))
    }
}

/// The Panda backend in a build without it: loading says how to get it.
#[cfg(not(feature = "panda"))]
#[derive(Debug, Clone)]
pub enum PandaNotBuilt {}

#[cfg(not(feature = "panda"))]
impl<'de> Deserialize<'de> for PandaNotBuilt {
    fn deserialize<D: serde::Deserializer<'de>>(_: D) -> Result<Self, D::Error> {
        Err(serde::de::Error::custom(
            "this cablecell was built without the Panda driver: build it with \
             `cargo build --release --features panda` (see the README, Bringing up devices)",
        ))
    }
}

/// The simulated arm: where it ends up and how long it takes. Its motion
/// is a jerk-limited straight line (see `sim::motion`), the translation's
/// speed capped by the task; the limits are a Panda's Cartesian ones.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimArmConfig {
    /// Standard deviation, per axis, of the reached position about the
    /// commanded one (a Panda's pose repeatability is about 0.1 mm); 0
    /// switches it off.
    #[serde(deserialize_with = "non_negative")]
    pub repeatability_mm: f64,
    /// Translational acceleration limit (a Panda's: 13 m/s²).
    #[serde(deserialize_with = "positive")]
    pub max_accel_mm_s2: f64,
    /// Translational jerk limit (a Panda's: 6500 m/s³).
    #[serde(deserialize_with = "positive")]
    pub max_jerk_mm_s3: f64,
    /// Rotational speed limit (a Panda's: 2.5 rad/s).
    #[serde(deserialize_with = "positive")]
    pub max_angular_speed_rad_s: f64,
    /// Rotational acceleration limit (a Panda's: 25 rad/s²).
    #[serde(deserialize_with = "positive")]
    pub max_angular_accel_rad_s2: f64,
    /// Rotational jerk limit (a Panda's: 12500 rad/s³).
    #[serde(deserialize_with = "positive")]
    pub max_angular_jerk_rad_s3: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GripperConfig {
    pub backend: GripperBackend,
}

/// Which gripper: `sim` simulated (no driver), `pg70` the real driver on a
/// real serial port, `emulated_pg70` the real driver on a pseudo-terminal
/// to an emulated PG70 that moves the simulated jaws.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum GripperBackend {
    Sim(SimGripperConfig),
    Pg70(Pg70Config),
    EmulatedPg70(EmulatedPg70Config),
}

/// The PG70 over SMP on a serial port.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pg70Config {
    /// The serial port, e.g. `/dev/ttyUSB0` (a USB-to-RS232 adapter).
    pub port: String,
    /// The module's baud rate (9600 unless reconfigured).
    #[serde(default = "pg70_baud")]
    pub baud: u32,
    /// The module id set in the module (0x0C in the ROS driver's launch file).
    pub module_id: u8,
    /// How long the module may take to answer a request.
    #[serde(default = "pg70_reply_timeout_ms")]
    pub reply_timeout_ms: u64,
    /// How long a move (reference, position, grip) may take to end.
    #[serde(default = "pg70_move_timeout_ms")]
    pub move_timeout_ms: u64,
    /// Jaw speed and acceleration of position moves; the module's own
    /// when left out.
    #[serde(default)]
    pub motion: Option<Pg70Motion>,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pg70Motion {
    #[serde(deserialize_with = "positive")]
    pub speed_mm_s: f64,
    #[serde(deserialize_with = "positive")]
    pub accel_mm_s2: f64,
}

fn pg70_baud() -> u32 {
    9600
}

fn pg70_reply_timeout_ms() -> u64 {
    500
}

fn pg70_move_timeout_ms() -> u64 {
    10_000
}

/// The real PG70 driver talking to an emulated PG70 (started in process on
/// a pseudo-terminal) whose jaws are the simulated ones.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmulatedPg70Config {
    pub module_id: u8,
    /// The simulated jaws the emulator moves.
    pub jaws: SimGripperConfig,
    /// Fault injection: how the emulator misbehaves, and from which
    /// request on.
    #[serde(default)]
    pub fault: Option<Fault<pg70::Misbehaviour>>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimGripperConfig {
    /// Largest jaw opening (the PG70's stroke is 68 mm).
    #[serde(deserialize_with = "positive")]
    pub stroke_mm: f64,
    /// Jaw speed while moving freely.
    #[serde(deserialize_with = "positive")]
    pub speed_mm_s: f64,
    /// How much the jaws squeeze a cable (both pads together, as a
    /// fraction of its diameter) per ampere of grip current: it sets how
    /// deep the cable dents the pads.
    #[serde(deserialize_with = "positive")]
    pub squeeze_fraction_per_a: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TactileConfig {
    /// Distance between neighbouring taxel centres (3.55 mm on the paper's pad).
    #[serde(deserialize_with = "positive")]
    pub pitch_mm: f64,
    /// Polling rate of the sensor (500 Hz in the paper).
    #[serde(deserialize_with = "positive")]
    pub rate_hz: f64,
    /// Where the pad sits on the hand: the sensor frame in the TCP frame.
    pub tcp_from_sensor: FrameConfig,
    pub backend: TactileBackend,
}

/// Which tactile sensor: `sim` simulated (no driver), `remodel` the real
/// driver on a real serial port, `emulated_remodel` the real driver on a
/// pseudo-terminal to an emulated microcontroller that reads the simulated
/// pad. The two real-driver backends are polled on their own thread at
/// `rate_hz`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum TactileBackend {
    Sim(SimTactileConfig),
    Remodel(RemodelConfig),
    EmulatedRemodel(EmulatedRemodelConfig),
}

impl TactileBackend {
    /// The simulated pad, if there is one (simulated or emulated sensors).
    pub fn sim_pad_mut(&mut self) -> Option<&mut SimTactileConfig> {
        match self {
            TactileBackend::Sim(pad) => Some(pad),
            TactileBackend::EmulatedRemodel(emulated) => Some(&mut emulated.pad),
            TactileBackend::Remodel(_) => None,
        }
    }
}

/// The REMODEL finger's microcontroller on a serial port.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RemodelConfig {
    /// The serial port, e.g. `/dev/ttyACM0`.
    pub port: String,
    /// The link's baud rate (1 Mbaud on the REMODEL firmware).
    #[serde(default = "remodel_baud")]
    pub baud: u32,
    /// `layout[k]` is the ADC channel of taxel k (c11, c12, … c55, row by
    /// row); the channel order is the identity when left out.
    #[serde(default = "identity_layout", deserialize_with = "taxel_layout")]
    pub layout: [usize; TAXEL_COUNT],
    /// How long a sample may take to arrive whole (51 bytes take 0.51 ms).
    #[serde(default = "remodel_deadline_ms")]
    pub deadline_ms: u64,
}

fn remodel_baud() -> u32 {
    1_000_000
}

fn remodel_deadline_ms() -> u64 {
    20
}

pub fn identity_layout() -> [usize; TAXEL_COUNT] {
    std::array::from_fn(|taxel| taxel)
}

/// 25 channels, each of 0..24 once.
fn taxel_layout<'de, D: Deserializer<'de>>(d: D) -> Result<[usize; TAXEL_COUNT], D::Error> {
    let layout = <[usize; TAXEL_COUNT]>::deserialize(d)?;
    let mut seen = [false; TAXEL_COUNT];
    for &channel in &layout {
        match seen.get_mut(channel) {
            Some(seen) if !*seen => *seen = true,
            _ => {
                return Err(D::Error::custom(format!(
                    "expected each ADC channel 0..{} once, found {channel} {}",
                    TAXEL_COUNT - 1,
                    if channel < TAXEL_COUNT {
                        "twice"
                    } else {
                        "out of range"
                    }
                )));
            }
        }
    }
    Ok(layout)
}

/// The real tactile driver talking to an emulated microcontroller (started
/// in process on a pseudo-terminal) that samples the simulated pad.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmulatedRemodelConfig {
    /// The channel order the emulator sends and the driver undoes.
    #[serde(default = "identity_layout", deserialize_with = "taxel_layout")]
    pub layout: [usize; TAXEL_COUNT],
    /// How long a sample may take to arrive whole: the emulator shares the
    /// host's cores, so a loaded host may want more than a real link.
    #[serde(default = "remodel_deadline_ms")]
    pub deadline_ms: u64,
    /// The simulated pad the emulator samples.
    pub pad: SimTactileConfig,
    /// Fault injection: how the emulator misbehaves, and from which
    /// request on.
    #[serde(default)]
    pub fault: Option<Fault<tactile::Misbehaviour>>,
}

/// The first simulated pad: a line-spread response, per-taxel offsets and
/// gains, a saturating photo-reflector and noise. See `sim::tactile_model`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimTactileConfig {
    /// Width (σ) of the cap's deformation across the cable, in pitches.
    #[serde(deserialize_with = "positive")]
    pub line_spread_pitch: f64,
    /// Voltage swing of a taxel from rest to full deformation.
    #[serde(deserialize_with = "positive")]
    pub span_v: f64,
    /// Range of the taxels' resting voltages (drawn once per cell).
    #[serde(deserialize_with = "voltage_range")]
    pub rest_v: [f64; 2],
    /// Relative spread of the taxels' gains (drawn once per cell).
    #[serde(deserialize_with = "fraction")]
    pub gain_spread: f64,
    /// Noise standard deviation as a fraction of `span_v`.
    #[serde(deserialize_with = "fraction")]
    pub noise_fraction: f64,
    /// Fault injection: the sensor stops answering after this many frames.
    #[serde(default)]
    pub silent_after_frames: Option<u64>,
}

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
    /// The vision pipeline on the camera's image (the paper's Section II).
    Vision(VisionDetectorConfig),
}

fn default_straight_edge_radius_px() -> f64 {
    VisionConfig::default().straight_edge_radius_px
}

fn default_work_width_px() -> u32 {
    VisionConfig::default().work_width_px
}

fn default_net_scale() -> f64 {
    DEFAULT_INPUT_SCALE
}

fn net_scale<'de, D: Deserializer<'de>>(deserializer: D) -> Result<f64, D::Error> {
    let scale = f64::deserialize(deserializer)?;
    if input_scale_is_valid(scale) {
        Ok(scale)
    } else {
        Err(D::Error::custom(format!(
            "net_scale {scale} is outside (0, {MAX_INPUT_SCALE}]"
        )))
    }
}

/// The vision detector: the pipeline's settings, and what turns a grasp
/// point in the image into a grasp frame in the base frame.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VisionDetectorConfig {
    /// `auto` (classical on a plain background unless that mask is in
    /// doubt, else the network),
    /// `classical` or `network`.
    pub mask: MaskMethod,
    /// `skeleton` or `superpixels` (the paper's).
    pub instances: InstanceMethod,
    /// The segmentation network, relative to the cell file.
    pub model: PathBuf,
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
    /// The plane the cable lies in, known from the fixture (the paper's
    /// "known distance" of the cable from the camera): a grasp point's ray
    /// from the camera meets it at the grasp point in the base frame.
    pub cable_plane: PlaneConfig,
    /// The direction, in the base frame, the hand comes from: the grasp
    /// frame's y points to this side.
    #[serde(deserialize_with = "unit_vector3")]
    pub approach_from: [f64; 3],
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

/// The simulated scene: one cable resting on two supports, sagging under
/// its own weight, that the jaws drag and that springs back. See
/// `sim::cable` and docs/simulated-cell.md.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldConfig {
    #[serde(deserialize_with = "positive")]
    pub cable_diameter_mm: f64,
    /// The cable's midpoint between the supports (its lowest point, where
    /// the detector puts the grasp frame), in the base frame.
    #[serde(deserialize_with = "vector3")]
    pub cable_center_mm: [f64; 3],
    /// Direction of the cable in the base's horizontal plane.
    #[serde(deserialize_with = "finite")]
    pub cable_yaw_rad: f64,
    /// Inclination of the line between the supports from horizontal.
    #[serde(deserialize_with = "finite")]
    pub cable_tilt_rad: f64,
    /// How far across the pad a cable can lie and still end up between the
    /// closing fingers.
    #[serde(deserialize_with = "positive")]
    pub capture_half_height_mm: f64,
    /// Distance between the two supports.
    #[serde(deserialize_with = "positive")]
    pub support_span_mm: f64,
    /// The cable's weight per length (0 for a straight cable).
    #[serde(deserialize_with = "non_negative")]
    pub cable_weight_n_mm: f64,
    /// Bending stiffness EI: with the weight it sets the sag, and with the
    /// span the cable's resistance to being shifted (48 EI / L³) or turned
    /// (12 EI / L a², a the jaws' half-width) on the pad.
    #[serde(deserialize_with = "positive")]
    pub bending_stiffness_n_mm2: f64,
    /// The closing jaws' drag, as the resistance at which a cable settles
    /// half of `settle_fraction`: a cable softer than this is dragged.
    #[serde(deserialize_with = "positive")]
    pub jaw_drag_stiffness_n_mm: f64,
    /// What holds a bend once the jaws open (the strands' internal
    /// friction, the silicone's grip), as the resistance at which a cable
    /// recovers half of `spring_back_fraction`: a cable stiffer than this
    /// springs back.
    #[serde(deserialize_with = "positive")]
    pub hold_stiffness_n_mm: f64,
    /// For a limp cable, the fraction of the caught pose's distance from
    /// the pad's axis (offset and angle) that the closing jaws remove; 0
    /// switches settling off.
    #[serde(deserialize_with = "fraction")]
    pub settle_fraction: f64,
    /// For a cable far stiffer than what holds a bend, the fraction of the
    /// displacement the grasp imposed that it recovers when the jaws open
    /// (below 1: copper strands take a set); 0 switches spring-back off.
    #[serde(deserialize_with = "fraction")]
    pub spring_back_fraction: f64,
}

impl CellFile {
    /// Makes the file's paths relative to `dir`, the cell file's folder.
    pub fn resolve_paths(&mut self, dir: &Path) {
        if let DetectorBackend::Vision(vision) = &mut self.detector.backend {
            vision.model = dir.join(&vision.model);
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

impl VisionDetectorConfig {
    /// The pipeline's settings.
    pub fn vision(&self) -> VisionConfig {
        VisionConfig {
            mask: self.mask,
            instances: self.instances,
            roi_px: self
                .roi_px
                .map(|[x, y, width, height]| Rect::new(x, y, width, height)),
            work_width_px: self.work_width_px,
            straight_edge_radius_px: self.straight_edge_radius_px,
            // The cell needs grasp frames only.
            cable_masks: false,
            ..VisionConfig::default()
        }
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
        }
    }
}

/// A rigid transform as written in a cell file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameConfig {
    #[serde(deserialize_with = "vector3")]
    pub translation_mm: [f64; 3],
    /// Roll, pitch, yaw (about x, y, z of the parent, applied in that order).
    #[serde(deserialize_with = "vector3")]
    pub rotation_rpy_rad: [f64; 3],
}

impl FrameConfig {
    pub fn from_isometry(isometry: &Isometry3<f64>) -> Self {
        let (roll, pitch, yaw) = isometry.rotation.euler_angles();
        Self {
            translation_mm: isometry.translation.vector.into(),
            rotation_rpy_rad: [roll, pitch, yaw],
        }
    }

    pub fn isometry(&self) -> Isometry3<f64> {
        let [x, y, z] = self.translation_mm;
        let [roll, pitch, yaw] = self.rotation_rpy_rad;
        Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_euler_angles(roll, pitch, yaw),
        )
    }
}
