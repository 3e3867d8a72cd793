//! What is where in the simulated cell, and what the cable does when the
//! jaws close on it and open again.

use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use nalgebra::{
    Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector2, Vector3,
};

use super::cable::CableModel;
use crate::geometry::{LineInSensor, planar_to_spatial};
use crate::perception::shape::{SHAPE_SPACING_MM, TactileCurve};
use crate::schema::validate::{finite, fraction, non_negative, positive, vector3};
use serde::Deserialize;

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

/// The world as the simulated devices share it.
pub type SharedWorld = Arc<Mutex<SimWorld>>;

/// Locks the world. A device that panicked while holding the lock left
/// plain data behind, so the poison is ignored.
pub fn lock(world: &SharedWorld) -> MutexGuard<'_, SimWorld> {
    world.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Newton steps that find the point of the sagging cable nearest the pad's
/// centre; the sag's slope changes by well under 1 % between steps.
const NEAREST_POINT_STEPS: usize = 4;

/// The cable while the jaws hold it.
#[derive(Debug, Clone, Copy)]
pub struct Grasp {
    /// Where it lay on the pad when the jaws touched it.
    pub caught: LineInSensor,
    /// Where the closing jaws left it: pressed on the pad, moving with
    /// the hand.
    pub held: LineInSensor,
    /// The cable's midpoint frame seen from the line it was caught on (a
    /// frame on the pad: origin at the foot of the perpendicular, x along
    /// the line), so that a release can put the cable back in the world.
    caught_line_from_cable: Isometry3<f64>,
}

#[derive(Debug, Clone)]
pub struct SimWorld {
    /// Simulated time since the cell started.
    pub now_s: f64,
    /// The free cable's midpoint frame: x along it, y up in its vertical
    /// plane, z horizontal (towards the camera). The cable sags between
    /// its supports about this frame (see `CableModel`).
    pub base_from_cable: Isometry3<f64>,
    pub cable_diameter_mm: f64,
    pub cable: CableModel,
    capture_half_height_mm: f64,
    tcp_from_sensor: Isometry3<f64>,
    /// Where the arm's TCP really is.
    pub base_from_tcp: Isometry3<f64>,
    pub opening_mm: f64,
    /// The cable between the jaws, while they hold it.
    pub grasp: Option<Grasp>,
    /// How far each pad is pressed into the cable, as a fraction of its
    /// diameter, while the jaws hold it.
    pub squeeze_fraction: f64,
}

impl WorldConfig {
    /// The free cable's midpoint frame before anything touches it: its
    /// true grasp frame.
    pub fn base_from_cable(&self) -> Isometry3<f64> {
        cable_frame(
            self.cable_center_mm,
            self.cable_yaw_rad,
            self.cable_tilt_rad,
        )
    }
}

impl SimWorld {
    /// The scene of `config`, with the arm parked 150 mm above the cable
    /// in the pose that would grasp it perfectly, and the jaws closed.
    pub fn new(config: &WorldConfig, tcp_from_sensor: Isometry3<f64>) -> Self {
        let base_from_cable = config.base_from_cable();
        let base_from_tcp =
            Translation3::new(0.0, 0.0, 150.0) * base_from_cable * tcp_from_sensor.inverse();
        Self {
            now_s: 0.0,
            base_from_cable,
            cable_diameter_mm: config.cable_diameter_mm,
            cable: CableModel::new(config),
            capture_half_height_mm: config.capture_half_height_mm,
            tcp_from_sensor,
            base_from_tcp,
            opening_mm: 0.0,
            grasp: None,
            squeeze_fraction: 0.0,
        }
    }

    pub fn shared(self) -> SharedWorld {
        Arc::new(Mutex::new(self))
    }

    /// The cable pressed on the pad, while the jaws hold it.
    pub fn held(&self) -> Option<LineInSensor> {
        self.grasp.map(|grasp| grasp.held)
    }

    fn base_from_sensor(&self) -> Isometry3<f64> {
        self.base_from_tcp * self.tcp_from_sensor
    }

    /// The cable's centre line in the base frame while the jaws hold it,
    /// from one support to the other: over the pad (`|x|` in the sensor
    /// frame up to `pad_half_side_mm`) the line the jaws hold it on,
    /// elsewhere the free cable as it was caught. (The model has no bend
    /// between the two: where the jaws moved the cable, its centre line
    /// steps at the pad's edges.) `None` while nothing is held.
    pub fn true_centre_line(&self, pad_half_side_mm: f64) -> Option<Vec<Point3<f64>>> {
        let held = self.held()?;
        let base_from_sensor = self.base_from_sensor();
        let sensor_from_base = base_from_sensor.inverse();
        let free: Vec<Point3<f64>> = self
            .cable
            .centre_line_mm(SHAPE_SPACING_MM)
            .into_iter()
            .map(|p| self.base_from_cable * p)
            .collect();
        let x_in_sensor = |p: &Point3<f64>| (sensor_from_base * p).x;
        let mut on_pad: Vec<Point3<f64>> = TactileCurve::Line(held)
            .points_in_sensor(pad_half_side_mm)
            .into_iter()
            .map(|p| base_from_sensor * Point3::new(p.x, p.y, 0.0))
            .collect();
        // The free cable runs along the sensor's x one way or the other.
        let rising = free.last().map(x_in_sensor) > free.first().map(x_in_sensor);
        if rising != (on_pad.last().map(x_in_sensor) > on_pad.first().map(x_in_sensor)) {
            on_pad.reverse();
        }
        let before = free
            .iter()
            .take_while(|p| x_in_sensor(p).abs() > pad_half_side_mm);
        let after = free
            .iter()
            .rev()
            .take_while(|p| x_in_sensor(p).abs() > pad_half_side_mm);
        let mut line: Vec<Point3<f64>> = before.copied().collect();
        line.extend(on_pad);
        let mut tail: Vec<Point3<f64>> = after.copied().collect();
        tail.reverse();
        line.extend(tail);
        Some(line)
    }

    /// The free cable as the pad would see it if the jaws closed now: its
    /// tangent at the point nearest the pad's centre, projected onto the
    /// pad's plane. `None` if the cable runs along the closing axis.
    pub fn cable_in_sensor(&self) -> Option<LineInSensor> {
        let sensor_from_cable = self.base_from_sensor().inverse() * self.base_from_cable;
        let pad_centre_in_cable = sensor_from_cable.inverse().translation.vector;
        let mut u_mm = pad_centre_in_cable.x;
        let mut line = None;
        for _ in 0..NEAREST_POINT_STEPS {
            let (height_mm, slope) = self.cable.height_and_slope(u_mm);
            let point = sensor_from_cable * nalgebra::Point3::new(u_mm, height_mm, 0.0);
            let tangent = sensor_from_cable.rotation * Vector3::new(1.0, slope, 0.0);
            let in_plane = Vector2::new(tangent.x, tangent.y);
            let squared = in_plane.norm_squared();
            if squared < 1e-12 {
                return None;
            }
            line = Some(LineInSensor::through(point.coords.xy(), in_plane));
            // Slide along the tangent to the foot of the perpendicular
            // from the pad's centre.
            u_mm -= point.coords.xy().dot(&in_plane) / squared;
        }
        line
    }

    /// The jaws close: the cable is caught if it lies within reach of the
    /// fingers, and settles on the pad towards its axis.
    pub fn close_on_cable(&mut self, squeeze_fraction: f64) -> Option<LineInSensor> {
        let caught = self
            .cable_in_sensor()
            .filter(|line| line.n_mm.abs() <= self.capture_half_height_mm)?;
        let caught_line_from_cable = planar_to_spatial(&caught.sensor_from_line()).inverse()
            * self.base_from_sensor().inverse()
            * self.base_from_cable;
        let held = self.cable.settled(&caught);
        self.grasp = Some(Grasp {
            caught,
            held,
            caught_line_from_cable,
        });
        self.squeeze_fraction = squeeze_fraction;
        Some(held)
    }

    /// The jaws open: the cable springs back, partly, towards where it was
    /// caught, and stays there as the new free cable.
    pub fn release(&mut self) {
        if let Some(grasp) = self.grasp.take() {
            let free = self.cable.released(&grasp.caught, &grasp.held);
            self.base_from_cable = self.base_from_sensor()
                * planar_to_spatial(&free.sensor_from_line())
                * grasp.caught_line_from_cable;
        }
        self.squeeze_fraction = 0.0;
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
    use crate::sim::cable::tests::config;
    use approx::assert_relative_eq;

    /// A stiff straight cable: no sag, no settle, no spring-back.
    fn world(tilt_rad: f64) -> SimWorld {
        let config = WorldConfig {
            cable_tilt_rad: tilt_rad,
            cable_weight_n_mm: 0.0,
            settle_fraction: 0.0,
            spring_back_fraction: 0.0,
            ..config()
        };
        SimWorld::new(&config, tcp_from_sensor())
    }

    fn tcp_from_sensor() -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(0.0, 0.0, -10.0),
            UnitQuaternion::from_euler_angles(-std::f64::consts::FRAC_PI_2, 0.0, 0.0),
        )
    }

    fn over(world: &SimWorld, base_from_sensor: Isometry3<f64>) -> Isometry3<f64> {
        base_from_sensor * world.tcp_from_sensor.inverse()
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
        let mut world = SimWorld::new(&config(), tcp_from_sensor());
        world.base_from_tcp = over(&world, world.base_from_cable);
        let line = world.close_on_cable(0.05).unwrap();
        assert_relative_eq!(line.alpha_rad, 0.0, epsilon = 1e-9);
        assert_relative_eq!(line.n_mm, 0.0, epsilon = 1e-9);
    }

    #[test]
    fn a_tilted_cable_grasped_level_lies_at_its_tilt() {
        let mut world = world(0.2);
        let level = cable_frame([450.0, 0.0, 250.0], 0.3, 0.0);
        // Grasp 2 mm too low: the cable's midpoint sits 2 mm up the pad
        // (towards +y), and the line through it at 0.2 rad is 2 cos 0.2 mm
        // from the pad's centre.
        world.base_from_tcp = Translation3::new(0.0, 0.0, -2.0) * over(&world, level);
        let line = world.close_on_cable(0.05).unwrap();
        assert_relative_eq!(line.alpha_rad, 0.2, epsilon = 1e-9);
        assert_relative_eq!(line.n_mm, 2.0 * 0.2_f64.cos(), epsilon = 1e-9);
    }

    #[test]
    fn a_cable_out_of_reach_is_not_caught() {
        let mut world = world(0.0);
        world.base_from_tcp =
            Translation3::new(0.0, 0.0, 20.0) * over(&world, world.base_from_cable);
        assert!(world.close_on_cable(0.05).is_none());
        assert!(world.grasp.is_none());
    }

    #[test]
    fn off_the_midpoint_the_pad_sees_the_sags_slope_and_height() {
        let mut world = SimWorld::new(&config(), tcp_from_sensor());
        let u_mm = 20.0;
        let (height_mm, slope) = world.cable.height_and_slope(u_mm);
        let along = world.base_from_cable * Translation3::new(u_mm, 0.0, 0.0);
        world.base_from_tcp = over(&world, along);
        let caught = world.cable_in_sensor().unwrap();
        // The pad sees the tangent at the foot of its perpendicular, a
        // little short of u (by about h s), where the slope is a little
        // smaller: to first order in the sag's curvature, the tangent at u,
        // which passes h cos(atan s) above the pad's centre.
        assert_relative_eq!(caught.alpha_rad, slope.atan(), epsilon = 1e-3);
        assert_relative_eq!(caught.n_mm, height_mm * slope.atan().cos(), epsilon = 1e-3);
        assert!(height_mm > 0.5, "{height_mm}");
    }

    #[test]
    fn settle_and_spring_back_leave_the_cable_where_the_model_says() {
        let mut world = SimWorld::new(&config(), tcp_from_sensor());
        // Grasp 3 mm too high and turned by 0.2 rad about the closing axis.
        let sensor = world.base_from_cable
            * Translation3::new(0.0, 3.0, 0.0)
            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.2);
        world.base_from_tcp = over(&world, sensor);
        let caught = world.cable_in_sensor().unwrap();
        let held = world.close_on_cable(0.05).unwrap();
        assert_eq!(held, world.cable.settled(&caught));
        assert!(held.n_mm.abs() < caught.n_mm.abs());
        world.release();
        let free = world.cable_in_sensor().unwrap();
        let expected = world.cable.released(&caught, &held);
        assert_relative_eq!(free.alpha_rad, expected.alpha_rad, epsilon = 1e-6);
        assert_relative_eq!(free.n_mm, expected.n_mm, epsilon = 1e-6);
        assert!(world.grasp.is_none());
    }

    #[test]
    fn the_true_centre_line_follows_the_held_line_over_the_pad() {
        let mut world = SimWorld::new(&config(), tcp_from_sensor());
        assert!(world.true_centre_line(8.875).is_none());
        // Grasp 3 mm off the midpoint across the cable: the jaws move it.
        let sensor = world.base_from_cable * Translation3::new(0.0, 3.0, 0.0);
        world.base_from_tcp = over(&world, sensor);
        let held = world.close_on_cable(0.05).unwrap();
        let line = world.true_centre_line(8.875).unwrap();
        let sensor_from_base = world.base_from_sensor().inverse();
        let in_sensor: Vec<Point3<f64>> = line.iter().map(|p| sensor_from_base * p).collect();
        // From support to support, in order along the pad's x.
        assert!(
            in_sensor.windows(2).all(|w| w[1].x > w[0].x),
            "{in_sensor:?}"
        );
        assert!(in_sensor[0].x < -70.0 && in_sensor[in_sensor.len() - 1].x > 70.0);
        for p in &in_sensor {
            if p.x.abs() <= 8.875 {
                let off = held.distance_mm(Vector2::new(p.x, p.y));
                assert!(off.abs() < 1e-9, "{p}: {off}");
            } else {
                // The free cable: its height above the midpoint at u.
                let in_cable = world.base_from_cable.inverse() * (world.base_from_sensor() * p);
                let (height_mm, _) = world.cable.height_and_slope(in_cable.x);
                assert!((in_cable.y - height_mm).abs() < 1e-9, "{in_cable}");
            }
        }
        // The jaws moved the cable: it steps at the pad's edge.
        assert!(held.n_mm.abs() < world.grasp.unwrap().caught.n_mm.abs());
    }

    #[test]
    fn without_spring_back_the_cable_stays_where_it_was_held() {
        let config = WorldConfig {
            spring_back_fraction: 0.0,
            ..config()
        };
        let mut world = SimWorld::new(&config, tcp_from_sensor());
        let sensor = world.base_from_cable * Translation3::new(0.0, -2.0, 0.0);
        world.base_from_tcp = over(&world, sensor);
        let held = world.close_on_cable(0.05).unwrap();
        world.release();
        let free = world.cable_in_sensor().unwrap();
        assert_relative_eq!(free.n_mm, held.n_mm, epsilon = 1e-6);
        assert_relative_eq!(free.alpha_rad, held.alpha_rad, epsilon = 1e-6);
    }
}
