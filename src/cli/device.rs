//! `cablecell device gripper|tactile --port PATH ...` and `cablecell device
//! arm --address HOST ...`: bring-up commands that talk to one device and
//! print what it answered.

use crate::cli::output::outln;
use std::time::{Duration, Instant};

use cablecell::hw::clock::MonotonicClock;
use cablecell::hw::gripper::config::{GRIP_CURRENT_A, OPENING_MM};
use cablecell::hw::gripper::smp::{Reply, state_bits};
use cablecell::hw::gripper::{GripOutcome, Gripper, Pg70};
use cablecell::hw::tactile::RemodelTactile;
use cablecell::perception::tactile::{BiasEstimator, PAPER_BIAS_SAMPLES, RawFrame, raw_to_volts};
use clap::Subcommand;
use serialport::TTYPort;

use super::{Status, device_error_status, number_within};

#[derive(Subcommand, Debug)]
pub enum GripperAction {
    /// The module's state: position, velocity, current, state bits, error.
    State,
    /// Home the jaws (moves are refused until this is done).
    Reference,
    /// Move the jaws to an opening, at the module's own speed and
    /// acceleration unless both are given.
    MovePos {
        /// The opening to move the jaws to, mm.
        #[arg(value_parser = opening_mm)]
        opening_mm: f64,
        /// Jaw speed, mm/s (with --accel).
        #[arg(long = "speed", value_name = "MM_S", requires = "accel_mm_s2", value_parser = speed_mm_s)]
        speed_mm_s: Option<f32>,
        /// Jaw acceleration, mm/s² (with --speed).
        #[arg(long = "accel", value_name = "MM_S2", requires = "speed_mm_s", value_parser = accel_mm_s2)]
        accel_mm_s2: Option<f32>,
    },
    /// Close with a motor current until blocked.
    Grip {
        /// The motor current to close with, A.
        #[arg(value_parser = current_a)]
        current_a: f64,
    },
    /// Stop the jaws where they are.
    Stop,
    /// Acknowledge an error.
    Ack,
}

#[derive(Subcommand, Debug)]
pub enum TactileAction {
    /// The sensor's id (F… for a tactile pad).
    Id,
    /// The number of taxels.
    Count,
    /// Read samples: the raw map, the bias-removed map, the sample rate.
    Read {
        /// How many frames to read.
        #[arg(long, default_value_t = 100, value_parser = samples)]
        samples: usize,
        /// Print the reading as JSON (`cablecell json-schema device-tactile-read`).
        #[arg(long)]
        json: bool,
    },
}

fn opening_mm(text: &str) -> Result<f64, String> {
    number_within(text, OPENING_MM, "mm")
}

/// 0.1 to 1000 mm/s: the PG70's jaws are far slower than 1 m/s, and a
/// slower move than 0.1 mm/s would outlast any bring-up.
fn speed_mm_s(text: &str) -> Result<f32, String> {
    number_within(text, 0.1..=1000.0, "mm/s").map(|v: f64| v as f32)
}

/// 1 to 10 000 mm/s²: a jaw at 10 m/s² reaches any speed it has within a
/// few millimetres.
fn accel_mm_s2(text: &str) -> Result<f32, String> {
    number_within(text, 1.0..=10_000.0, "mm/s²").map(|v: f64| v as f32)
}

fn current_a(text: &str) -> Result<f64, String> {
    number_within(text, GRIP_CURRENT_A, "A")
}

/// 1 to 10 000 samples: 5 s at the link's 2 kHz, 100 s at 100 Hz.
fn samples(text: &str) -> Result<usize, String> {
    number_within(text, 1..=10_000, "samples")
}

#[derive(Subcommand, Debug)]
pub enum ArmAction {
    /// The TCP pose in the base frame (the end effector as set in Desk).
    State,
    /// Move the TCP by DX DY DZ mm along a straight line in the base frame,
    /// keeping its orientation: at most 50 mm, at most 20 mm/s.
    #[command(allow_negative_numbers = true)]
    MoveRel {
        /// Along the base's x, mm.
        dx_mm: f64,
        /// Along the base's y, mm.
        dy_mm: f64,
        /// Along the base's z, mm.
        dz_mm: f64,
        /// The TCP's speed along the line, mm/s.
        #[arg(long = "speed", value_name = "MM_S", default_value_t = 10.0)]
        speed_mm_s: f64,
    },
    /// Stop any motion.
    Stop,
    /// Clear the controller's errors after a reflex (automatic error
    /// recovery), once its cause is gone.
    Recover,
}

#[cfg(feature = "panda")]
pub fn arm(address: &str, action: &ArmAction) -> Status {
    use cablecell::hw::arm::panda::panda_limits;
    use cablecell::hw::arm::{Arm, Panda, WorkspaceBox, WorkspaceLimited};
    use nalgebra::{Isometry3, Translation3, Vector3};
    // A bring-up move: short and slow enough to stop by hand, with a tenth
    // of the Panda's acceleration and jerk.
    const MOVE_MAX_MM: f64 = 50.0;
    const SPEED_MAX_MM_S: f64 = 20.0;
    const DYNAMICS_FRACTION: f64 = 0.1;
    let describe = |pose: &Isometry3<f64>| {
        let t = pose.translation.vector;
        let (roll, pitch, yaw) = pose.rotation.euler_angles();
        format!(
            "TCP in base: x {:+.3} y {:+.3} z {:+.3} mm, roll {roll:+.4} pitch {pitch:+.4} yaw {yaw:+.4} rad",
            t.x, t.y, t.z
        )
    };
    if let ArmAction::MoveRel {
        dx_mm,
        dy_mm,
        dz_mm,
        ..
    } = action
    {
        let offset_mm = Vector3::new(*dx_mm, *dy_mm, *dz_mm);
        if !(offset_mm.norm() <= MOVE_MAX_MM) {
            eprintln!(
                "error: move-rel moves at most {MOVE_MAX_MM} mm; asked {:.1} mm",
                offset_mm.norm()
            );
            return Status::BadInput;
        }
    }
    let mut panda = Panda::new(
        address,
        Isometry3::identity(),
        panda_limits(DYNAMICS_FRACTION),
    );
    let result = match action {
        ArmAction::State => panda.base_from_tcp().map(|pose| describe(&pose)),
        ArmAction::MoveRel {
            dx_mm,
            dy_mm,
            dz_mm,
            speed_mm_s,
        } => (move || {
            let start = panda.base_from_tcp()?;
            // The cell's limits, whatever the arm: here a box around the
            // start that the move may not leave, and the speed limit.
            let at_mm: [f64; 3] = start.translation.vector.into();
            let workspace = WorkspaceBox {
                min_mm: at_mm.map(|x| x - MOVE_MAX_MM),
                max_mm: at_mm.map(|x| x + MOVE_MAX_MM),
            };
            let mut arm = WorkspaceLimited::new(panda, workspace, SPEED_MAX_MM_S);
            let offset = Translation3::new(*dx_mm, *dy_mm, *dz_mm);
            arm.move_linear(&(offset * start), *speed_mm_s)?;
            arm.base_from_tcp()
                .map(|end| format!("moved; {}", describe(&end)))
        })(),
        ArmAction::Stop => panda.stop().map(|()| "stopped".into()),
        ArmAction::Recover => panda.recover().map(|()| "errors cleared".into()),
    };
    report(result)
}

#[cfg(not(feature = "panda"))]
pub fn arm(_address: &str, _action: &ArmAction) -> Status {
    eprintln!(
        "error: this cablecell was built without the Panda driver: build it with `cargo build --release --features panda`"
    );
    Status::BadInput
}

fn open(port: &str, baud: u32) -> Result<TTYPort, String> {
    serialport::new(port, baud)
        .timeout(Duration::from_millis(5))
        .open_native()
        .map_err(|e| format!("{port}: cannot open the port: {e}"))
}

pub fn gripper(port: &str, baud: u32, module_id: u8, action: &GripperAction) -> Status {
    let link = match open(port, baud) {
        Ok(link) => link,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    let mut pg70 = Pg70::new(link, port, module_id);
    if let GripperAction::MovePos {
        speed_mm_s: Some(speed_mm_s),
        accel_mm_s2: Some(accel_mm_s2),
        ..
    } = action
    {
        pg70 = pg70.with_motion(*speed_mm_s, *accel_mm_s2);
    }
    let result = match action {
        GripperAction::State => pg70.state().map(|reply| describe_state(&reply)),
        GripperAction::Reference => pg70.reference().map(|()| "referenced".into()),
        GripperAction::MovePos { opening_mm, .. } => pg70
            .move_to(*opening_mm)
            .map(|()| format!("at {opening_mm} mm")),
        GripperAction::Grip { current_a } => pg70.grip(*current_a).map(|outcome| match outcome {
            GripOutcome::Holding { opening_mm } => {
                format!("holding an object at {opening_mm:.2} mm")
            }
            GripOutcome::Empty => "closed on nothing".into(),
        }),
        GripperAction::Stop => pg70.stop().map(|()| "stopped".into()),
        GripperAction::Ack => pg70.acknowledge().map(|()| "error acknowledged".into()),
    };
    report(result)
}

fn describe_state(reply: &Reply) -> String {
    match reply {
        Reply::State {
            position_mm,
            velocity_mm_s,
            current_a,
            state,
            error,
        } => {
            let flags: Vec<&str> = [
                (state_bits::REFERENCED, "referenced"),
                (state_bits::MOVING, "moving"),
                (state_bits::ERROR, "error"),
                (state_bits::MOVE_BLOCKED, "blocked"),
                (state_bits::POSITION_REACHED, "position reached"),
            ]
            .iter()
            .filter(|(bit, _)| state & bit != 0)
            .map(|(_, name)| *name)
            .collect();
            format!(
                "position {position_mm:.3} mm, velocity {}, current {}, state 0x{state:02X} [{}], error 0x{error:02X}",
                velocity_mm_s.map_or("—".into(), |v| format!("{v:.3} mm/s")),
                current_a.map_or("—".into(), |c| format!("{c:.3} A")),
                flags.join(", ")
            )
        }
        other => format!("{other:?}"),
    }
}

pub fn tactile(port: &str, baud: u32, action: &TactileAction) -> Status {
    let link = match open(port, baud) {
        Ok(link) => link,
        Err(error) => {
            eprintln!("error: {error}");
            return Status::BadInput;
        }
    };
    let identity = std::array::from_fn(|k| k);
    // Bring-up is no control loop: room for a USB adapter's latency timer
    // (16 ms on FTDI's) and a busy host.
    let mut sensor = RemodelTactile::new(link, port, identity, Box::new(MonotonicClock::new()))
        .with_deadline(Duration::from_millis(200));
    let result = match action {
        TactileAction::Id => sensor.id(),
        TactileAction::Count => sensor.count().map(|n| n.to_string()),
        TactileAction::Read { samples, json } => match read(&mut sensor, *samples) {
            Ok(reading) if *json => return super::json::print(reading),
            reading => reading.map(|reading| reading.text()),
        },
    };
    report(result)
}

/// What `device tactile … read` found; `--json` prints it as it is.
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct TactileReading {
    samples: usize,
    /// Frames read per second over the whole read.
    rate_hz: f64,
    /// The last frame, taxels c11 … c55 row by row.
    raw_v: [[f64; 5]; 5],
    /// The last frame less the bias of the first frames (up to the
    /// paper's 50).
    dv_v: [[f64; 5]; 5],
    /// How many frames the bias was measured from.
    bias_samples: usize,
}

fn read(
    sensor: &mut RemodelTactile<TTYPort>,
    samples: usize,
) -> Result<TactileReading, cablecell::hw::DeviceError> {
    let started = Instant::now();
    let frames: Vec<RawFrame> = (0..samples)
        .map(|_| sensor.sample())
        .collect::<Result<_, _>>()?;
    let rate_hz = samples as f64 / started.elapsed().as_secs_f64();
    let bias_samples = PAPER_BIAS_SAMPLES.min(samples);
    let mut estimator = BiasEstimator::new(bias_samples);
    let bias = frames.iter().find_map(|f| estimator.push(f));
    let last = frames[frames.len() - 1];
    let raw_v =
        std::array::from_fn(|row| std::array::from_fn(|col| raw_to_volts(last[5 * row + col])));
    // `samples` ≥ 1 and the estimator wants at most that many frames.
    let dv_v = bias.map_or([[0.0; 5]; 5], |b| b.remove(&last).dv_v);
    Ok(TactileReading {
        samples,
        rate_hz,
        raw_v,
        dv_v,
        bias_samples,
    })
}

impl TactileReading {
    /// For a person: the rate, then both maps, a row a line.
    fn text(&self) -> String {
        let rows = |map: &[[f64; 5]; 5], sign: bool| -> String {
            map.iter()
                .map(|row| {
                    let cells: Vec<String> = row
                        .iter()
                        .map(|v| {
                            if sign {
                                format!("{v:+6.3}")
                            } else {
                                format!("{v:6.3}")
                            }
                        })
                        .collect();
                    format!("  {}\n", cells.join(" "))
                })
                .collect()
        };
        let text = format!(
            "{} samples at {:.0} Hz\nraw (V), last sample:\n{}Δv (V), bias from the first {} samples:\n{}",
            self.samples,
            self.rate_hz,
            rows(&self.raw_v, false),
            self.bias_samples,
            rows(&self.dv_v, true)
        );
        text.trim_end().to_owned()
    }
}

fn report(result: Result<String, cablecell::hw::DeviceError>) -> Status {
    match result {
        Ok(text) => {
            outln!("{text}");
            Status::Success
        }
        Err(error) => {
            eprintln!("error: {error}");
            device_error_status(&error)
        }
    }
}
