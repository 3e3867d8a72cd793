//! The tactile sensor's table of a cell file: the pad's geometry, where it
//! sits on the hand, and which backend reads it.

use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

use super::remodel_emulator::Misbehaviour;
use crate::hw::emulator::Fault;
use crate::perception::tactile::TAXEL_COUNT;
use crate::schema::FrameConfig;
use crate::schema::validate::within;
use crate::sim::tactile_model::SimTactileConfig;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TactileConfig {
    /// Distance between neighbouring taxel centres (3.55 mm on the paper's pad).
    #[serde(deserialize_with = "pitch_mm")]
    pub pitch_mm: f64,
    /// Polling rate of the sensor (500 Hz in the paper).
    #[serde(deserialize_with = "rate_hz")]
    pub rate_hz: f64,
    /// Where the pad sits on the hand: the sensor frame in the TCP frame.
    pub tcp_from_sensor: FrameConfig,
    pub backend: TactileBackend,
}

/// Taxel pitches of a fingertip pad: 1 mm (the densest tactile arrays) to
/// 20 mm (a 5×5 pad 10 cm across, wider than any finger).
pub const PITCH_MM: std::ops::RangeInclusive<f64> = 1.0..=20.0;

fn pitch_mm<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    within(d, PITCH_MM, "mm")
}

/// Bytes of one sample exchange on the REMODEL link: the request `'a'` and
/// its 50-byte answer.
pub const SAMPLE_EXCHANGE_BYTES: f64 = 51.0;

/// Samples per second a serial link at `baud` carries (10 bits a byte, 8N1).
pub fn link_rate_hz(baud: u32) -> f64 {
    f64::from(baud) / (10.0 * SAMPLE_EXCHANGE_BYTES)
}

/// 100 Hz (a fifth of the paper's 500 Hz, so that a task's largest frame
/// count, 1000, takes 10 s) to what the REMODEL link carries at its 1 Mbaud,
/// about 1.96 kHz; a slower `baud` lowers the top (checked when the cell
/// loads).
fn rate_hz<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    within(d, 100.0..=link_rate_hz(remodel_baud()).floor(), "Hz")
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
    pub fault: Option<Fault<Misbehaviour>>,
}
