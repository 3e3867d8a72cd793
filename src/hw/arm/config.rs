//! The arm's table of a cell file: its limits and which backend drives it.

use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

use super::WorkspaceBox;
use crate::schema::FrameConfig;
use crate::schema::validate::{non_negative, positive};

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
             `cargo build --release --features panda` (see docs/devices.md, The Panda)",
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
