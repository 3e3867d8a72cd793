//! How far a data set's labels agree with themselves: the curve each
//! labelled cable's mask was drawn along, and how well those curves,
//! drawn at one width, explain the labelled masks.

use opencv::prelude::*;
use schemars::JsonSchema;

use super::dataset::GroundTruth;
use super::measure::{count, dice, distance_to_polylines, mean};
use crate::perception::vision::error::VisionError;
use crate::perception::vision::paths::polyline_length;
use crate::perception::vision::pipeline::draw_paths;
use crate::perception::vision::spline::BSpline;

/// Mean squared distance (px²) of a labelled cable's points from the curve
/// [`label_curve`] draws through them. Measured on cables-dev: its masks
/// match curves fitted to 2 px² at a union DICE of 0.90 (1 px²: 0.88,
/// 3 px²: 0.90; the polylines themselves: 0.85).
const LABEL_CURVE_RESIDUAL_PX2: f64 = 2.0;

/// The curve a labelled cable's mask was drawn along: the B-spline with the
/// fewest control points that passes within [`LABEL_CURVE_RESIDUAL_PX2`]
/// of the labelled points, sampled a pixel apart. The data set calls the
/// points spline control points, and its masks follow such a smoothed
/// curve, not the polyline through them, which cuts up to a few pixels
/// inside each bend.
pub fn label_curve(points_px: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let samples = polyline_length(points_px).ceil() as usize + 2;
    let mut curve = points_px.to_vec();
    for control_points in 4..=(points_px.len() / 2).max(4) {
        let Some(spline) = BSpline::fit(points_px, control_points) else {
            break;
        };
        curve = spline.sample(samples);
        let on_curve = std::slice::from_ref(&curve);
        let residual_px2 = mean(
            points_px
                .iter()
                .map(|&p| distance_to_polylines(p, on_curve).powi(2)),
        );
        if residual_px2.is_none_or(|r| r <= LABEL_CURVE_RESIDUAL_PX2) {
            break;
        }
    }
    curve
}

/// The line thicknesses (OpenCV's, px) among which [`label_consistency`]
/// picks.
const LABEL_THICKNESSES_PX: std::ops::RangeInclusive<i32> = 1..=15;

/// How well a data set's labelled centre lines explain its labelled
/// masks: each image's union DICE of its lines' curves ([`label_curve`])
/// drawn at one width against its union mask, at the width that fits all
/// images best. Masks drawn by hand beside the cables hold every method's
/// union DICE down with them: this measures how far the labels agree with
/// themselves, as a reference, not a bound.
#[derive(Clone, Debug, PartialEq, serde::Serialize, JsonSchema)]
pub struct LabelConsistency {
    /// The drawn lines' area over their length (OpenCV draws a line of
    /// thickness t about t + 2 px wide).
    pub width_px: f64,
    /// Per image, in the order given.
    pub union_dice: Vec<f64>,
}

/// The labels' consistency over `truths`; `None` when none has a
/// centre line.
pub fn label_consistency(truths: &[&GroundTruth]) -> Result<Option<LabelConsistency>, VisionError> {
    let length_px: f64 = truths
        .iter()
        .flat_map(|t| &t.polylines_px)
        .map(|line| polyline_length(line))
        .sum();
    if length_px == 0.0 {
        return Ok(None);
    }
    let curves_per_truth: Vec<Vec<Vec<[f64; 2]>>> = truths
        .iter()
        .map(|t| {
            t.polylines_px
                .iter()
                .map(|line| label_curve(line))
                .collect()
        })
        .collect();
    let lines_per_truth: Vec<Vec<&[[f64; 2]]>> = curves_per_truth
        .iter()
        .map(|curves| curves.iter().map(Vec::as_slice).collect())
        .collect();
    let mut best: Option<(f64, LabelConsistency)> = None;
    for thickness_px in LABEL_THICKNESSES_PX {
        let mut area_px = 0.0;
        let mut union_dice = Vec::with_capacity(truths.len());
        for (truth, lines) in truths.iter().zip(&lines_per_truth) {
            let union = &truth.union_mask;
            let drawn = draw_paths(union.rows(), union.cols(), lines, thickness_px)?;
            area_px += count(&drawn);
            union_dice.push(dice(&drawn, union));
        }
        let mean_dice = union_dice.iter().sum::<f64>() / union_dice.len() as f64;
        if best.as_ref().is_none_or(|(b, _)| mean_dice > *b) {
            let width_px = area_px / length_px;
            best = Some((
                mean_dice,
                LabelConsistency {
                    width_px,
                    union_dice,
                },
            ));
        }
    }
    Ok(best.map(|(_, consistency)| consistency))
}

/// Truth whose masks are the curves of `lines` drawn at OpenCV
/// thickness `thickness_px`, moved down by `shift_px`, in a 160 × 120
/// image.
#[cfg(test)]
pub(super) fn drawn_truth(
    lines: Vec<Vec<[f64; 2]>>,
    thickness_px: i32,
    shift_px: f64,
) -> GroundTruth {
    let shifted: Vec<Vec<[f64; 2]>> = lines
        .iter()
        .map(|l| {
            label_curve(l)
                .iter()
                .map(|p| [p[0], p[1] + shift_px])
                .collect()
        })
        .collect();
    let masks: Vec<opencv::core::Mat> = shifted
        .iter()
        .map(|l| draw_paths(120, 160, &[l.as_slice()], thickness_px).unwrap())
        .collect();
    let all: Vec<&[[f64; 2]]> = shifted.iter().map(Vec::as_slice).collect();
    GroundTruth {
        masks,
        union_mask: draw_paths(120, 160, &all, thickness_px).unwrap(),
        polylines_px: lines,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_drawn_along_their_lines_are_consistent_at_their_width() {
        let lines = vec![
            vec![[10.0, 20.0], [80.0, 60.0], [150.0, 30.0]],
            vec![[20.0, 100.0], [140.0, 90.0]],
        ];
        let exact = drawn_truth(lines.clone(), 7, 0.0);
        let consistency = label_consistency(&[&exact, &exact]).unwrap().unwrap();
        assert_eq!(consistency.union_dice, vec![1.0, 1.0]);
        // Thickness 7 draws about 9 px wide (its round ends add a little).
        assert!(
            (8.5..10.0).contains(&consistency.width_px),
            "{consistency:?}"
        );

        // Masks drawn 3 px beside their lines: no width explains them.
        let beside = drawn_truth(lines, 7, 3.0);
        let consistency = label_consistency(&[&exact, &beside]).unwrap().unwrap();
        assert!(consistency.union_dice[1] < 0.8, "{consistency:?}");

        let unlabelled = drawn_truth(Vec::new(), 7, 0.0);
        assert_eq!(label_consistency(&[&unlabelled]).unwrap(), None);
    }

    #[test]
    fn label_curves_follow_the_bend_the_polyline_cuts() {
        // A quarter circle of 100 px radius labelled every 0.4 rad: each
        // chord of the polyline cuts 2 px inside the arc at its middle.
        let arc = |a: f64| [200.0 + 100.0 * a.cos(), 200.0 + 100.0 * a.sin()];
        let points: Vec<[f64; 2]> = (0..=4).map(|i| arc(f64::from(i) * 0.4)).collect();
        let off_arc_px = |p: [f64; 2]| ((p[0] - 200.0).hypot(p[1] - 200.0) - 100.0).abs();
        let chord_middle = [
            (points[1][0] + points[2][0]) / 2.0,
            (points[1][1] + points[2][1]) / 2.0,
        ];
        assert!(off_arc_px(chord_middle) > 1.9);

        let curve = label_curve(&points);
        let worst_px = curve.iter().map(|&p| off_arc_px(p)).fold(0.0, f64::max);
        assert!(worst_px < 0.5, "{worst_px}");
        let steps: Vec<f64> = curve
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .collect();
        assert!(steps.iter().all(|&d| d < 1.1), "{steps:?}");

        // Two points: the segment between them.
        let segment = label_curve(&[[0.0, 0.0], [10.0, 0.0]]);
        assert_eq!(segment.first(), Some(&[0.0, 0.0]));
        assert!(
            segment
                .iter()
                .all(|p| p[1].abs() < 1e-9 && (0.0..=10.0).contains(&p[0]))
        );
        // One point: itself.
        assert_eq!(label_curve(&[[3.0, 4.0]]), vec![[3.0, 4.0]]);
    }
}
