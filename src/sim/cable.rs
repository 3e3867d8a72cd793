//! The cable: an elastic beam resting on two supports, sagging under its
//! own weight, that the closing jaws drag part of the way towards the
//! pad's axis and that springs back, partly, when they open.
//!
//! How far the jaws drag it and how far it springs back depend on how stiff
//! the cable is against each move, and each move has its own stiffness: the
//! beam's resistance to a shift of its midpoint, 48 EI / L³, and to a turn
//! of it, 12 EI / L, felt at the jaws' half-width as 12 EI / (L a²). For a
//! cable between supports a hand's width apart the turn is some seventy
//! times stiffer than the shift: the jaws shift a cable easily but hardly
//! turn it, and what they turn springs back. Against each, two frictions:
//! the closing jaws' drag (strong) and what holds a bend once they open
//! (the strands' internal friction, the silicone's grip; weak).
//!
//! See docs/simulated-cell.md for the model and the reasons for its values.

use nalgebra::Point3;

use super::world::WorldConfig;
use crate::geometry::LineInSensor;

/// Half the width of the jaws' pads, the lever of a turn of the cable
/// between them: the cap's half side, 2.5 pitches of 3.55 mm.
const JAW_HALF_WIDTH_MM: f64 = 8.875;

/// How the cable moves in one of its two in-plane modes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeFractions {
    /// Fraction of the caught error the closing jaws remove.
    pub settle: f64,
    /// Fraction of the displacement the grasp imposed that the cable
    /// recovers when the jaws open.
    pub spring_back: f64,
}

impl ModeFractions {
    /// The fractions of a mode of stiffness `stiffness_n_mm`.
    fn new(config: &WorldConfig, stiffness_n_mm: f64) -> Self {
        let drag = config.jaw_drag_stiffness_n_mm;
        let hold = config.hold_stiffness_n_mm;
        Self {
            settle: config.settle_fraction * drag / (drag + stiffness_n_mm),
            spring_back: config.spring_back_fraction * stiffness_n_mm / (stiffness_n_mm + hold),
        }
    }
}

/// The cable's mechanics, from the world's configuration.
#[derive(Debug, Clone, Copy)]
pub struct CableModel {
    /// Distance between the two supports.
    pub span_mm: f64,
    /// Drop of the midpoint below the supports.
    pub sag_mm: f64,
    /// Weight per length over bending stiffness, q / EI (1/mm³): the
    /// beam's load term, which fixes the sag's shape.
    load_per_stiffness_per_mm3: f64,
    /// A shift across the pad (the offset n).
    pub shift: ModeFractions,
    /// A turn in the pad's plane (the angle α).
    pub turn: ModeFractions,
}

impl CableModel {
    pub fn new(config: &WorldConfig) -> Self {
        let ei = config.bending_stiffness_n_mm2;
        let span = config.support_span_mm;
        let load_per_stiffness_per_mm3 = config.cable_weight_n_mm / ei;
        let shift_stiffness_n_mm = 48.0 * ei / span.powi(3);
        let turn_stiffness_n_mm = 12.0 * ei / (span * JAW_HALF_WIDTH_MM * JAW_HALF_WIDTH_MM);
        Self {
            span_mm: span,
            sag_mm: 5.0 * load_per_stiffness_per_mm3 * span.powi(4) / 384.0,
            load_per_stiffness_per_mm3,
            shift: ModeFractions::new(config, shift_stiffness_n_mm),
            turn: ModeFractions::new(config, turn_stiffness_n_mm),
        }
    }

    /// Height of the free cable above its midpoint at `u_mm` along it from
    /// the midpoint, and the slope there: the deflection of a simply
    /// supported beam under its own weight, w(x) = q x (L³ − 2 L x² + x³)
    /// / 24 EI, measured from its lowest point. Beyond the supports the
    /// cable goes on straight along its end slope (a smooth stand-in for
    /// the overhang, which the pad never reaches).
    pub fn height_and_slope(&self, u_mm: f64) -> (f64, f64) {
        let half = self.span_mm / 2.0;
        let u = u_mm.clamp(-half, half);
        let x = u + half;
        let l = self.span_mm;
        let k = self.load_per_stiffness_per_mm3 / 24.0;
        let deflection = k * x * (l.powi(3) - 2.0 * l * x * x + x.powi(3));
        let slope = -k * (l.powi(3) - 6.0 * l * x * x + 4.0 * x.powi(3));
        let height = self.sag_mm - deflection;
        (height + slope * (u_mm - u), slope)
    }

    /// The free cable between its supports, in its midpoint frame (x along
    /// the line between the supports, y up), a point every `spacing_mm`
    /// along x from one support to the other.
    pub fn centre_line_mm(&self, spacing_mm: f64) -> Vec<Point3<f64>> {
        let half_steps = (self.span_mm / 2.0 / spacing_mm).floor() as i64;
        (-half_steps..=half_steps)
            .map(|k| {
                let u_mm = k as f64 * spacing_mm;
                Point3::new(u_mm, self.height_and_slope(u_mm).0, 0.0)
            })
            .collect()
    }

    /// Where the jaws leave the cable they caught at `caught`: moved
    /// towards the pad's x-axis (offset and angle) by the settle fraction.
    pub fn settled(&self, caught: &LineInSensor) -> LineInSensor {
        LineInSensor::new(
            caught.alpha_rad * (1.0 - self.turn.settle),
            caught.n_mm * (1.0 - self.shift.settle),
        )
    }

    /// Where the cable held at `held` comes to rest when the jaws open:
    /// back towards where it was caught by the spring-back fraction of the
    /// displacement the grasp imposed.
    pub fn released(&self, caught: &LineInSensor, held: &LineInSensor) -> LineInSensor {
        LineInSensor::new(
            held.alpha_rad + self.turn.spring_back * (caught.alpha_rad - held.alpha_rad),
            held.n_mm + self.shift.spring_back * (caught.n_mm - held.n_mm),
        )
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use approx::assert_relative_eq;

    pub(crate) fn config() -> WorldConfig {
        WorldConfig {
            cable_diameter_mm: 2.5,
            cable_center_mm: [450.0, 0.0, 250.0],
            cable_yaw_rad: 0.3,
            cable_tilt_rad: 0.0,
            capture_half_height_mm: 12.0,
            support_span_mm: 150.0,
            cable_weight_n_mm: 1e-4,
            bending_stiffness_n_mm2: 60.0,
            jaw_drag_stiffness_n_mm: 1e-3,
            hold_stiffness_n_mm: 2e-4,
            settle_fraction: 1.0,
            spring_back_fraction: 1.0,
        }
    }

    #[test]
    fn the_sag_is_a_simply_supported_beams() {
        let cable = CableModel::new(&config());
        // 5 q L⁴ / 384 EI = 5 · 1e-4 · 150⁴ / (384 · 60) mm.
        assert_relative_eq!(cable.sag_mm, 10.986328125, epsilon = 1e-9);
        let (mid, mid_slope) = cable.height_and_slope(0.0);
        assert_relative_eq!(mid, 0.0, epsilon = 1e-9);
        assert_relative_eq!(mid_slope, 0.0, epsilon = 1e-12);
        let (end, end_slope) = cable.height_and_slope(75.0);
        assert_relative_eq!(end, cable.sag_mm, epsilon = 1e-9);
        // q L³ / 24 EI at the supports, rising outwards.
        assert_relative_eq!(
            end_slope,
            1e-4 * 150f64.powi(3) / (24.0 * 60.0),
            epsilon = 1e-12
        );
        let (left, left_slope) = cable.height_and_slope(-30.0);
        let (right, right_slope) = cable.height_and_slope(30.0);
        assert_relative_eq!(left, right, epsilon = 1e-9);
        assert_relative_eq!(left_slope, -right_slope, epsilon = 1e-12);
    }

    #[test]
    fn the_fractions_follow_the_beams_stiffness_against_the_frictions() {
        let cable = CableModel::new(&config());
        // Shift: 48 · 60 / 150³ = 8.533e-4 N/mm.
        let shift = 48.0 * 60.0 / 150f64.powi(3);
        assert_relative_eq!(cable.shift.settle, 1e-3 / (1e-3 + shift), epsilon = 1e-12);
        assert_relative_eq!(
            cable.shift.spring_back,
            shift / (shift + 2e-4),
            epsilon = 1e-12
        );
        // A turn is far stiffer: it hardly settles, and springs back.
        assert!(cable.turn.settle < 0.05, "{:?}", cable.turn);
        assert!(cable.turn.spring_back > 0.99, "{:?}", cable.turn);
    }

    #[test]
    fn settling_moves_the_cable_towards_the_pads_axis_by_its_fractions() {
        let cable = CableModel::new(&config());
        let held = cable.settled(&LineInSensor::new(0.3, 4.0));
        assert_relative_eq!(
            held.alpha_rad,
            0.3 * (1.0 - cable.turn.settle),
            epsilon = 1e-12
        );
        assert_relative_eq!(held.n_mm, 4.0 * (1.0 - cable.shift.settle), epsilon = 1e-12);
        assert!(held.n_mm < 2.5, "a limp cable's shift settles by half");
    }

    #[test]
    fn spring_back_moves_the_cable_back_by_its_fractions() {
        let cable = CableModel::new(&config());
        let caught = LineInSensor::new(0.3, 4.0);
        let held = LineInSensor::new(0.2, 3.0);
        let free = cable.released(&caught, &held);
        assert_relative_eq!(
            free.alpha_rad,
            0.2 + 0.1 * cable.turn.spring_back,
            epsilon = 1e-12
        );
        assert_relative_eq!(free.n_mm, 3.0 + cable.shift.spring_back, epsilon = 1e-12);
    }

    #[test]
    fn a_stiffer_cable_springs_back_more_and_settles_less() {
        let soft = CableModel::new(&config());
        let stiff = CableModel::new(&WorldConfig {
            bending_stiffness_n_mm2: 240.0,
            ..config()
        });
        assert!(stiff.shift.spring_back > soft.shift.spring_back);
        assert!(stiff.shift.settle < soft.shift.settle);
        assert!(stiff.turn.spring_back > soft.turn.spring_back);
        assert!(stiff.turn.settle < soft.turn.settle);
        assert!(stiff.sag_mm < soft.sag_mm);
    }

    #[test]
    fn zero_fractions_switch_the_sources_off() {
        let cable = CableModel::new(&WorldConfig {
            settle_fraction: 0.0,
            spring_back_fraction: 0.0,
            ..config()
        });
        let caught = LineInSensor::new(0.3, 4.0);
        assert_eq!(cable.settled(&caught), caught);
        let held = LineInSensor::new(0.1, 1.0);
        assert_eq!(cable.released(&caught, &held), held);
    }
}
