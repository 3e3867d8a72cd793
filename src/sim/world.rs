//! What is where in the simulated cell.

use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector2, Vector3};

use crate::geometry::LineInSensor;
use crate::task::cell_file::WorldConfig;

/// The world as the simulated devices share it.
pub type SharedWorld = Arc<Mutex<SimWorld>>;

/// Locks the world. A device that panicked while holding the lock left
/// plain data behind, so the poison is ignored.
pub fn lock(world: &SharedWorld) -> MutexGuard<'_, SimWorld> {
    world.lock().unwrap_or_else(PoisonError::into_inner)
}

#[derive(Debug, Clone)]
pub struct SimWorld {
    /// Simulated time since the cell started.
    pub now_s: f64,
    /// The cable's free pose: x along it, y up in its vertical plane, z
    /// horizontal (towards the camera).
    pub base_from_cable: Isometry3<f64>,
    pub cable_diameter_mm: f64,
    capture_half_height_mm: f64,
    tcp_from_sensor: Isometry3<f64>,
    /// Where the arm's TCP really is.
    pub base_from_tcp: Isometry3<f64>,
    pub opening_mm: f64,
    /// The cable pressed on the pad, while the jaws hold it.
    pub held: Option<LineInSensor>,
}

impl SimWorld {
    /// The scene of `config`, with the arm parked 150 mm above the cable
    /// in the pose that would grasp it perfectly, and the jaws closed.
    pub fn new(config: &WorldConfig, tcp_from_sensor: Isometry3<f64>) -> Self {
        let base_from_cable = cable_frame(
            config.cable_center_mm,
            config.cable_yaw_rad,
            config.cable_tilt_rad,
        );
        let base_from_tcp =
            Translation3::new(0.0, 0.0, 150.0) * base_from_cable * tcp_from_sensor.inverse();
        Self {
            now_s: 0.0,
            base_from_cable,
            cable_diameter_mm: config.cable_diameter_mm,
            capture_half_height_mm: config.capture_half_height_mm,
            tcp_from_sensor,
            base_from_tcp,
            opening_mm: 0.0,
            held: None,
        }
    }

    pub fn shared(self) -> SharedWorld {
        Arc::new(Mutex::new(self))
    }

    /// The free cable as the pad would see it if the jaws closed now:
    /// its line projected onto the pad's plane. `None` if the cable runs
    /// along the closing axis.
    pub fn cable_in_sensor(&self) -> Option<LineInSensor> {
        let base_from_sensor = self.base_from_tcp * self.tcp_from_sensor;
        let sensor_from_cable = base_from_sensor.inverse() * self.base_from_cable;
        let point = sensor_from_cable.translation.vector;
        let direction = sensor_from_cable.rotation * Vector3::x();
        let in_plane = Vector2::new(direction.x, direction.y);
        (in_plane.norm() > 1e-6).then(|| LineInSensor::through(point.xy(), in_plane))
    }

    /// The jaws close: the cable is caught if it lies within reach of the
    /// fingers, and is then pressed flat on the pad where it lay.
    pub fn close_on_cable(&mut self) -> Option<LineInSensor> {
        self.held = self
            .cable_in_sensor()
            .filter(|line| line.offset_mm.abs() <= self.capture_half_height_mm);
        self.held
    }
}

/// The cable's frame from its midpoint, its direction in the horizontal
/// plane (`yaw`) and its inclination (`tilt`).
fn cable_frame(center_mm: [f64; 3], yaw_rad: f64, tilt_rad: f64) -> Isometry3<f64> {
    let x = Vector3::new(
        yaw_rad.cos() * tilt_rad.cos(),
        yaw_rad.sin() * tilt_rad.cos(),
        tilt_rad.sin(),
    );
    let z = Vector3::new(yaw_rad.sin(), -yaw_rad.cos(), 0.0);
    let y = z.cross(&x);
    let rotation = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
    Isometry3::from_parts(
        Translation3::from(Vector3::from(center_mm)),
        UnitQuaternion::from_rotation_matrix(&rotation),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn world(tilt_rad: f64) -> SimWorld {
        let config = WorldConfig {
            cable_diameter_mm: 2.5,
            cable_center_mm: [450.0, 0.0, 250.0],
            cable_yaw_rad: 0.3,
            cable_tilt_rad: tilt_rad,
            capture_half_height_mm: 12.0,
        };
        let tcp_from_sensor = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, -10.0),
            UnitQuaternion::from_euler_angles(-std::f64::consts::FRAC_PI_2, 0.0, 0.0),
        );
        SimWorld::new(&config, tcp_from_sensor)
    }

    #[test]
    fn cable_frame_is_right_handed_with_y_up() {
        let frame = cable_frame([0.0; 3], 0.7, 0.0);
        let y = frame.rotation * Vector3::y();
        assert_relative_eq!(y, Vector3::z(), epsilon = 1e-12);
        assert_relative_eq!(
            frame.rotation.to_rotation_matrix().matrix().determinant(),
            1.0,
            epsilon = 1e-12
        );
    }

    #[test]
    fn a_perfect_grasp_puts_the_cable_on_the_pads_x_axis() {
        let mut world = world(0.0);
        world.base_from_tcp = world.base_from_cable * world.tcp_from_sensor.inverse();
        let line = world.close_on_cable().unwrap();
        assert_relative_eq!(line.alpha_rad, 0.0, epsilon = 1e-9);
        assert_relative_eq!(line.offset_mm, 0.0, epsilon = 1e-9);
    }

    #[test]
    fn a_tilted_cable_grasped_level_lies_at_its_tilt() {
        let mut world = world(0.2);
        let level = cable_frame([450.0, 0.0, 250.0], 0.3, 0.0);
        // Grasp 2 mm too low: the cable's midpoint sits 2 mm up the pad
        // (towards +y), and the line through it at 0.2 rad is 2 cos 0.2 mm
        // from the pad's centre.
        world.base_from_tcp =
            Translation3::new(0.0, 0.0, -2.0) * level * world.tcp_from_sensor.inverse();
        let line = world.close_on_cable().unwrap();
        assert_relative_eq!(line.alpha_rad, 0.2, epsilon = 1e-9);
        assert_relative_eq!(line.offset_mm, 2.0 * 0.2_f64.cos(), epsilon = 1e-9);
    }

    #[test]
    fn a_cable_out_of_reach_is_not_caught() {
        let mut world = world(0.0);
        world.base_from_tcp = Translation3::new(0.0, 0.0, 20.0)
            * world.base_from_cable
            * world.tcp_from_sensor.inverse();
        assert!(world.close_on_cable().is_none());
        assert!(world.held.is_none());
    }
}
