//! The numerical kernels under stress: the paper's fits, the ridge fit,
//! the line and T_corr, B-spline fitting and the fusion, fed extreme scales
//! (1e-9 to 1e6), degenerate inputs (nothing, one point, duplicates,
//! collinear, all zeros, saturated taxels, NaN and infinities), a cable
//! across the pad along y and one at the 45° direction switch. They must
//! not panic, must give nothing that is not finite from finite input, and
//! must say so explicitly (an error, `None`) where there is no answer.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use cablecell::geometry::{CorrectionGain, LineInSensor, t_corr, t_corr_with_gain};
use cablecell::perception::fusion::fuse;
use cablecell::perception::shape::ShapePoint;
use cablecell::perception::tactile::map::{taxel_x_mm, taxel_y_mm};
use cablecell::perception::tactile::ridge_fit::{RELATIVE_TOLERANCE, RidgeFit, fit_ridge};
use cablecell::perception::tactile::{
    FitConfig, FitError, PAPER_PITCH_MM, TAXEL_COLS, TAXEL_ROWS, TactileMap, fit_wire,
};
use cablecell::perception::vision::BSpline;
use cablecell::perception::vision::spline::Sample;
use nalgebra::{Isometry2, Isometry3, Point3, Vector2, Vector3};
use proptest::prelude::*;

/// A Δv: mostly ordinary, often extreme or degenerate.
fn taxel() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => 0.0..1.5f64,
        1 => Just(0.0),
        1 => -1e6..0.0f64,
        1 => (-9.0..6.0f64).prop_map(|e| 10f64.powf(e)),
        1 => prop_oneof![
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(f64::NEG_INFINITY),
            Just(f64::MAX),
            Just(f64::MIN_POSITIVE),
            Just(5e-324),
        ],
    ]
}

/// A map of such taxels, some flagged saturated. (Drawn as vectors: 25
/// nested value trees of `taxel` in arrays overflow a test thread's stack.)
fn map() -> impl Strategy<Value = TactileMap> {
    (
        prop::collection::vec(taxel(), TAXEL_ROWS * TAXEL_COLS),
        prop::collection::vec(prop::bool::weighted(0.1), TAXEL_ROWS * TAXEL_COLS),
    )
        .prop_map(|(dv_v, saturated)| {
            let mut map = TactileMap::from_fn(|row, col| dv_v[row * TAXEL_COLS + col]);
            map.saturated = std::array::from_fn(|row| {
                std::array::from_fn(|col| saturated[row * TAXEL_COLS + col])
            });
            map
        })
}

/// A pitch from 1e-9 mm (below what a fit accepts) to 1e6 mm.
fn pitch_mm() -> impl Strategy<Value = f64> {
    (-9.0..6.0f64).prop_map(|e| 10f64.powf(e))
}

fn config() -> impl Strategy<Value = FitConfig> {
    (pitch_mm(), prop_oneof![Just(0.0), 0.001..3.3f64]).prop_map(
        |(pitch_mm, contact_threshold_v)| FitConfig {
            pitch_mm,
            contact_threshold_v,
        },
    )
}

fn in_half_turn(alpha_rad: f64) -> bool {
    alpha_rad > -FRAC_PI_2 && alpha_rad <= FRAC_PI_2
}

fn assert_finite_line(line: &LineInSensor) {
    assert!(
        line.alpha_rad.is_finite() && line.n_mm.is_finite(),
        "{line:?}"
    );
    assert!(in_half_turn(line.alpha_rad), "{line:?}");
}

/// The operations between a map and a fitted line, counted as Eigen's
/// test helpers count them for a tolerance: each of the 25 taxels divided
/// by the peak and summed into its column and row (or into the ridge's
/// normal equations), then the fit's sums over its at most 5 samples
/// (or the 4 × 4 solve): about 100 either way.
const FIT_OPERATIONS: f64 = 100.0;

/// How far rounding alone moves a fit's answer, relative to its size: the
/// least squares' condition number times the machine epsilon times the
/// operations. (Measured over 5 000 lines at every scale of Δv and pitch:
/// the paper's fit stays within 1.8 κ ε, the ridge fit within 0.4 κ ε.)
fn rounding_tolerance(condition: f64) -> f64 {
    condition * f64::EPSILON * FIT_OPERATIONS
}

/// How far two ridge fits of the same line may differ: each lies within
/// rounding of its normal equations (Levenberg–Marquardt solves JᵀJ, whose
/// condition number is κ²) plus what the solver leaves when it stops. Its
/// last step lowered the cost C by at most `RELATIVE_TOLERANCE` · C, so
/// the step left is at most √(`RELATIVE_TOLERANCE` · C / λmin(JᵀJ)), with
/// λmin = λmax / κ² and λmax at least about 1 (the amplitude's column holds
/// the peak taxel's response, near 1): κ √(`RELATIVE_TOLERANCE` · C), C
/// being the taxels' count times the squared rms residual over the peak.
/// Twice that, for two fits. `None` without a condition number.
fn ridge_tolerance(fit: &RidgeFit, map: &TactileMap) -> Option<f64> {
    let kappa = fit.condition?;
    let peak_v = map.dv_v.iter().flatten().copied().fold(0.0, f64::max);
    let cost = (TAXEL_ROWS * TAXEL_COLS) as f64 * (fit.rms_residual_v / peak_v).powi(2);
    let stop = kappa * (RELATIVE_TOLERANCE * cost).sqrt();
    Some(2.0 * (rounding_tolerance(kappa * kappa) + stop))
}

/// A straight cable's Gaussian ridge on the pad (σ = 0.55 pitch), `peak_v`
/// high, at angle `alpha_rad` and offset `n_mm`.
fn cable_map(alpha_rad: f64, n_mm: f64, peak_v: f64, pitch_mm: f64) -> TactileMap {
    let line = LineInSensor::new(alpha_rad, n_mm);
    let sigma_mm = 0.55 * pitch_mm;
    TactileMap::from_fn(|row, col| {
        let d = line.distance_mm(Vector2::new(
            taxel_x_mm(col, pitch_mm),
            taxel_y_mm(row, pitch_mm),
        ));
        peak_v * (-d * d / (2.0 * sigma_mm * sigma_mm)).exp()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn the_paper_s_fit_gives_a_finite_line_or_says_why_not(map in map(), config in config()) {
        match fit_wire(&map, &config) {
            Ok(fit) => {
                assert_finite_line(&fit.line);
                for c in &fit.centroids {
                    prop_assert!(c.x_mm.is_finite() && c.y_mm.is_finite() && c.weight_v.is_finite(), "{c:?}");
                }
                if let Some(q) = fit.quadratic {
                    prop_assert!(q.a.is_finite() && q.b.is_finite() && q.c.is_finite(), "{q:?}");
                }
                prop_assert!(fit.h_v.is_finite() && fit.v_v.is_finite() && fit.peak_dv_v.is_finite());
                // Distinct whole pitches keep the bases apart: κ finite, ≥ 1.
                let kappas = [Some(fit.condition.line), fit.condition.quadratic];
                for kappa in kappas.into_iter().flatten() {
                    prop_assert!(kappa.is_finite() && kappa >= 1.0, "{:?}", fit.condition);
                }
            }
            Err(FitError::InvalidConfig { .. }) => prop_assert!(config.pitch_mm < 1e-6),
            Err(FitError::NoContact { .. } | FitError::TooFewCentroids { .. }) => {}
            Err(other) => prop_assert!(false, "{other}"),
        }
    }

    #[test]
    fn the_ridge_fit_gives_a_finite_ridge_or_says_why_not(map in map(), config in config()) {
        match fit_ridge(&map, &config) {
            Ok(fit) => {
                assert_finite_line(&fit.line);
                prop_assert!(fit.amplitude_v.is_finite(), "{fit:?}");
                prop_assert!(fit.sigma_mm.is_finite() && fit.sigma_mm > 0.0, "{fit:?}");
                prop_assert!(fit.rms_residual_v.is_finite(), "{fit:?}");
                prop_assert!(fit.condition.is_none_or(|k| k.is_finite() && k >= 1.0), "{fit:?}");
            }
            Err(FitError::InvalidConfig { .. }) => prop_assert!(config.pitch_mm < 1e-6),
            Err(FitError::NoContact { .. } | FitError::TooFewCentroids { .. }) => {}
            Err(other) => prop_assert!(false, "{other}"),
        }
    }

    /// Δv and the threshold scaled together from 1e-9 to 1e6, the pitch
    /// from 1e-6 to 1e6 mm: the same line, its offset in pitches, within
    /// what the fit's condition number allows (and, for the ridge fit,
    /// its solver's stopping rule).
    #[test]
    fn both_fits_are_the_same_at_every_scale(
        alpha_rad in -FRAC_PI_2..FRAC_PI_2,
        n_pitches in -1.0..1.0f64,
        volts_exp in -9.0..6.0f64,
        pitch_exp in -6.0..6.0f64,
    ) {
        let (volts, pitch_mm) = (10f64.powf(volts_exp), 10f64.powf(pitch_exp));
        let unit = cable_map(alpha_rad, n_pitches * PAPER_PITCH_MM, 1.0, PAPER_PITCH_MM);
        let scaled = cable_map(alpha_rad, n_pitches * pitch_mm, volts, pitch_mm);
        let unit_config = FitConfig::default();
        let config = FitConfig { pitch_mm, contact_threshold_v: 0.05 * volts };
        let paper = (fit_wire(&unit, &unit_config), fit_wire(&scaled, &config));
        let ridge = (fit_ridge(&unit, &unit_config), fit_ridge(&scaled, &config));
        // Each line with the tolerance of its unit map's fit.
        let lines = [
            (
                paper.0.map(|f| (f.line, Some(rounding_tolerance(f.condition.line)))),
                paper.1.map(|f| f.line),
            ),
            (
                ridge.0.map(|f| (f.line, ridge_tolerance(&f, &unit))),
                ridge.1.map(|f| f.line),
            ),
        ];
        for (unit, scaled) in lines {
            match (unit, scaled) {
                (Ok((unit, tolerance)), Ok(scaled)) => {
                    assert_finite_line(&scaled);
                    let Some(tolerance) = tolerance else {
                        return Err(TestCaseError::fail(format!("no condition number: {unit:?}")));
                    };
                    let error = scaled.error_to(&unit);
                    prop_assert!(error.alpha_rad.abs() <= tolerance, "{unit:?} {scaled:?}, ±{tolerance}");
                    let n_pitches = unit.n_mm / PAPER_PITCH_MM;
                    let n_error = scaled.n_mm / pitch_mm - n_pitches;
                    prop_assert!(
                        n_error.abs() <= tolerance * (1.0 + n_pitches.abs()),
                        "{unit:?} {scaled:?}, ±{tolerance}"
                    );
                }
                (Err(unit), Err(scaled)) => prop_assert_eq!(
                    std::mem::discriminant(&unit),
                    std::mem::discriminant(&scaled)
                ),
                (unit, scaled) => prop_assert!(false, "{unit:?} against {scaled:?}"),
            }
        }
    }

    #[test]
    fn a_line_lands_in_the_half_turn_from_any_finite_angle(
        alpha_rad in -1e6..1e6f64,
        n_mm in -1e6..1e6f64,
    ) {
        let line = LineInSensor::new(alpha_rad, n_mm);
        assert_finite_line(&line);
        // The same line: its normal and offset agree with the given ones up
        // to the half-turns taken off.
        let given = Vector2::new(-alpha_rad.sin(), alpha_rad.cos()) * n_mm;
        let kept = line.normal() * line.n_mm;
        prop_assert!((given - kept).norm() <= 1e-6 * (1.0 + n_mm.abs()), "{line:?}");
    }

    /// T_corr takes the measured line to the target, at every scale.
    #[test]
    fn t_corr_puts_the_measured_line_on_the_target(
        measured in (-1e3..1e3f64, -1e6..1e6f64),
        target in (-FRAC_PI_2..FRAC_PI_2, -1e6..1e6f64),
    ) {
        let (measured, target) = (
            LineInSensor::new(measured.0, measured.1),
            LineInSensor::new(target.0, target.1),
        );
        let old_from_new = t_corr(&measured, &target);
        prop_assert!(old_from_new.translation.vector.iter().all(|v| v.is_finite()));
        prop_assert!(old_from_new.rotation.coords.iter().all(|v| v.is_finite()));
        let planar = Isometry2::new(
            old_from_new.translation.vector.xy(),
            old_from_new.rotation.euler_angles().2,
        );
        let seen = measured.transformed(&planar.inverse());
        let error = seen.error_to(&target);
        let scale = 1.0 + measured.n_mm.abs() + target.n_mm.abs();
        prop_assert!(error.alpha_rad.abs() < 1e-9, "{seen:?} {target:?}");
        prop_assert!(error.n_mm.abs() < 1e-9 * scale, "{seen:?} {target:?}");
        let none = t_corr_with_gain(&measured, &target, &CorrectionGain { n: 0.0, alpha: 0.0 });
        prop_assert_eq!(none, Isometry3::identity());
    }

    /// Any points at all: a spline with finite points, or none.
    #[test]
    fn a_spline_of_any_points_is_finite_or_none(
        points in prop::collection::vec(
            prop::array::uniform2(prop_oneof![
                6 => -1e6..1e6f64,
                1 => (-9.0..-3.0f64).prop_map(|e| 10f64.powf(e)),
                1 => Just(0.0),
                1 => Just(f64::NAN),
                1 => Just(f64::INFINITY),
            ]),
            0..40,
        ),
        control_points in 0usize..12,
    ) {
        if let Some(spline) = BSpline::fit(&points, control_points) {
            for point in spline.sample(50) {
                prop_assert!(point.iter().all(|v| v.is_finite()), "{point:?}");
            }
            prop_assert!(spline.grasp_direction_rad().is_finite());
        }
    }

    /// Weighted samples with any weights and parameters: finite or none,
    /// and a finite σ where it is fitted.
    #[test]
    fn a_weighted_spline_is_finite_or_none(
        samples in prop::collection::vec(
            (
                prop::array::uniform2(-1e6..1e6f64),
                prop_oneof![0.0..=1.0f64, Just(0.5), Just(-0.1), Just(f64::NAN)],
                prop_oneof![(-12.0..12.0f64).prop_map(|e| 10f64.powf(e)), Just(0.0), Just(f64::INFINITY)],
            ),
            0..30,
        ),
        control_points in 0usize..10,
        bending_weight in prop_oneof![Just(0.0), (-9.0..6.0f64).prop_map(|e| 10f64.powf(e))],
    ) {
        let samples: Vec<Sample> = samples
            .into_iter()
            .map(|(point, s, weight)| Sample { point, s, weight })
            .collect();
        if let Some(fit) = BSpline::fit_weighted(&samples, control_points, bending_weight) {
            for k in 0..=20 {
                let s = f64::from(k) / 20.0;
                prop_assert!(fit.spline.point(s).iter().all(|v| v.is_finite()));
                let sigma = fit.sigma(s);
                prop_assert!(sigma.is_finite() && sigma >= 0.0, "σ({s}) = {sigma}");
            }
        }
    }

    /// Points of a cable at any scale and σ: the fused shape is finite or
    /// there is none.
    #[test]
    fn the_fusion_of_any_points_is_finite_or_none(
        points in prop::collection::vec(
            (
                prop::array::uniform3(prop_oneof![
                    8 => -1.0..1.0f64,
                    1 => Just(0.0),
                    1 => Just(f64::NAN),
                ]),
                prop_oneof![Just(0.0), (-9.0..3.0f64).prop_map(|e| 10f64.powf(e)), Just(f64::INFINITY)],
            ),
            0..30,
        ),
        scale_exp in -9.0..6.0f64,
        angle_rad in -PI..PI,
    ) {
        // One scale a case, from 1e-9 to 1e6 mm, so that the points make a
        // shape (or are too far apart for one) at every scale.
        let scale_mm = 10f64.powf(scale_exp);
        let points: Vec<ShapePoint> = points
            .into_iter()
            .map(|(p, sigma_mm)| ShapePoint { in_base_mm: Point3::from(p) * scale_mm, sigma_mm })
            .collect();
        let base_from_plane = Isometry3::new(Vector3::new(1.0, 2.0, 3.0), Vector3::z() * angle_rad);
        let (first, second) = points.split_at(points.len() / 2);
        if let Some(shape) = fuse(&[first, second], &base_from_plane) {
            for point in &shape {
                prop_assert!(point.in_base_mm.coords.iter().all(|v| v.is_finite()), "{point:?}");
                prop_assert!(point.sigma_mm.is_finite(), "{point:?}");
            }
        }
    }
}

/// A cable along y (vertical across the pad), and cables on either side of
/// the 45° where the paper's fit switches from rows to columns: each fit
/// gives a finite line within its known worst case of the truth.
#[test]
fn a_vertical_cable_and_the_direction_switch_at_45_degrees() {
    let angles = [
        FRAC_PI_2,
        -FRAC_PI_2 + 1e-12,
        FRAC_PI_4,
        FRAC_PI_4 - 1e-12,
        FRAC_PI_4 + 1e-12,
        -FRAC_PI_4,
        -FRAC_PI_4 + 1e-12,
    ];
    for alpha_rad in angles {
        for n_mm in [0.0, 1.0, -2.0] {
            let map = cable_map(alpha_rad, n_mm, 1.0, PAPER_PITCH_MM);
            let truth = LineInSensor::new(alpha_rad, n_mm);
            let config = FitConfig::default();
            let paper = fit_wire(&map, &config)
                .expect("a cable across the pad")
                .line;
            let ridge = fit_ridge(&map, &config)
                .expect("a cable across the pad")
                .line;
            for (name, line, worst_rad) in [("paper", paper, 0.35), ("ridge", ridge, 0.02)] {
                assert_finite_line(&line);
                let error = line.error_to(&truth);
                assert!(
                    error.alpha_rad.abs() < worst_rad && error.n_mm.abs() < 1.0,
                    "{name} at α {alpha_rad}, n {n_mm}: {line:?}"
                );
            }
        }
    }
}

/// Degenerate maps with no answer get an explicit error, not a line.
#[test]
fn maps_with_no_line_are_refused_explicitly() {
    let config = FitConfig::default();
    let zeros = TactileMap::from_fn(|_, _| 0.0);
    let nan = TactileMap::from_fn(|_, _| f64::NAN);
    let single = TactileMap::from_fn(|row, col| if (row, col) == (2, 2) { 1.0 } else { 0.0 });
    let mut saturated_spot = single;
    saturated_spot.saturated = [[true; TAXEL_COLS]; TAXEL_ROWS];
    for (name, map) in [
        ("zeros", zeros),
        ("NaN", nan),
        ("one taxel", single),
        ("one saturated taxel", saturated_spot),
    ] {
        for fit in [
            fit_wire(&map, &config).map(|f| f.line),
            fit_ridge(&map, &config).map(|f| f.line),
        ] {
            assert!(
                matches!(
                    fit,
                    Err(FitError::NoContact { .. } | FitError::TooFewCentroids { .. })
                ),
                "{name}: {fit:?}"
            );
        }
    }
    // Every taxel saturated at once: a flat press, still a finite answer
    // or an error, never a NaN.
    let mut flat = TactileMap::from_fn(|_, _| 3.3);
    flat.saturated = [[true; TAXEL_COLS]; TAXEL_ROWS];
    for line in [
        fit_wire(&flat, &config).map(|f| f.line),
        fit_ridge(&flat, &config).map(|f| f.line),
    ]
    .iter()
    .flatten()
    {
        assert_finite_line(line);
    }
}

/// One point, one point repeated, points on one spot: no spline; collinear
/// points: the straight line through them.
#[test]
fn degenerate_points_give_no_spline_and_collinear_ones_a_straight_one() {
    assert!(BSpline::fit(&[], 4).is_none());
    assert!(BSpline::fit(&[[1.0, 2.0]], 4).is_none());
    assert!(BSpline::fit(&[[1.0, 2.0]; 30], 4).is_none());
    assert!(BSpline::fit(&[[f64::NAN, 0.0], [0.0, f64::INFINITY]], 4).is_none());
    for scale in [1e-9, 1.0, 1e6] {
        let points: Vec<[f64; 2]> = (0..20)
            .map(|k| [f64::from(k) * scale, 2.0 * f64::from(k) * scale])
            .collect();
        let spline = BSpline::fit(&points, 6).expect("a line");
        for [x, y] in spline.sample(25) {
            assert!((y - 2.0 * x).abs() <= 1e-6 * scale, "{scale}: ({x}, {y})");
        }
    }
    let on_one_spot = [ShapePoint {
        in_base_mm: Point3::new(1.0, 1.0, 1.0),
        sigma_mm: 0.1,
    }; 10];
    assert!(fuse(&[&on_one_spot], &Isometry3::identity()).is_none());
}
