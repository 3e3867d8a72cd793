//! Scoring what the pipeline found against the ground truth: union and
//! instance overlap, counts, which cables each side missed, centre-line
//! and grasp-point distances, and their means over a data set.

use opencv::core::{self, Mat};
use opencv::imgproc;
use opencv::prelude::*;
use schemars::JsonSchema;

use super::dataset::GroundTruth;
use super::measure::{count, dice, distance_to_polylines, mean, overlap, size_of};
use crate::perception::vision::error::VisionError;
use crate::perception::vision::paths::polyline_length;
use crate::perception::vision::pipeline::{CableInstance, VisionOutput, first_to_grasp};

/// How one image's result compares with its truth.
#[derive(Clone, Debug, PartialEq, serde::Serialize, JsonSchema)]
pub struct ImageScore {
    /// Intersection over union of the predicted and true union masks.
    pub union_iou: f64,
    /// DICE (2|A∩B| / (|A| + |B|)) of the union masks.
    pub union_dice: f64,
    /// Mean over true cables of the DICE of the predicted instance matched
    /// to it (0 when none is): matching is greedy, highest DICE first, each
    /// instance matched at most once.
    pub instance_dice: f64,
    /// As many instances predicted as there are true cables.
    pub count_right: bool,
    pub predicted_count: usize,
    pub truth_count: usize,
    /// Mean distance from the predicted splines' samples to the nearest true
    /// centreline; `None` when nothing was predicted.
    pub centerline_px: Option<f64>,
    /// Mean distance from each predicted grasp point to the nearest true
    /// centreline; `None` when nothing was predicted.
    pub grasp_error_px: Option<f64>,
    /// Predicted cables whose grasp point lies within
    /// [`CENTRELINE_NEAR_PX`] of a labelled centre line: grasps that would
    /// hold a cable, a figure labels lying a few pixels off their wires do
    /// not move (as the masks' DICE is moved).
    pub grasps_near: usize,
    /// Whether the cable the task would grasp first (the most confident,
    /// the longer of two equally so) has its grasp point within
    /// [`CENTRELINE_NEAR_PX`] of a labelled centre line: a trial grasp
    /// that would hold a cable. `None` when nothing was found.
    pub first_grasp_near: Option<bool>,
    /// Labelled cables that no instance matches (instance DICE at least
    /// [`MATCH_MIN_DICE`]): why a count came out low.
    pub missed: Vec<Unmatched>,
    /// Instances that match no labelled cable: why a count came out high.
    pub unlabelled: Vec<Unmatched>,
    /// Labelled cables along which two or more found cables lie (see
    /// [`ALONG_SHARE`]): one cable reported in pieces, where its mask
    /// broke and the pieces were not joined.
    pub in_pieces: Vec<InPieces>,
    /// Length of the labelled centre lines (px), and of it, the length
    /// within [`CENTRELINE_NEAR_PX`] of a found one: how much of the
    /// cables was found, whatever the masks' widths and the labels' offsets.
    pub labelled_length_px: f64,
    pub labelled_length_found_px: f64,
    /// Length of the found centre lines (px), and of it, the length within
    /// [`CENTRELINE_NEAR_PX`] of a labelled one.
    pub found_length_px: f64,
    pub found_length_labelled_px: f64,
    /// The whole-pixel shift `[dx, dy]` of the found union mask that
    /// matches the labelled one best ([`best_offset`]), and the union DICE
    /// so moved: how much of the DICE lost is labels lying beside the
    /// wires found, not wires missed.
    pub mask_offset_px: [i32; 2],
    pub union_dice_at_offset: f64,
}

/// How near (px) a point of one centre line must lie to the other side's
/// for its length to count as found (or labelled): the grasp point's goal.
/// Labels a few pixels beside their wires stay within it; a cable missed,
/// or found where none is labelled, does not.
pub const CENTRELINE_NEAR_PX: f64 = 5.0;

/// The instance DICE at which a found cable and a labelled one are the
/// same cable. In cables-dev, labels that lie a few pixels off their wires
/// score as low as 0.2 against the wire found; a cable crossing another
/// shares only the crossing with it.
pub const MATCH_MIN_DICE: f64 = 0.15;

/// A found cable lies along a labelled one when at least this share of
/// its length lies within [`CENTRELINE_NEAR_PX`] of the labelled centre
/// line: a piece of it, not a cable crossing it.
pub const ALONG_SHARE: f64 = 0.8;

/// How near the image border (px) a cable's mask must reach for the cable
/// to run out of view.
const AT_BORDER_PX: i32 = 10;

/// A cable on one side of the comparison that none on the other matches.
#[derive(Clone, Debug, PartialEq, serde::Serialize, JsonSchema)]
pub struct Unmatched {
    /// The labelled cable's number (`NNNNN_mask_K.png`, line K + 1 of
    /// `NNNNN.txt`) or the found one's (in the pipeline's order).
    pub index: usize,
    /// Along its centre line (a found cable's spline); `None` for a
    /// labelled mask without a line.
    pub length_px: Option<f64>,
    /// Its mask reaches within [`AT_BORDER_PX`] of the image border: the
    /// cable runs out of view.
    pub at_border: bool,
}

/// A labelled cable reported as several found ones.
#[derive(Clone, Debug, PartialEq, serde::Serialize, JsonSchema)]
pub struct InPieces {
    /// The labelled cable's number, as in [`Unmatched::index`].
    pub index: usize,
    /// How many found cables lie along it.
    pub pieces: usize,
}

/// The labelled cables (`labelled`, centre lines) along which two or more
/// of `found` lie (see [`ALONG_SHARE`]).
fn labels_in_pieces(found: &[Vec<[f64; 2]>], labelled: &[Vec<[f64; 2]>]) -> Vec<InPieces> {
    labelled
        .iter()
        .enumerate()
        .filter_map(|(index, label)| {
            let pieces = found
                .iter()
                .filter(|line| {
                    let (length_px, near_px) =
                        length_near(std::slice::from_ref(line), std::slice::from_ref(label));
                    length_px > 0.0 && near_px >= ALONG_SHARE * length_px
                })
                .count();
            (pieces >= 2).then_some(InPieces { index, pieces })
        })
        .collect()
}

/// Whether `mask`'s pixels reach within [`AT_BORDER_PX`] of its border.
fn reaches_border(mask: &Mat) -> bool {
    let Ok(r) = imgproc::bounding_rect(mask) else {
        return false;
    };
    r.width > 0
        && (r.x < AT_BORDER_PX
            || r.y < AT_BORDER_PX
            || r.x + r.width > mask.cols() - AT_BORDER_PX
            || r.y + r.height > mask.rows() - AT_BORDER_PX)
}

/// How far (px, along each axis) [`best_offset`] moves a found mask: as
/// far as cables-dev's labels mostly lie beside their wires; a cable
/// found farther from its label is another matter (centre-line distance).
pub const MASK_OFFSET_SEARCH_PX: i32 = 3;

/// The whole-pixel shift `[dx, dy]`, each within ±[`MASK_OFFSET_SEARCH_PX`],
/// that moves `found` to its best union DICE against `labelled` (pixels
/// moved out of view count as unmatched), and that DICE; the smallest such
/// shift on a tie. Masks of different sizes give `([0, 0], 0)`.
pub fn best_offset(found: &Mat, labelled: &Mat) -> ([i32; 2], f64) {
    if size_of(found) != size_of(labelled) {
        return ([0, 0], 0.0);
    }
    let (n_found, n_labelled) = (count(found), count(labelled));
    if n_found + n_labelled == 0.0 {
        return ([0, 0], 1.0);
    }
    let (w, h) = (found.cols(), found.rows());
    let r = MASK_OFFSET_SEARCH_PX;
    let mut shifts: Vec<[i32; 2]> = (-r..=r)
        .flat_map(|dx| (-r..=r).map(move |dy| [dx, dy]))
        .collect();
    shifts.sort_by_key(|[dx, dy]| dx * dx + dy * dy);
    let mut best = ([0, 0], -1.0);
    for [dx, dy] in shifts {
        let (wide, high) = (w - dx.abs(), h - dy.abs());
        if wide <= 0 || high <= 0 {
            continue;
        }
        let from = core::Rect::new((-dx).max(0), (-dy).max(0), wide, high);
        let to = core::Rect::new(dx.max(0), dy.max(0), wide, high);
        let mut both = Mat::default();
        let anded = Mat::roi(found, from).and_then(|moved| {
            let under = Mat::roi(labelled, to)?;
            core::bitwise_and(&moved, &under, &mut both, &core::no_array())
        });
        if anded.is_err() {
            continue;
        }
        let d = 2.0 * count(&both) / (n_found + n_labelled);
        if d > best.1 {
            best = ([dx, dy], d);
        }
    }
    best
}

/// The length of `lines` (px), and of it, the length within
/// [`CENTRELINE_NEAR_PX`] of `others`, measured piece by piece, each
/// piece at most a pixel long.
fn length_near(lines: &[Vec<[f64; 2]>], others: &[Vec<[f64; 2]>]) -> (f64, f64) {
    let (mut total_px, mut near_px) = (0.0, 0.0);
    for w in lines.iter().flat_map(|line| line.windows(2)) {
        let (a, b) = (w[0], w[1]);
        let length_px = (b[0] - a[0]).hypot(b[1] - a[1]);
        let pieces = length_px.ceil().max(1.0);
        for i in 0..pieces as usize {
            let t = (i as f64 + 0.5) / pieces;
            let middle = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            if distance_to_polylines(middle, others) <= CENTRELINE_NEAR_PX {
                near_px += length_px / pieces;
            }
        }
        total_px += length_px;
    }
    (total_px, near_px)
}

/// Scores a pipeline output, its cables' masks drawn, against the truth.
pub fn score(output: &VisionOutput, truth: &GroundTruth) -> Result<ImageScore, VisionError> {
    let union_mask = output
        .union_mask
        .as_ref()
        .ok_or(VisionError::NoCableMasks)?;
    score_cables(&output.cables, union_mask, truth)
}

/// Scores instances, their masks drawn, and a union mask against the truth
/// (for results that did not come from
/// [`Pipeline::detect`](crate::perception::vision::Pipeline::detect)).
pub fn score_cables(
    cables: &[CableInstance],
    union_mask: &Mat,
    truth: &GroundTruth,
) -> Result<ImageScore, VisionError> {
    let masks = cables
        .iter()
        .map(|c| c.mask.as_ref().ok_or(VisionError::NoCableMasks))
        .collect::<Result<Vec<&Mat>, _>>()?;
    let (inter, np, nt) = overlap(union_mask, &truth.union_mask);
    let union = np + nt - inter;
    let union_iou = if union > 0.0 { inter / union } else { 1.0 };
    let union_dice = if np + nt > 0.0 {
        2.0 * inter / (np + nt)
    } else {
        1.0
    };

    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (t, tm) in truth.masks.iter().enumerate() {
        for (p, own) in masks.iter().enumerate() {
            let d = dice(own, tm);
            if d > 0.0 {
                pairs.push((d, t, p));
            }
        }
    }
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0));
    // The DICE each true cable and each instance was matched at.
    let mut truth_dice: Vec<Option<f64>> = vec![None; truth.masks.len()];
    let mut pred_dice: Vec<Option<f64>> = vec![None; cables.len()];
    let mut matched = 0.0;
    for (d, t, p) in pairs {
        if truth_dice[t].is_none() && pred_dice[p].is_none() {
            truth_dice[t] = Some(d);
            pred_dice[p] = Some(d);
            matched += d;
        }
    }
    let same_cable = |d: &Option<f64>| d.is_some_and(|d| d >= MATCH_MIN_DICE);
    let missed = (0..truth.masks.len())
        .filter(|&t| !same_cable(&truth_dice[t]))
        .map(|t| Unmatched {
            index: t,
            length_px: truth.polylines_px.get(t).map(|line| polyline_length(line)),
            at_border: reaches_border(&truth.masks[t]),
        })
        .collect();
    let unlabelled = (0..cables.len())
        .filter(|&p| !same_cable(&pred_dice[p]))
        .map(|p| Unmatched {
            index: p,
            length_px: Some(polyline_length(&cables[p].samples_px)),
            at_border: reaches_border(masks[p]),
        })
        .collect();
    let truth_count = truth.masks.len();
    let instance_dice = if truth_count > 0 {
        matched / truth_count as f64
    } else if cables.is_empty() {
        1.0
    } else {
        0.0
    };
    let centerline_px = mean(
        cables
            .iter()
            .flat_map(|c| c.samples_px.iter())
            .map(|&p| distance_to_polylines(p, &truth.polylines_px)),
    );
    let grasp_error_px = mean(
        cables
            .iter()
            .map(|c| distance_to_polylines(c.grasp_px, &truth.polylines_px)),
    );
    let grasp_near = |c: &CableInstance| {
        distance_to_polylines(c.grasp_px, &truth.polylines_px) <= CENTRELINE_NEAR_PX
    };
    let grasps_near = cables.iter().filter(|c| grasp_near(c)).count();
    let first_grasp_near = first_to_grasp(cables).map(grasp_near);
    let (mask_offset_px, union_dice_at_offset) = best_offset(union_mask, &truth.union_mask);
    let found_lines: Vec<Vec<[f64; 2]>> = cables.iter().map(|c| c.samples_px.clone()).collect();
    let (labelled_length_px, labelled_length_found_px) =
        length_near(&truth.polylines_px, &found_lines);
    let (found_length_px, found_length_labelled_px) =
        length_near(&found_lines, &truth.polylines_px);
    let in_pieces = labels_in_pieces(&found_lines, &truth.polylines_px);
    Ok(ImageScore {
        union_iou,
        union_dice,
        instance_dice,
        count_right: cables.len() == truth_count,
        predicted_count: cables.len(),
        truth_count,
        centerline_px,
        grasp_error_px,
        grasps_near,
        first_grasp_near,
        missed,
        unlabelled,
        in_pieces,
        labelled_length_px,
        labelled_length_found_px,
        found_length_px,
        found_length_labelled_px,
        mask_offset_px,
        union_dice_at_offset,
    })
}

/// Scores over a data set: means of the per-image scores (the distance
/// means over the images that have them).
#[derive(Clone, Debug, PartialEq, serde::Serialize, JsonSchema)]
pub struct ScoreSummary {
    pub images: usize,
    /// Fraction of images with the right number of instances.
    pub count_accuracy: f64,
    pub union_iou: f64,
    pub union_dice: f64,
    pub instance_dice: f64,
    pub centerline_px: Option<f64>,
    pub grasp_error_px: Option<f64>,
}

/// Summarises per-image scores.
pub fn summarize(scores: &[ImageScore]) -> ScoreSummary {
    let n = scores.len().max(1) as f64;
    ScoreSummary {
        images: scores.len(),
        count_accuracy: scores.iter().filter(|s| s.count_right).count() as f64 / n,
        union_iou: scores.iter().map(|s| s.union_iou).sum::<f64>() / n,
        union_dice: scores.iter().map(|s| s.union_dice).sum::<f64>() / n,
        instance_dice: scores.iter().map(|s| s.instance_dice).sum::<f64>() / n,
        centerline_px: mean(scores.iter().filter_map(|s| s.centerline_px)),
        grasp_error_px: mean(scores.iter().filter_map(|s| s.grasp_error_px)),
    }
}

#[cfg(test)]
mod tests {
    use super::super::labels::drawn_truth;
    use super::*;
    use crate::perception::vision::mask::zeros_u8;
    use crate::perception::vision::pipeline::draw_paths;
    use crate::perception::vision::spline::BSpline;

    /// A found cable whose centre line is the straight `from`–`to`.
    fn found_along(from: [f64; 2], to: [f64; 2]) -> CableInstance {
        let samples_px: Vec<[f64; 2]> = (0..=20)
            .map(|i| {
                let t = f64::from(i) / 20.0;
                [
                    from[0] + t * (to[0] - from[0]),
                    from[1] + t * (to[1] - from[1]),
                ]
            })
            .collect();
        CableInstance {
            spline: BSpline::fit(&samples_px, 4).unwrap(),
            grasp_px: samples_px[10],
            direction_rad: 0.0,
            length_px: polyline_length(&samples_px),
            confidence: 1.0,
            mask: Some(draw_paths(120, 160, &[samples_px.as_slice()], 7).unwrap()),
            samples_px,
        }
    }

    #[test]
    fn the_best_offset_moves_a_found_mask_back_onto_its_labels() {
        let band = |dx: f64, dy: f64| {
            let line = [
                [20.0 + dx, 40.0 + dy],
                [90.0 + dx, 70.0 + dy],
                [140.0 + dx, 50.0 + dy],
            ];
            draw_paths(120, 160, &[line.as_slice()], 5).unwrap()
        };
        let labelled = band(0.0, 0.0);
        let found = band(2.0, -1.0);
        assert!(dice(&found, &labelled) < 0.9);
        assert_eq!(best_offset(&found, &labelled), ([-2, 1], 1.0));
        assert_eq!(best_offset(&labelled, &labelled), ([0, 0], 1.0));

        // Beyond the search, as near as it goes.
        let level = |dy: f64| {
            draw_paths(
                120,
                160,
                &[[[20.0, 60.0 + dy], [140.0, 60.0 + dy]].as_slice()],
                5,
            )
            .unwrap()
        };
        let (offset, moved_dice) = best_offset(&level(6.0), &level(0.0));
        assert_eq!(offset, [0, -MASK_OFFSET_SEARCH_PX]);
        assert!(moved_dice > dice(&level(6.0), &level(0.0)) && moved_dice < 1.0);

        // Nothing to match, and masks that cannot be compared.
        let empty = zeros_u8(120, 160).unwrap();
        assert_eq!(best_offset(&empty, &empty), ([0, 0], 1.0));
        let other_size = zeros_u8(60, 80).unwrap();
        assert_eq!(best_offset(&found, &other_size), ([0, 0], 0.0));
    }

    #[test]
    fn centre_line_length_is_found_within_the_grasp_goal_of_the_other_side() {
        let truth = drawn_truth(
            vec![
                vec![[10.0, 20.0], [150.0, 20.0]],
                vec![[10.0, 100.0], [150.0, 100.0]],
            ],
            7,
            0.0,
        );
        let cables = [
            // Half of the first cable, 3 px beside its label.
            found_along([10.0, 23.0], [80.0, 23.0]),
            // Where nothing is labelled.
            found_along([20.0, 60.0], [120.0, 60.0]),
            // Along the second cable, but 6 px beside it.
            found_along([10.0, 106.0], [150.0, 106.0]),
        ];
        let score = score_cables(&cables, &truth.union_mask, &truth).unwrap();
        let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
        assert!(near(score.labelled_length_px, 280.0), "{score:?}");
        // 70 px beside the found half, and 4 px past its end, where the
        // label still lies within 5 px of it (√(4² + 3²)).
        assert!(near(score.labelled_length_found_px, 74.0), "{score:?}");
        assert!(near(score.found_length_px, 310.0), "{score:?}");
        assert!(near(score.found_length_labelled_px, 70.0), "{score:?}");

        let none = score_cables(&[], &truth.union_mask, &truth).unwrap();
        assert_eq!(none.labelled_length_found_px, 0.0);
        assert_eq!(none.found_length_px, 0.0);
    }

    #[test]
    fn the_first_grasp_is_the_most_confident_cables_and_the_longer_of_two_alike() {
        let truth = drawn_truth(vec![vec![[10.0, 20.0], [150.0, 20.0]]], 7, 0.0);
        let on_label = found_along([10.0, 21.0], [150.0, 21.0]);
        let off_label = |confidence: f64, to_x: f64| CableInstance {
            confidence,
            ..found_along([2.0, 80.0], [to_x, 80.0])
        };
        let first = |cables: &[CableInstance]| {
            score_cables(cables, &truth.union_mask, &truth)
                .unwrap()
                .first_grasp_near
        };
        // Paint more confident than the cable is grasped first, and misses.
        let paint = off_label(1.0, 120.0);
        let cable = CableInstance {
            confidence: 0.9,
            ..on_label.clone()
        };
        assert_eq!(first(&[cable.clone(), paint]), Some(false));
        assert_eq!(first(&[cable, off_label(0.5, 120.0)]), Some(true));
        // As confident: the longer is grasped first.
        assert_eq!(first(&[off_label(1.0, 60.0), on_label.clone()]), Some(true));
        assert_eq!(first(&[on_label, off_label(1.0, 158.0)]), Some(false));
        assert_eq!(first(&[]), None);
    }

    #[test]
    fn a_cable_found_in_pieces_is_named_and_one_crossing_it_is_not() {
        let truth = drawn_truth(
            vec![
                vec![[10.0, 20.0], [150.0, 20.0]],
                vec![[80.0, 5.0], [80.0, 115.0]],
            ],
            7,
            0.0,
        );
        let cables = [
            // The first cable in two pieces, either side of the crossing.
            found_along([10.0, 21.0], [70.0, 21.0]),
            found_along([90.0, 19.0], [150.0, 19.0]),
            // The second whole, across the first.
            found_along([80.0, 5.0], [80.0, 115.0]),
        ];
        let score = score_cables(&cables, &truth.union_mask, &truth).unwrap();
        assert_eq!(
            score.in_pieces,
            vec![InPieces {
                index: 0,
                pieces: 2
            }]
        );
        let whole = score_cables(
            &[found_along([10.0, 20.0], [150.0, 20.0]), cables[2].clone()],
            &truth.union_mask,
            &truth,
        )
        .unwrap();
        assert!(whole.in_pieces.is_empty());
    }
}
