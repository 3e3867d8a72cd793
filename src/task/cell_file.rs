//! The cell file: which backend each device uses, with its limits and
//! calibration. `config/cell.sim.toml` is the simulated cell.

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use serde::Deserialize;

use super::validate::{finite, fraction, non_negative, positive, vector3, voltage_range};

/// A cell file, e.g. `config/cell.sim.toml`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CellFile {
    pub cell: CellSection,
    pub arm: ArmConfig,
    pub gripper: GripperConfig,
    pub tactile: TactileConfig,
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
    pub backend: ArmBackend,
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

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum GripperBackend {
    Sim(SimGripperConfig),
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

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum TactileBackend {
    Sim(SimTactileConfig),
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
pub struct DetectorConfig {
    pub backend: DetectorBackend,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum DetectorBackend {
    /// Reads the simulated cable's true pose and adds noise: a stand-in
    /// for the vision pipeline, named as such.
    Oracle(OracleConfig),
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
    pub fn isometry(&self) -> Isometry3<f64> {
        let [x, y, z] = self.translation_mm;
        let [roll, pitch, yaw] = self.rotation_rpy_rad;
        Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_euler_angles(roll, pitch, yaw),
        )
    }
}
