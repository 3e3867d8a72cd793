//! A cell: the devices a cell file names, ready to use.

use crate::geometry::LineInSensor;
use crate::hw::arm::{Arm, SimArm};
use crate::hw::clock::{Clock, SimClock};
use crate::hw::detector::{CableDetector, OracleDetector};
use crate::hw::gripper::{Gripper, SimGripper};
use crate::hw::tactile::{SimTactile, TactileSensor};
use crate::sim::motion::CartesianLimits;
use crate::sim::tactile_model::TactileModel;
use crate::sim::world::{SharedWorld, SimWorld, lock};
use crate::sim::{Stream, rng};
use crate::task::CellFile;
use crate::task::cell_file::{ArmBackend, DetectorBackend, GripperBackend, TactileBackend};

pub struct Cell {
    pub name: String,
    pub arm: Box<dyn Arm>,
    pub gripper: Box<dyn Gripper>,
    pub tactile: Box<dyn TactileSensor>,
    pub detector: Box<dyn CableDetector>,
    pub clock: Box<dyn Clock>,
    /// The simulated world, when there is one: it knows the truth.
    world: SharedWorld,
}

impl Cell {
    /// Builds the cell of `file`; `seed` seeds every simulated source.
    pub fn build(file: &CellFile, seed: u64) -> Self {
        let world = SimWorld::new(&file.world, file.tactile.tcp_from_sensor.isometry()).shared();
        let arm: Box<dyn Arm> = match &file.arm.backend {
            ArmBackend::Sim(sim) => Box::new(SimArm::new(
                world.clone(),
                file.arm.max_speed_mm_s,
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
                file.arm.max_speed_mm_s,
                crate::hw::arm::panda::panda_limits(panda.dynamics_fraction),
            )),
            #[cfg(not(feature = "panda"))]
            ArmBackend::Panda(not_built) => match *not_built {},
        };
        let gripper: Box<dyn Gripper> = match &file.gripper.backend {
            GripperBackend::Sim(sim) => Box::new(SimGripper::new(
                world.clone(),
                sim.stroke_mm,
                sim.speed_mm_s,
                sim.squeeze_fraction_per_a,
            )),
        };
        let tactile: Box<dyn TactileSensor> = match &file.tactile.backend {
            TactileBackend::Sim(sim) => {
                let model = TactileModel::new(
                    sim,
                    file.tactile.pitch_mm,
                    &mut rng(seed, Stream::TactileCalibration),
                );
                Box::new(SimTactile::new(
                    world.clone(),
                    model,
                    file.tactile.rate_hz,
                    sim.silent_after_frames,
                    rng(seed, Stream::Tactile),
                ))
            }
        };
        let detector: Box<dyn CableDetector> = match &file.detector.backend {
            DetectorBackend::Oracle(oracle) => Box::new(OracleDetector::new(
                world.clone(),
                oracle.clone(),
                rng(seed, Stream::Detector),
            )),
        };
        Self {
            name: file.cell.name.clone(),
            arm,
            gripper,
            tactile,
            detector,
            clock: Box::new(SimClock::new(world.clone())),
            world,
        }
    }

    /// Where the cable really lies on the pad, if the cell can know it.
    pub fn cable_on_pad_truth(&self) -> Option<LineInSensor> {
        lock(&self.world).held()
    }
}
