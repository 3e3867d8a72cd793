//! The gripper's table of a cell file: which backend, on which port.

use std::ops::RangeInclusive;

use serde::Deserialize;

use super::pg70_emulator::Misbehaviour;
use crate::hw::emulator::Fault;
use crate::schema::validate::positive;

/// Jaw openings the PG70 reaches: its full stroke, 34 mm a jaw.
pub const OPENING_MM: RangeInclusive<f64> = 0.0..=68.0;

/// Grip currents: the PG70's motor grips with a few amperes; 0.1 A moves
/// nothing and 10 A is beyond any it takes.
pub const GRIP_CURRENT_A: RangeInclusive<f64> = 0.1..=10.0;

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
    pub fault: Option<Fault<Misbehaviour>>,
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
