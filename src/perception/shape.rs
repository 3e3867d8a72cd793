//! A cable's shape in the base frame, whatever saw it: points along its
//! centre line one [`SHAPE_SPACING_MM`] apart, each with its standard
//! deviation. The tactile fits' curves become such shapes over the pad, and
//! any shape is measured against the true cable over the grasped stretch
//! and beyond it.

use nalgebra::{DMatrix, DVector, Isometry3, Point2, Point3, Vector2};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::tactile::{Centroid, Direction, Quadratic};
use crate::geometry::LineInSensor;

/// The spacing of every shape's points along the cable: one spacing for
/// every source, so that weights of 1/σ² compare per length of cable.
pub const SHAPE_SPACING_MM: f64 = 1.0;

/// How far beyond each end of the pad a shape is measured against the
/// true cable: about two pad lengths, the stretch a regrasp or a routing
/// move would use, where only the camera sees the cable.
pub const BEYOND_PAD_MM: f64 = 30.0;

/// One point of a cable's centre line.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ShapePoint {
    #[schemars(with = "[f64; 3]")]
    pub in_base_mm: Point3<f64>,
    /// Standard deviation of the point across the cable.
    pub sigma_mm: f64,
}

/// A curve of a tactile fit in the pad's plane (sensor frame, mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TactileCurve {
    /// The linear fit (eq. 2), or the ridge's line.
    Line(LineInSensor),
    /// The quadratic fit: `y = a x² + b x + c` for a horizontal cable
    /// (eq. 3), `x = a y² + b y + c` for a vertical one (eq. 4).
    Quadratic(Direction, Quadratic),
}

impl TactileCurve {
    /// Points of the curve one [`SHAPE_SPACING_MM`] apart (about, for the
    /// quadratic) inside the square of half side `half_side_mm` about the
    /// pad's centre, in the sensor frame.
    pub fn points_in_sensor(&self, half_side_mm: f64) -> Vec<Point2<f64>> {
        let steps = (half_side_mm / SHAPE_SPACING_MM).floor() as i64;
        let inside = |p: &Point2<f64>| p.x.abs() <= half_side_mm && p.y.abs() <= half_side_mm;
        match *self {
            TactileCurve::Line(line) => {
                let foot = line.normal() * line.n_mm;
                let along = Vector2::new(line.alpha_rad.cos(), line.alpha_rad.sin());
                // The square's half diagonal bounds the chord inside it.
                let reach =
                    (std::f64::consts::SQRT_2 * half_side_mm / SHAPE_SPACING_MM).ceil() as i64;
                (-reach..=reach)
                    .map(|k| Point2::from(foot + along * (k as f64 * SHAPE_SPACING_MM)))
                    .filter(inside)
                    .collect()
            }
            TactileCurve::Quadratic(direction, q) => (-steps..=steps)
                .map(|k| {
                    let u = k as f64 * SHAPE_SPACING_MM;
                    let t = q.a * u * u + q.b * u + q.c;
                    match direction {
                        Direction::Horizontal => Point2::new(u, t),
                        Direction::Vertical => Point2::new(t, u),
                    }
                })
                .filter(inside)
                .collect(),
        }
    }

    /// The curve's direction at the pad's centre (or across from it), as
    /// an angle from the pad's x in (-π/2, π/2].
    pub fn angle_at_centre_rad(&self) -> f64 {
        match *self {
            TactileCurve::Line(line) => line.alpha_rad,
            TactileCurve::Quadratic(Direction::Horizontal, q) => q.b.atan(),
            TactileCurve::Quadratic(Direction::Vertical, q) => {
                LineInSensor::through(Vector2::zeros(), Vector2::new(q.b, 1.0)).alpha_rad
            }
        }
    }

    /// The curve's standard deviation along the pad, from how the
    /// centroids it was fitted to scatter about it: the least-squares
    /// standard error at each point (the residuals' variance times the
    /// point's leverage), with `floor_mm` added in quadrature for what the
    /// residuals cannot show (the centroids' truncation at the pad's edge
    /// is a bias, not a scatter).
    pub fn sigma_from_centroids(
        &self,
        centroids: &[Centroid],
        direction: Direction,
        floor_mm: f64,
    ) -> impl Fn(Point2<f64>) -> f64 + use<> {
        let main_axis = move |x_mm: f64, y_mm: f64| match direction {
            Direction::Horizontal => x_mm,
            Direction::Vertical => y_mm,
        };
        let (params, residuals): (usize, Vec<f64>) = match *self {
            TactileCurve::Line(line) => (
                2,
                centroids
                    .iter()
                    .map(|c| line.distance_mm(Vector2::new(c.x_mm, c.y_mm)))
                    .collect(),
            ),
            TactileCurve::Quadratic(direction, q) => (
                3,
                centroids
                    .iter()
                    .map(|c| {
                        let (u, t) = match direction {
                            Direction::Horizontal => (c.x_mm, c.y_mm),
                            Direction::Vertical => (c.y_mm, c.x_mm),
                        };
                        t - (q.a * u * u + q.b * u + q.c)
                    })
                    .collect(),
            ),
        };
        let us: Vec<f64> = centroids
            .iter()
            .map(|c| main_axis(c.x_mm, c.y_mm))
            .collect();
        let leverage = Leverage::new(&us, &residuals, params);
        move |p: Point2<f64>| {
            let u = main_axis(p.x, p.y);
            let fit_variance = leverage.as_ref().map_or(0.0, |l| l.variance(u));
            (fit_variance + floor_mm * floor_mm).sqrt()
        }
    }

    /// The curve over the square of half side `half_side_mm` as a shape
    /// in the base frame, each point with `sigma_mm` of its place.
    pub fn shape(
        &self,
        base_from_sensor: &Isometry3<f64>,
        half_side_mm: f64,
        sigma_mm: impl Fn(Point2<f64>) -> f64,
    ) -> Vec<ShapePoint> {
        self.points_in_sensor(half_side_mm)
            .into_iter()
            .map(|p| ShapePoint {
                in_base_mm: base_from_sensor * Point3::new(p.x, p.y, 0.0),
                sigma_mm: sigma_mm(p),
            })
            .collect()
    }
}

/// A polynomial least-squares fit's standard error along its axis.
struct Leverage {
    /// The residuals' variance, unbiased.
    residual_variance: f64,
    /// The inverse of the design's normal matrix.
    inverse_normal: DMatrix<f64>,
}

impl Leverage {
    /// `None` with no degree of freedom left to see a scatter.
    fn new(us: &[f64], residuals: &[f64], params: usize) -> Option<Self> {
        let dof = us.len().checked_sub(params).filter(|&d| d > 0)?;
        let rss: f64 = residuals.iter().map(|r| r * r).sum();
        let design = DMatrix::from_fn(us.len(), params, |i, k| us[i].powi(k as i32));
        let inverse_normal = (design.transpose() * design).try_inverse()?;
        Some(Self {
            residual_variance: rss / dof as f64,
            inverse_normal,
        })
    }

    fn variance(&self, u: f64) -> f64 {
        let phi = DVector::from_fn(self.inverse_normal.nrows(), |k, _| u.powi(k as i32));
        self.residual_variance * phi.dot(&(&self.inverse_normal * &phi)).max(0.0)
    }
}

/// `points` (in order along a cable) again, one `spacing_mm` apart along
/// the polyline through them, from the first; with the last if it is more
/// than a tenth of a spacing past the one before.
pub fn resample(points: &[Point3<f64>], spacing_mm: f64) -> Vec<Point3<f64>> {
    let Some(&first) = points.first() else {
        return Vec::new();
    };
    let mut out = vec![first];
    let mut to_next = spacing_mm;
    for pair in points.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let length = (b - a).norm();
        let mut at = 0.0;
        while length - at >= to_next {
            at += to_next;
            out.push(a + (b - a) * (at / length));
            to_next = spacing_mm;
        }
        to_next -= length - at;
    }
    if let Some(&last) = points.last()
        && spacing_mm - to_next > 0.1 * spacing_mm
    {
        out.push(last);
    }
    out
}

/// Mean and largest distance from the true cable's points to a shape.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Distances {
    pub mean_mm: f64,
    pub max_mm: f64,
}

/// A shape's distance to the true cable over the stretch the pad holds
/// and over [`BEYOND_PAD_MM`] beyond each end of it; `None` where the true
/// cable has no point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct StretchErrors {
    pub grasped: Option<Distances>,
    pub beyond: Option<Distances>,
}

/// The true cable, its points sorted into the stretch on the pad (`|x|` in
/// the sensor frame up to the pad's half side) and the stretches beyond it
/// on either side.
#[derive(Clone, Debug, PartialEq)]
pub struct TrueStretches {
    grasped: Vec<Point3<f64>>,
    beyond: Vec<Point3<f64>>,
}

impl TrueStretches {
    pub fn new(
        truth_in_base: &[Point3<f64>],
        base_from_sensor: &Isometry3<f64>,
        half_side_mm: f64,
        beyond_mm: f64,
    ) -> Self {
        let sensor_from_base = base_from_sensor.inverse();
        let (mut grasped, mut beyond) = (Vec::new(), Vec::new());
        for &point in truth_in_base {
            let x = (sensor_from_base * point).x.abs();
            if x <= half_side_mm {
                grasped.push(point);
            } else if x <= half_side_mm + beyond_mm {
                beyond.push(point);
            }
        }
        Self { grasped, beyond }
    }

    /// How far `shape` (a polyline, in order along the cable, taken to go
    /// on straight past its ends) lies from the true cable; `None` for an
    /// empty shape.
    pub fn errors(&self, shape: &[Point3<f64>]) -> Option<StretchErrors> {
        (!shape.is_empty()).then(|| StretchErrors {
            grasped: distances(&self.grasped, shape),
            beyond: distances(&self.beyond, shape),
        })
    }
}

fn distances(truth: &[Point3<f64>], shape: &[Point3<f64>]) -> Option<Distances> {
    if truth.is_empty() {
        return None;
    }
    let each: Vec<f64> = truth
        .iter()
        .map(|p| distance_to_polyline(p, shape))
        .collect();
    Some(Distances {
        mean_mm: each.iter().sum::<f64>() / each.len() as f64,
        max_mm: each.iter().copied().fold(0.0, f64::max),
    })
}

/// Distance from `point` to `polyline` (to its one point if it has only
/// one): to the nearer of the two segments beside its nearest point (the
/// polyline's points lie a millimetre apart along a smooth curve), the
/// first and last segments going on straight past the polyline's ends: a
/// shape that stops short of the stretch measured (the camera's view cut
/// off, or only the pad's stretch felt) is taken to go on as it ended.
fn distance_to_polyline(point: &Point3<f64>, polyline: &[Point3<f64>]) -> f64 {
    let Some(nearest) = (0..polyline.len()).min_by(|&a, &b| {
        (polyline[a] - point)
            .norm_squared()
            .total_cmp(&(polyline[b] - point).norm_squared())
    }) else {
        return f64::INFINITY;
    };
    let last = polyline.len().saturating_sub(2);
    let to_segment = |k: usize| {
        let (a, b) = (polyline[k], polyline[k + 1]);
        let ab = b - a;
        let length_squared = ab.norm_squared();
        let t = if length_squared > 0.0 {
            (point - a).dot(&ab) / length_squared
        } else {
            0.0
        };
        let low = if k == 0 { f64::NEG_INFINITY } else { 0.0 };
        let high = if k == last { f64::INFINITY } else { 1.0 };
        (point - (a + ab * t.clamp(low, high))).norm()
    };
    let before = nearest.checked_sub(1).map(to_segment);
    let after = (nearest + 1 < polyline.len()).then(|| to_segment(nearest));
    match (before, after) {
        (Some(a), Some(b)) => a.min(b),
        (Some(d), None) | (None, Some(d)) => d,
        (None, None) => (polyline[nearest] - point).norm(),
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    use super::*;

    fn centroid(x_mm: f64, y_mm: f64) -> Centroid {
        Centroid {
            x_mm,
            y_mm,
            weight_v: 1.0,
        }
    }

    #[test]
    fn a_line_is_sampled_inside_the_pad_only() {
        let line = TactileCurve::Line(LineInSensor::new(0.0, 1.5));
        let points = line.points_in_sensor(8.875);
        assert_eq!(points.len(), 17);
        assert!(points.iter().all(|p| (p.y - 1.5).abs() < 1e-12));
        assert!(points.iter().all(|p| p.x.abs() <= 8.875));
        // Steep, across a corner: only what lies on the pad.
        // (The corner (-8.875, 8.875) lies 12.55 mm out along the normal.)
        let diagonal = TactileCurve::Line(LineInSensor::new(std::f64::consts::FRAC_PI_4, 11.5));
        let corner = diagonal.points_in_sensor(8.875);
        assert!(!corner.is_empty() && corner.len() < 4, "{corner:?}");
    }

    #[test]
    fn the_angle_at_the_centre_is_the_curves_tangent_there() {
        let line = TactileCurve::Line(LineInSensor::new(0.3, 1.0));
        assert_eq!(line.angle_at_centre_rad(), 0.3);
        let q = Quadratic {
            a: 0.05,
            b: 0.2,
            c: 1.0,
        };
        let across = TactileCurve::Quadratic(Direction::Horizontal, q);
        assert!((across.angle_at_centre_rad() - 0.2f64.atan()).abs() < 1e-12);
        // x = 0.2 y + …: nearly along y, leaning towards +x.
        let along_y = TactileCurve::Quadratic(Direction::Vertical, q);
        let expected = std::f64::consts::FRAC_PI_2 - 0.2f64.atan();
        assert!((along_y.angle_at_centre_rad() - expected).abs() < 1e-12);
    }

    #[test]
    fn a_vertical_quadratic_runs_along_y() {
        let q = Quadratic {
            a: 0.01,
            b: 0.0,
            c: -1.0,
        };
        let points = TactileCurve::Quadratic(Direction::Vertical, q).points_in_sensor(8.875);
        assert_eq!(points.len(), 17);
        for p in points {
            assert!((p.x - (0.01 * p.y * p.y - 1.0)).abs() < 1e-12);
        }
    }

    #[test]
    fn sigma_grows_with_the_scatter_and_towards_the_pads_edge() {
        let exact: Vec<Centroid> = (-2..=2)
            .map(|k| centroid(3.55 * f64::from(k), 0.5))
            .collect();
        let line = TactileCurve::Line(LineInSensor::new(0.0, 0.5));
        let sigma = line.sigma_from_centroids(&exact, Direction::Horizontal, 0.2);
        assert!((sigma(Point2::new(0.0, 0.5)) - 0.2).abs() < 1e-12);
        let scattered: Vec<Centroid> = [0.3, -0.3, 0.3, -0.3, 0.3]
            .iter()
            .zip(-2..=2)
            .map(|(dy, k)| centroid(3.55 * f64::from(k), 0.5 + dy))
            .collect();
        let sigma = line.sigma_from_centroids(&scattered, Direction::Horizontal, 0.0);
        let (centre, edge) = (sigma(Point2::new(0.0, 0.5)), sigma(Point2::new(8.0, 0.5)));
        assert!(centre > 0.1 && edge > 1.5 * centre, "{centre} {edge}");
        // With no degree of freedom left, the floor alone.
        let quadratic = TactileCurve::Quadratic(
            Direction::Horizontal,
            Quadratic {
                a: 0.0,
                b: 0.0,
                c: 0.5,
            },
        );
        let sigma = quadratic.sigma_from_centroids(&exact[..3], Direction::Horizontal, 0.3);
        assert_eq!(sigma(Point2::new(1.0, 0.5)), 0.3);
    }

    #[test]
    fn a_shape_on_the_pad_lands_in_the_base_frame() {
        let base_from_sensor = Isometry3::from_parts(
            Translation3::new(450.0, 0.0, 250.0),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), -std::f64::consts::FRAC_PI_2),
        );
        let shape =
            TactileCurve::Line(LineInSensor::new(0.0, 2.0))
                .shape(&base_from_sensor, 8.875, |_| 0.25);
        // A −90° turn about x takes sensor y to base −z.
        for point in &shape {
            assert!((point.in_base_mm.z - 248.0).abs() < 1e-9, "{point:?}");
            assert!(point.in_base_mm.y.abs() < 1e-9);
            assert_eq!(point.sigma_mm, 0.25);
        }
    }

    #[test]
    fn resampling_keeps_the_spacing_along_a_bend() {
        let corner = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(2.5, 0.0, 0.0),
            Point3::new(2.5, 2.5, 0.0),
        ];
        let points = resample(&corner, 1.0);
        assert_eq!(points.len(), 6);
        assert_eq!(points[3], Point3::new(2.5, 0.5, 0.0));
        assert_eq!(points[5], Point3::new(2.5, 2.5, 0.0));
        assert!(resample(&[], 1.0).is_empty());
    }

    #[test]
    fn errors_are_measured_per_stretch_against_the_nearest_segment() {
        // The true cable along base x; the pad centred on it, x along it.
        let truth: Vec<Point3<f64>> = (-60..=60)
            .map(|x| Point3::new(f64::from(x), 0.0, 0.0))
            .collect();
        let stretches = TrueStretches::new(&truth, &Isometry3::identity(), 8.875, 30.0);
        // A shape 0.5 mm off over the pad and 2 mm off beyond.
        let shape: Vec<Point3<f64>> = (-80..=80)
            .map(|x| {
                let x = f64::from(x);
                Point3::new(x, if x.abs() <= 10.0 { 0.5 } else { 2.0 }, 0.0)
            })
            .collect();
        let errors = stretches.errors(&shape).unwrap();
        let grasped = errors.grasped.unwrap();
        assert!((grasped.mean_mm - 0.5).abs() < 1e-9, "{grasped:?}");
        let beyond = errors.beyond.unwrap();
        assert!((beyond.max_mm - 2.0).abs() < 1e-9, "{beyond:?}");
        assert!(beyond.mean_mm > 1.5 && beyond.mean_mm < 2.0, "{beyond:?}");
        assert!(stretches.errors(&[]).is_none());
        // A shape over the pad only, 0.5 mm off and parallel: taken on
        // straight, it is 0.5 mm off beyond too.
        let short: Vec<Point3<f64>> = (-9..=9)
            .map(|x| Point3::new(f64::from(x), 0.5, 0.0))
            .collect();
        let beyond = stretches.errors(&short).unwrap().beyond.unwrap();
        assert!((beyond.max_mm - 0.5).abs() < 1e-9, "{beyond:?}");
        // A one-point shape: the distance to it.
        let single = stretches.errors(&[Point3::new(0.0, 3.0, 4.0)]).unwrap();
        let grasped = single.grasped.unwrap();
        assert!((grasped.max_mm - 89f64.sqrt()).abs() < 1e-9, "{grasped:?}");
        assert!(grasped.mean_mm > 5.0);
    }
}
