//! The fusion of the paper's Fig. 12: one cubic B-spline refitted to the
//! camera's and the pad's points of a cable together, each weighted by
//! 1/σ², along the pad's x at the grasp. Where the pad is sure it dominates;
//! where the camera was blocked only the pad and the spline's smoothness
//! hold the curve; away from the pad the camera's points hold it alone.

use nalgebra::{Isometry3, Point3};

use super::shape::{SHAPE_SPACING_MM, ShapePoint};
use super::vision::spline::{BSpline, Sample};

/// Length of cable per control point of the fused curve: fine enough to
/// pass from the pad's line to the camera's curve within a third of the
/// pad's length, coarse enough that a stretch of a few millimetres with no
/// point does not let the curve swing.
pub const FUSED_MM_PER_CONTROL_POINT: f64 = 6.0;

/// The prior on how the cable bends, as white noise in its curvature:
/// the curvature's variance times the length over which it holds,
/// `BEND_PRIOR_CURVATURE_PER_MM² × BEND_PRIOR_LENGTH_MM` (1/mm). Where
/// only one source sees the cable, the curve carries its direction on
/// by this much before bending towards the other.
fn bend_prior_per_mm() -> f64 {
    BEND_PRIOR_CURVATURE_PER_MM * BEND_PRIOR_CURVATURE_PER_MM * BEND_PRIOR_LENGTH_MM
}

/// A cable between supports bends about this much (1/mm): the shipped
/// simulated cable's sag is 1/213 mm at its middle.
pub const BEND_PRIOR_CURVATURE_PER_MM: f64 = 1.0 / 200.0;

/// Over about this length a cable's curvature keeps its value.
pub const BEND_PRIOR_LENGTH_MM: f64 = 50.0;

/// Points spread over more than this are no one cable the cell can
/// grasp (its arm reaches about a metre): such a shape would be a point a
/// millimetre for ever, and its control points would overflow a count.
const MAX_FUSED_LENGTH_MM: f64 = 10_000.0;

/// Below this a point's σ counts as this: a source that claims to be exact
/// (a noiseless oracle) must not make the system singular.
const MIN_SIGMA_MM: f64 = 0.01;

/// The cable through every point of `sources`, parameterised along the
/// x-axis of `base_from_plane` (a frame in the pad's plane at the grasp, x
/// along the cable): the points are taken in that frame, and their y
/// (across the cable in the pad's plane) and z (the depth from it) are
/// fitted against x by one B-spline with weights 1/σ². The curve comes
/// back in the base frame one [`SHAPE_SPACING_MM`] apart in x, each point
/// with the fit's standard deviation there.
///
/// The cable must run along the frame's x and not turn back on itself
/// along it (a cable between two supports, grasped across). `None` if the
/// points span no length, or more than any cable (10 m).
pub fn fuse(
    sources: &[&[ShapePoint]],
    base_from_plane: &Isometry3<f64>,
) -> Option<Vec<ShapePoint>> {
    let plane_from_base = base_from_plane.inverse();
    let in_plane: Vec<(Point3<f64>, f64)> = sources
        .iter()
        .flat_map(|points| points.iter())
        .map(|point| {
            let sigma_mm = point.sigma_mm.max(MIN_SIGMA_MM);
            (
                plane_from_base * point.in_base_mm,
                1.0 / (sigma_mm * sigma_mm),
            )
        })
        .filter(|(p, weight)| p.coords.iter().all(|v| v.is_finite()) && weight.is_finite())
        .collect();
    let x_min = in_plane
        .iter()
        .map(|(p, _)| p.x)
        .fold(f64::INFINITY, f64::min);
    let x_max = in_plane
        .iter()
        .map(|(p, _)| p.x)
        .fold(f64::NEG_INFINITY, f64::max);
    let length_mm = x_max - x_min;
    if length_mm <= SHAPE_SPACING_MM || length_mm > MAX_FUSED_LENGTH_MM {
        return None;
    }
    // x is the parameter itself; the curve fitted is (y, z) against it.
    let samples: Vec<Sample> = in_plane
        .iter()
        .map(|&(p, weight)| Sample {
            point: [p.y, p.z],
            s: (p.x - x_min) / length_mm,
            weight,
        })
        .collect();
    let control_points = (length_mm / FUSED_MM_PER_CONTROL_POINT).ceil() as usize + 3;
    // f'' ≈ Δ²c / h² over each knot span h, so ∫ f''² dx / q is about
    // Σ (Δ²c)² / (q h³).
    let span_mm = length_mm / (control_points - 3) as f64;
    let bending_weight = 1.0 / (bend_prior_per_mm() * span_mm.powi(3));
    let fit = BSpline::fit_weighted(&samples, control_points, bending_weight)?;
    let steps = (length_mm / SHAPE_SPACING_MM).round() as usize;
    Some(
        (0..=steps)
            .map(|k| {
                let s = k as f64 / steps as f64;
                let [y, z] = fit.spline.point(s);
                ShapePoint {
                    in_base_mm: base_from_plane * Point3::new(x_min + s * length_mm, y, z),
                    sigma_mm: fit.sigma(s),
                }
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use nalgebra::{Translation3, UnitQuaternion};

    use super::*;

    /// The plane: the pad's at a grasp, x along the cable, turned and
    /// placed anywhere in the base frame.
    fn base_from_plane() -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(450.0, 3.0, 250.0),
            UnitQuaternion::from_euler_angles(-1.4, 0.2, 0.1),
        )
    }

    /// Points one millimetre apart at x in `xs` of the plane, on `y(x)`.
    fn points(
        xs: impl Iterator<Item = i32>,
        y: impl Fn(f64) -> f64,
        sigma_mm: f64,
    ) -> Vec<ShapePoint> {
        xs.map(|x| {
            let x = f64::from(x);
            ShapePoint {
                in_base_mm: base_from_plane() * Point3::new(x, y(x), 0.0),
                sigma_mm,
            }
        })
        .collect()
    }

    /// The fused curve's y at plane x (interpolated between its points),
    /// and its σ there.
    fn at(fused: &[ShapePoint], x: f64) -> (f64, f64) {
        let plane = base_from_plane().inverse();
        let local: Vec<(Point3<f64>, f64)> = fused
            .iter()
            .map(|p| (plane * p.in_base_mm, p.sigma_mm))
            .collect();
        let k = local
            .windows(2)
            .position(|w| w[0].0.x <= x && x <= w[1].0.x)
            .unwrap_or_else(|| panic!("x {x} outside the fused curve"));
        let (a, b) = (local[k], local[k + 1]);
        let t = (x - a.0.x) / (b.0.x - a.0.x);
        (a.0.y + t * (b.0.y - a.0.y), a.1 + t * (b.1 - a.1))
    }

    /// A circle's arc of radius 400 mm through the origin, tangent to x:
    /// a sagging cable's bend.
    fn arc(x: f64) -> f64 {
        400.0 - (400.0f64 * 400.0 - x * x).sqrt()
    }

    #[test]
    fn on_a_straight_cable_touch_wins_on_the_pad_and_vision_beyond_it() {
        // The camera sees the cable 0.8 mm too high everywhere; the pad
        // sees it where it is.
        let vision = points(-80..=80, |_| 0.8, 0.8);
        let touch = points(-9..=9, |_| 0.0, 0.1);
        let fused = fuse(&[&vision, &touch], &base_from_plane()).unwrap();
        let (y, sigma) = at(&fused, 0.0);
        assert!(y.abs() < 0.05, "on the pad: {y}");
        assert!(sigma < 0.05, "{sigma}");
        for x in [-60.0, -40.0, 40.0, 60.0] {
            let (y, sigma) = at(&fused, x);
            assert!((y - 0.8).abs() < 0.05, "at {x}: {y}");
            assert!(sigma > 0.1, "at {x}: {sigma}");
        }
        // Every point lies in the plane, where both sources are.
        let plane = base_from_plane().inverse();
        assert!(fused.iter().all(|p| (plane * p.in_base_mm).z.abs() < 1e-9));
    }

    #[test]
    fn a_bent_cable_hidden_around_the_pad_is_held_by_touch_and_smoothness() {
        // The camera sees the bend but not within 30 mm of the grasp; the
        // pad sees its middle.
        let vision = points((-90..=90).filter(|x: &i32| x.abs() > 30), arc, 0.5);
        let touch = points(-9..=9, arc, 0.1);
        let fused = fuse(&[&vision, &touch], &base_from_plane()).unwrap();
        for x in (-80..=80).step_by(5).map(f64::from) {
            let (y, _) = at(&fused, x);
            assert!((y - arc(x)).abs() < 0.1, "at {x}: {y} against {}", arc(x));
        }
        // Surer on the pad than where nothing was seen.
        assert!(at(&fused, 0.0).1 < at(&fused, 20.0).1);
    }

    #[test]
    fn touch_past_the_end_of_what_vision_saw_extends_the_curve() {
        // The camera lost the cable at x = 0 (an occluder beyond); the pad
        // holds it from 5 to 23 mm, where the bend goes on.
        let vision = points(-80..=0, arc, 0.5);
        let touch = points(5..=23, arc, 0.1);
        let fused = fuse(&[&vision, &touch], &base_from_plane()).unwrap();
        for x in [-70.0, -30.0, 0.0, 2.0, 10.0, 14.0, 22.0] {
            let (y, _) = at(&fused, x);
            assert!((y - arc(x)).abs() < 0.1, "at {x}: {y} against {}", arc(x));
        }
        let plane = base_from_plane().inverse();
        let last = plane * fused[fused.len() - 1].in_base_mm;
        assert!((last.x - 23.0).abs() < 1e-3, "{last}");
    }

    #[test]
    fn the_tactile_stretch_at_the_end_of_a_straight_cable_moves_only_that_end() {
        // Vision 1 mm off at its right end only, where the pad holds it.
        let vision = points(-80..=20, |x| if x > 0.0 { 1.0 } else { 0.0 }, 0.8);
        let touch = points(2..=20, |_| 0.0, 0.1);
        let fused = fuse(&[&vision, &touch], &base_from_plane()).unwrap();
        assert!(at(&fused, 12.0).0.abs() < 0.1, "{:?}", at(&fused, 12.0));
        assert!(at(&fused, -40.0).0.abs() < 0.05);
    }

    #[test]
    fn the_depth_is_fused_as_well() {
        // The camera puts the cable 2 mm behind the pad's plane, the pad in
        // it: near the pad the pad's depth, far from it the camera's.
        let vision: Vec<ShapePoint> = (-80..=80)
            .map(|x| ShapePoint {
                in_base_mm: base_from_plane() * Point3::new(f64::from(x), 0.0, -2.0),
                sigma_mm: 0.8,
            })
            .collect();
        let touch = points(-9..=9, |_| 0.0, 0.1);
        let fused = fuse(&[&vision, &touch], &base_from_plane()).unwrap();
        let plane = base_from_plane().inverse();
        let depth_at = |x: f64| {
            let nearest = fused
                .iter()
                .map(|p| plane * p.in_base_mm)
                .min_by(|a, b| (a.x - x).abs().total_cmp(&(b.x - x).abs()))
                .unwrap();
            nearest.z
        };
        assert!(depth_at(0.0).abs() < 0.1, "{}", depth_at(0.0));
        assert!((depth_at(60.0) + 2.0).abs() < 0.05, "{}", depth_at(60.0));
    }

    #[test]
    fn one_source_alone_is_smoothed_not_moved_and_nothing_gives_none() {
        let touch = points(-9..=9, |x| 0.002 * x * x, 0.1);
        let fused = fuse(&[&touch], &base_from_plane()).unwrap();
        assert_eq!(fused.len(), 19);
        assert!(
            (at(&fused, 5.0).0 - 0.05).abs() < 0.005,
            "{:?}",
            at(&fused, 5.0)
        );
        assert!(fuse(&[], &base_from_plane()).is_none());
        let one = points(0..=0, |_| 0.0, 0.1);
        assert!(fuse(&[&one, &one], &base_from_plane()).is_none());
        // An exact point does not break the fit.
        let exact = points(-9..=9, |_| 0.0, 0.0);
        assert!(fuse(&[&exact], &base_from_plane()).is_some());
    }

    /// Found by tests/numerical_stress.rs: points 1e300 mm apart made the
    /// control point count overflow (a panic), and would have made the
    /// shape a point a millimetre for ever.
    #[test]
    fn points_spread_beyond_any_cable_fuse_to_nothing() {
        let point = |x_mm: f64| ShapePoint {
            in_base_mm: Point3::new(x_mm, 0.0, 0.0),
            sigma_mm: 0.1,
        };
        let far = [point(0.0), point(1.0), point(1e300)];
        assert!(fuse(&[&far], &Isometry3::identity()).is_none());
        let cable = [point(0.0), point(10.0), point(20.0), point(30.0)];
        assert_eq!(
            fuse(&[&cable], &Isometry3::identity()).map(|s| s.len()),
            Some(31)
        );
    }
}
