//! A cell: the devices a cell file names, ready to use.
//!
//! Each device is simulated (`sim`: no driver, the simulated world), real
//! (`pg70`, `remodel`: the real driver on a real serial port) or emulated
//! (`emulated_pg70`, `emulated_remodel`: the real driver on a
//! pseudo-terminal to an emulator of the device that this cell runs on a
//! thread of its own, acting on the simulated world). Every arm is wrapped
//! in the cell's workspace and speed limits.

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use nalgebra::Point3;
use serialport::{SerialPort, TTYPort};

use crate::cell::CellFile;
use crate::detector::config::DetectorBackend;
use crate::detector::{CableDetector, OracleDetector, VisionDetector};
use crate::geometry::LineInSensor;
use crate::hw::arm::config::ArmBackend;
use crate::hw::arm::{Arm, SimArm, WorkspaceLimited};
use crate::hw::camera::config::CameraBackend;
use crate::hw::camera::{Camera, OpencvCamera, SimCamera};
use crate::hw::clock::{Clock, MonotonicClock, SimClock};
use crate::hw::emulator::{FaultSwitch, PtyEmulator};
use crate::hw::gripper::config::{GripperBackend, SimGripperConfig};
use crate::hw::gripper::pg70_emulator::{self, Pg70Emulator};
use crate::hw::gripper::{Gripper, Pg70, SimGripper};
use crate::hw::tactile::config::TactileBackend;
use crate::hw::tactile::remodel_emulator::{self, TactileEmulator};
use crate::hw::tactile::{PolledTactile, RemodelTactile, SimTactile, TactileSensor};
use crate::hw::{DeviceError, DeviceKind};
use crate::perception::tactile::TAXEL_COUNT;
use crate::sim::motion::CartesianLimits;
use crate::sim::tactile_model::SimTactileConfig;
use crate::sim::tactile_model::TactileModel;
use crate::sim::world::{SharedWorld, SimWorld, lock};
use crate::sim::{Stream, rng};

/// The devices a cell file names, ready to use, with the simulated world
/// they share when there is one.
pub struct CellDevices {
    pub name: String,
    pub arm: Box<dyn Arm>,
    pub gripper: Box<dyn Gripper>,
    pub tactile: Box<dyn TactileSensor>,
    pub camera: Box<dyn Camera>,
    pub detector: Box<dyn CableDetector>,
    pub clock: Box<dyn Clock>,
    /// The emulators the cell runs; dropped after the drivers that talk
    /// to them.
    pub emulators: Emulators,
    /// The simulated world, when there is one: it knows the truth.
    world: SharedWorld,
}

/// The device emulators of an emulated cell, each serving a
/// pseudo-terminal on its own thread until the cell is dropped.
#[derive(Default)]
pub struct Emulators {
    /// Switches the emulated PG70's misbehaviour, if the gripper is one.
    pub gripper_fault: Option<FaultSwitch<pg70_emulator::Misbehaviour>>,
    /// Switches the emulated tactile microcontroller's misbehaviour.
    pub tactile_fault: Option<FaultSwitch<remodel_emulator::Misbehaviour>>,
    running: Vec<PtyEmulator>,
}

impl Emulators {
    /// Starts an emulator on a new pseudo-terminal (see [`PtyEmulator`]);
    /// returns the slave end and its path, for the driver.
    fn start(
        &mut self,
        device: DeviceKind,
        serve: impl FnOnce(TTYPort, &AtomicBool) + Send + 'static,
    ) -> Result<(TTYPort, String), DeviceError> {
        let (emulator, slave) =
            PtyEmulator::start(serve).map_err(|e| DeviceError::Disconnected {
                device,
                port: "a new pseudo-terminal".into(),
                reason: format!("cannot make one: {e}"),
            })?;
        let path = emulator.path().to_owned();
        self.running.push(emulator);
        Ok((slave, path))
    }
}

impl CellDevices {
    /// Builds the cell of `file`, `seed` seeding every simulated source;
    /// opens the real devices' ports and starts the emulators.
    pub fn build(file: &CellFile, seed: u64) -> Result<Self, DeviceError> {
        let world = SimWorld::new(&file.world, file.tactile.tcp_from_sensor.isometry()).shared();
        // A simulated arm advances the simulated world's time by its moves;
        // with a real arm, time is the wall clock's, one start for every
        // device.
        let wall_clock = MonotonicClock::new();
        let simulated_time = matches!(file.arm.backend, ArmBackend::Sim(_));
        let clock = || -> Box<dyn Clock> {
            if simulated_time {
                Box::new(SimClock::new(world.clone()))
            } else {
                Box::new(wall_clock.clone())
            }
        };
        let mut emulators = Emulators::default();
        let arm: Box<dyn Arm> = match &file.arm.backend {
            ArmBackend::Sim(sim) => Box::new(SimArm::new(
                world.clone(),
                CartesianLimits {
                    accel_mm_s2: sim.max_accel_mm_s2,
                    jerk_mm_s3: sim.max_jerk_mm_s3,
                    angular_speed_rad_s: sim.max_angular_speed_rad_s,
                    angular_accel_rad_s2: sim.max_angular_accel_rad_s2,
                    angular_jerk_rad_s3: sim.max_angular_jerk_rad_s3,
                },
                sim.repeatability_mm,
                rng(seed, Stream::Arm),
            )),
            #[cfg(feature = "panda")]
            ArmBackend::Panda(panda) => Box::new(crate::hw::arm::Panda::new(
                &panda.address,
                panda.ee_from_tcp.isometry(),
                crate::hw::arm::panda::panda_limits(panda.dynamics_fraction),
            )),
            #[cfg(not(feature = "panda"))]
            ArmBackend::Panda(not_built) => match *not_built {},
        };
        let arm = Box::new(WorkspaceLimited::new(
            arm,
            file.arm.workspace,
            file.arm.max_speed_mm_s,
        ));
        let gripper: Box<dyn Gripper> = match &file.gripper.backend {
            GripperBackend::Sim(sim) => Box::new(sim_jaws(&world, sim)),
            GripperBackend::Pg70(pg70) => {
                let port = open(DeviceKind::Gripper, &pg70.port, pg70.baud, 10)?;
                let mut driver = Pg70::new(port, &pg70.port, pg70.module_id).with_timeouts(
                    Duration::from_millis(pg70.reply_timeout_ms),
                    Duration::from_millis(pg70.move_timeout_ms),
                );
                if let Some(motion) = pg70.motion {
                    driver =
                        driver.with_motion(motion.speed_mm_s as f32, motion.accel_mm_s2 as f32);
                }
                Box::new(driver)
            }
            GripperBackend::EmulatedPg70(emulated) => {
                let mut module =
                    Pg70Emulator::new(emulated.module_id, sim_jaws(&world, &emulated.jaws));
                module.fault.set(emulated.fault);
                emulators.gripper_fault = Some(module.fault.clone());
                let (port, path) = emulators.start(DeviceKind::Gripper, move |master, stop| {
                    module.serve(master, stop)
                })?;
                Box::new(Pg70::new(
                    with_timeout(port, &path, DeviceKind::Gripper)?,
                    &path,
                    emulated.module_id,
                ))
            }
        };
        let tactile: Box<dyn TactileSensor> = match &file.tactile.backend {
            TactileBackend::Sim(sim) => Box::new(sim_pad(&world, file, sim, seed)),
            TactileBackend::Remodel(remodel) => {
                let port = open(DeviceKind::Tactile, &remodel.port, remodel.baud, 2)?;
                let mut driver = RemodelTactile::new(port, &remodel.port, remodel.layout, clock())
                    .with_deadline(Duration::from_millis(remodel.deadline_ms));
                check_taxel_count(&mut driver, &remodel.port)?;
                Box::new(PolledTactile::start(driver, file.tactile.rate_hz))
            }
            TactileBackend::EmulatedRemodel(emulated) => {
                let mut pad = sim_pad(&world, file, &emulated.pad, seed);
                let mut mcu = TactileEmulator::new(emulated.layout, move || {
                    pad.read().ok().map(|frame| frame.raw)
                });
                mcu.fault.set(emulated.fault);
                emulators.tactile_fault = Some(mcu.fault.clone());
                let (port, path) = emulators.start(DeviceKind::Tactile, move |master, stop| {
                    mcu.serve(master, stop)
                })?;
                let port = with_timeout(port, &path, DeviceKind::Tactile)?;
                let mut driver = RemodelTactile::new(port, &path, emulated.layout, clock())
                    .with_deadline(Duration::from_millis(emulated.deadline_ms));
                check_taxel_count(&mut driver, &path)?;
                Box::new(PolledTactile::start(driver, file.tactile.rate_hz))
            }
        };
        let camera_config = &file.camera;
        let camera: Box<dyn Camera> = match &camera_config.backend {
            CameraBackend::Sim(sim) => {
                let mut stream = rng(seed, Stream::Camera);
                let appearance = sim.appearance(&mut stream);
                Box::new(SimCamera::new(
                    world.clone(),
                    camera_config.intrinsics,
                    sim.base_from_camera.isometry(),
                    camera_config.marker.on_finger(),
                    appearance,
                    stream,
                ))
            }
            CameraBackend::Opencv(opencv) => Box::new(OpencvCamera::new(
                opencv.source.clone(),
                camera_config.intrinsics,
            )),
        };
        let detector: Box<dyn CableDetector> = match &file.detector.backend {
            DetectorBackend::Oracle(oracle) => Box::new(OracleDetector::new(
                world.clone(),
                oracle.clone(),
                rng(seed, Stream::Detector),
            )),
            DetectorBackend::Vision(vision) => Box::new(VisionDetector::new(
                vision.pipeline(false),
                vision.network(),
                camera_config
                    .calibration
                    .as_ref()
                    .map(|calibration| vision.image_to_base(camera_config.intrinsics, calibration)),
            )),
        };
        Ok(Self {
            name: file.cell.name.clone(),
            arm,
            gripper,
            tactile,
            camera,
            detector,
            clock: clock(),
            emulators,
            world,
        })
    }

    /// Where the cable really lies on the pad, if the cell can know it.
    pub fn cable_on_pad_truth(&self) -> Option<LineInSensor> {
        lock(&self.world).held()
    }

    /// The cable's true centre line in the base frame while the jaws hold
    /// it (see [`SimWorld::true_centre_line`]), if the cell can know it.
    pub fn true_centre_line(&self, pad_half_side_mm: f64) -> Option<Vec<Point3<f64>>> {
        lock(&self.world).true_centre_line(pad_half_side_mm)
    }

    /// The simulated world that the simulated and emulated devices share:
    /// where the jaws and the arm really are.
    pub fn world(&self) -> SharedWorld {
        self.world.clone()
    }
}

fn sim_jaws(world: &SharedWorld, config: &SimGripperConfig) -> SimGripper {
    SimGripper::new(
        world.clone(),
        config.stroke_mm,
        config.speed_mm_s,
        config.squeeze_fraction_per_a,
    )
}

fn sim_pad(
    world: &SharedWorld,
    file: &CellFile,
    config: &SimTactileConfig,
    seed: u64,
) -> SimTactile {
    let model = TactileModel::new(
        config,
        file.tactile.pitch_mm,
        &mut rng(seed, Stream::TactileCalibration),
    );
    SimTactile::new(
        world.clone(),
        model,
        file.tactile.rate_hz,
        config.silent_after_frames,
        rng(seed, Stream::Tactile),
    )
}

/// Opens a real serial port whose reads return within `read_timeout_ms`,
/// so that the drivers keep their own deadlines.
fn open(
    device: DeviceKind,
    port: &str,
    baud: u32,
    read_timeout_ms: u64,
) -> Result<TTYPort, DeviceError> {
    serialport::new(port, baud)
        .timeout(Duration::from_millis(read_timeout_ms))
        .open_native()
        .map_err(|e| DeviceError::Disconnected {
            device,
            port: port.to_owned(),
            reason: format!("cannot open the port: {e}"),
        })
}

fn with_timeout(mut port: TTYPort, path: &str, device: DeviceKind) -> Result<TTYPort, DeviceError> {
    port.set_timeout(Duration::from_millis(2))
        .map_err(|e| DeviceError::Disconnected {
            device,
            port: path.to_owned(),
            reason: e.to_string(),
        })?;
    Ok(port)
}

/// A sensor that is not a 5×5 pad (a wrong port, a proximity sensor) is
/// caught before the task starts.
fn check_taxel_count(driver: &mut RemodelTactile<TTYPort>, port: &str) -> Result<(), DeviceError> {
    let count = driver.count()?;
    if usize::from(count) == TAXEL_COUNT {
        Ok(())
    } else {
        Err(DeviceError::Garbled {
            device: DeviceKind::Tactile,
            port: port.to_owned(),
            detail: format!("the sensor has {count} sensing elements, the pad {TAXEL_COUNT}"),
        })
    }
}
