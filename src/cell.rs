//! A cell: the devices a cell file names, ready to use.

use crate::geometry::LineInSensor;
use crate::hw::arm::{Arm, SimArm};
use crate::hw::camera::{Camera, OpencvCamera, SimCamera};
use crate::hw::clock::{Clock, SimClock};
use crate::hw::detector::{CableDetector, OracleDetector, VisionDetector};
use crate::hw::gripper::{Gripper, SimGripper};
use crate::hw::tactile::{SimTactile, TactileSensor};
use crate::perception::vision::Pipeline;
use crate::perception::vision::network::{LazyNetwork, runtime_library};
use crate::sim::motion::CartesianLimits;
use crate::sim::tactile_model::TactileModel;
use crate::sim::world::{SharedWorld, SimWorld, lock};
use crate::sim::{Stream, rng};
use crate::task::CellFile;
use crate::task::cell_file::{
    ArmBackend, CameraBackend, DetectorBackend, GripperBackend, TactileBackend,
};

pub struct Cell {
    pub name: String,
    pub arm: Box<dyn Arm>,
    pub gripper: Box<dyn Gripper>,
    pub tactile: Box<dyn TactileSensor>,
    pub camera: Box<dyn Camera>,
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
        let camera_config = &file.camera;
        let camera: Box<dyn Camera> = match &camera_config.backend {
            CameraBackend::Sim(sim) => Box::new(SimCamera::new(
                world.clone(),
                camera_config.intrinsics,
                sim.base_from_camera.isometry(),
                camera_config.marker.on_finger(),
                sim.appearance(),
                rng(seed, Stream::Camera),
            )),
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
                Pipeline::new(vision.vision()),
                LazyNetwork::new(
                    vision.model.clone(),
                    runtime_library(vision.onnxruntime.as_deref()),
                ),
                camera_config
                    .calibration
                    .as_ref()
                    .map(|calibration| vision.image_to_base(camera_config.intrinsics, calibration)),
            )),
        };
        Self {
            name: file.cell.name.clone(),
            arm,
            gripper,
            tactile,
            camera,
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
