//! The cable's shapes at a grasp (the paper's Fig. 12), computed by the
//! runner as soon as the machine has recorded the grasp: the vision shape
//! the detector gave, the pad's fits placed in the base frame through the
//! arm's measured pose, their fusion, and on a simulated cell their
//! distances to the true cable. Pure: no device is asked.

use nalgebra::{Point2, Point3, UnitQuaternion, Vector3};

use super::plan::Plan;
use crate::perception::fusion::fuse;
use crate::perception::shape::{BEYOND_PAD_MM, ShapePoint, TactileCurve, TrueStretches};
use crate::perception::tactile::{Estimate, PAD_HALF_SIDE_PITCH, WireFit, fit_wire};
use crate::record::{GraspRecord, GraspShapes, ShapeErrors, TactileShape};

/// What the pad's shapes are sure of at best, in pitches: the centroids'
/// pull towards the pad's middle near its edge and the ridge's own error
/// (a few hundredths of a pitch on the simulated pad) do not show in a
/// fit's residuals, and a handful of centroids can happen to line up.
pub const TACTILE_SIGMA_FLOOR_PITCH: f64 = 0.05;

/// Half the pad's side under `plan`: the stretch of cable a grasp holds
/// reaches this far each side of the pad's centre.
pub fn pad_half_side_mm(plan: &Plan) -> f64 {
    PAD_HALF_SIDE_PITCH * plan.fit.pitch_mm
}

/// One of the pad's curves and its shape over the pad.
struct Felt {
    curve: TactileCurve,
    shape: Vec<ShapePoint>,
}

/// The shapes of the cable at `grasp`: `vision` is the detected cable's
/// centre line, `truth` the true one when the cell knows it.
pub fn grasp_shapes(
    grasp: &GraspRecord,
    plan: &Plan,
    vision: Option<&[ShapePoint]>,
    truth: Option<&[Point3<f64>]>,
) -> GraspShapes {
    let base_from_sensor = grasp.base_from_tcp * plan.tcp_from_sensor;
    let pad_half_side_mm = pad_half_side_mm(plan);
    let floor_mm = TACTILE_SIGMA_FLOOR_PITCH * plan.fit.pitch_mm;
    let felt = |curve: TactileCurve, sigma: &dyn Fn(Point2<f64>) -> f64| Felt {
        curve,
        shape: curve.shape(&base_from_sensor, pad_half_side_mm, sigma),
    };
    // The paper's fits, whichever estimator the task uses.
    let wire: Option<WireFit> = match &grasp.fit {
        Some(Estimate::Centroids(fit)) => Some(fit.clone()),
        _ => fit_wire(&grasp.map, &plan.fit).ok(),
    };
    let from_centroids = |curve: TactileCurve, wire: &WireFit| {
        let sigma = curve.sigma_from_centroids(&wire.centroids, wire.direction, floor_mm);
        felt(curve, &sigma)
    };
    let linear = wire
        .as_ref()
        .map(|wire| from_centroids(TactileCurve::Line(wire.line), wire));
    let quadratic = wire.as_ref().and_then(|wire| {
        let curve = TactileCurve::Quadratic(wire.direction, wire.quadratic?);
        Some(from_centroids(curve, wire))
    });
    let ridge = match &grasp.fit {
        Some(Estimate::Ridge(fit)) => Some(felt(TactileCurve::Line(fit.line), &|_| floor_mm)),
        _ => None,
    };
    // The estimator's own shape; for the paper's, the quadratic, which
    // can follow a bend.
    let (fused_from, touch) = match (&ridge, &quadratic, &linear) {
        (Some(ridge), _, _) => (Some(TactileShape::Ridge), Some(ridge)),
        (None, Some(quadratic), _) => (Some(TactileShape::Quadratic), Some(quadratic)),
        (None, None, Some(linear)) => (Some(TactileShape::Linear), Some(linear)),
        (None, None, None) => (None, None),
    };
    let fused = touch.and_then(|touch| {
        let sources: Vec<&[ShapePoint]> = vision.into_iter().chain([&touch.shape[..]]).collect();
        // Along the cable as the pad feels it, whatever its angle there.
        let along =
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), touch.curve.angle_at_centre_rad());
        fuse(&sources, &(base_from_sensor * along))
    });
    let errors = truth.map(|truth| {
        let stretches =
            TrueStretches::new(truth, &base_from_sensor, pad_half_side_mm, BEYOND_PAD_MM);
        let points = |shape: &[ShapePoint]| -> Vec<Point3<f64>> {
            shape.iter().map(|p| p.in_base_mm).collect()
        };
        let extended = |felt: &Option<Felt>| {
            let reach_mm = pad_half_side_mm + BEYOND_PAD_MM;
            let curve = felt.as_ref()?.curve;
            stretches.errors(&points(&curve.shape(&base_from_sensor, reach_mm, |_| 0.0)))
        };
        ShapeErrors {
            beyond_mm: BEYOND_PAD_MM,
            vision: vision.and_then(|shape| stretches.errors(&points(shape))),
            tactile_linear: extended(&linear),
            tactile_quadratic: extended(&quadratic),
            tactile_ridge: extended(&ridge),
            fused: fused
                .as_deref()
                .and_then(|shape| stretches.errors(&points(shape))),
        }
    });
    GraspShapes {
        base_from_sensor,
        pad_half_side_mm,
        vision: vision.map(<[ShapePoint]>::to_vec),
        tactile_linear: linear.map(|felt| felt.shape),
        tactile_quadratic: quadratic.map(|felt| felt.shape),
        tactile_ridge: ridge.map(|felt| felt.shape),
        fused_from,
        fused,
        truth: truth.map(<[Point3<f64>]>::to_vec),
        errors,
    }
}
