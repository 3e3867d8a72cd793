//! Scoring the pipeline against ground truth laid out as in the Cables
//! Dataset (De Gregorio et al., arXiv 1810.04461): per image `STEM`, one
//! mask per cable (`STEM_mask_K.png`), their union (`STEM_mask_all.png`)
//! and each cable's polyline (`STEM.txt`, line K: `N x0 y0 x1 y1 ...`).
//!
//! The truth masks were drawn at one width along smoothed curves of the
//! polylines' points (see [`label_curve`]), so their edges are
//! approximate: the scores compare centrelines and counts as well as pixel
//! overlap.

use std::path::{Path, PathBuf};

use opencv::core::{self, Mat, Size};
use opencv::prelude::*;
use opencv::{imgcodecs, imgproc};

use super::error::{VisionError, cv};
use super::paths::polyline_length;
use super::pipeline::{CableInstance, VisionOutput, draw_paths};
use super::spline::BSpline;

/// One image's ground truth.
#[derive(Debug)]
pub struct GroundTruth {
    /// One CV_8U 0/255 mask per cable, the image's size.
    pub masks: Vec<Mat>,
    /// The union of the cables' masks.
    pub union_mask: Mat,
    /// Each cable's centreline, in pixels (x right, y down).
    pub polylines_px: Vec<Vec<[f64; 2]>>,
}

fn read_mask(path: &Path) -> Result<Mat, VisionError> {
    let read_error = |reason: String| VisionError::ReadImage {
        path: path.to_path_buf(),
        reason,
    };
    let text = path
        .to_str()
        .ok_or_else(|| read_error("path is not UTF-8".into()))?;
    let m = imgcodecs::imread(text, imgcodecs::IMREAD_GRAYSCALE)
        .map_err(|e| read_error(e.to_string()))?;
    if m.empty() {
        return Err(read_error("missing or not a decodable image".into()));
    }
    let mut binary = Mat::default();
    opencv::imgproc::threshold(
        &m,
        &mut binary,
        127.0,
        255.0,
        opencv::imgproc::THRESH_BINARY,
    )
    .map_err(cv("binarize truth mask"))?;
    Ok(binary)
}

/// Parses one annotation line: `N x0 y0 ... x(N-1) y(N-1)`.
fn parse_polyline(path: &Path, line_no: usize, line: &str) -> Result<Vec<[f64; 2]>, VisionError> {
    let bad = |reason: String| VisionError::BadAnnotation {
        path: path.to_path_buf(),
        line: line_no,
        reason,
    };
    let mut numbers = Vec::new();
    for word in line.split_whitespace() {
        let v: f64 = word
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| bad(format!("`{word}` is not a number")))?;
        numbers.push(v);
    }
    let Some((&count, coords)) = numbers.split_first() else {
        return Err(bad("empty line".into()));
    };
    if count < 0.0 || count.fract() != 0.0 || coords.len() != 2 * count as usize {
        return Err(bad(format!(
            "says {count} points but holds {} coordinates",
            coords.len()
        )));
    }
    Ok(coords.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
}

/// Checks that the mask read from `path` is `expected` in size, which
/// `expected_from` names.
fn check_mask_size(
    mask: &Mat,
    path: &Path,
    expected: Size,
    expected_from: impl FnOnce() -> String,
) -> Result<(), VisionError> {
    if mask.cols() == expected.width && mask.rows() == expected.height {
        return Ok(());
    }
    Err(VisionError::TruthMaskSize {
        path: path.to_path_buf(),
        cols: mask.cols(),
        rows: mask.rows(),
        expected_cols: expected.width,
        expected_rows: expected.height,
        expected_from: expected_from(),
    })
}

impl GroundTruth {
    /// Reads `STEM_mask_K.png` (K = 0, 1, ... while they exist),
    /// `STEM_mask_all.png` (or the masks' union when it is absent) and
    /// `STEM.txt` from `dir`. All masks must have the first one's size.
    pub fn load(dir: &Path, stem: &str) -> Result<GroundTruth, VisionError> {
        let first_path = dir.join(format!("{stem}_mask_0.png"));
        let like_first = || format!("the size of {}", first_path.display());
        let mut masks: Vec<Mat> = Vec::new();
        loop {
            let path = dir.join(format!("{stem}_mask_{}.png", masks.len()));
            if !path.exists() {
                break;
            }
            let mask = read_mask(&path)?;
            if let Some(first) = masks.first() {
                check_mask_size(&mask, &path, size_of(first), like_first)?;
            }
            masks.push(mask);
        }
        let Some(first) = masks.first() else {
            return Err(VisionError::NoTruthMasks {
                dir: dir.to_path_buf(),
                stem: stem.to_string(),
            });
        };
        let all_path = dir.join(format!("{stem}_mask_all.png"));
        let union_mask = if all_path.exists() {
            let union = read_mask(&all_path)?;
            check_mask_size(&union, &all_path, size_of(first), like_first)?;
            union
        } else {
            let mut union = masks[0].try_clone().map_err(cv("copy truth mask"))?;
            for m in &masks[1..] {
                let mut next = Mat::default();
                core::bitwise_or(&union, m, &mut next, &core::no_array())
                    .map_err(cv("union of truth masks"))?;
                union = next;
            }
            union
        };
        let txt: PathBuf = dir.join(format!("{stem}.txt"));
        let text = std::fs::read_to_string(&txt).map_err(|e| VisionError::ReadImage {
            path: txt.clone(),
            reason: e.to_string(),
        })?;
        let polylines_px = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty())
            .map(|(i, l)| parse_polyline(&txt, i + 1, l))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(GroundTruth {
            masks,
            union_mask,
            polylines_px,
        })
    }

    /// Checks that the masks are `image`'s size (`image_path` names it),
    /// so that they can be compared with what the pipeline finds in it.
    pub fn check_fits(
        &self,
        image: &Mat,
        image_path: &Path,
        dir: &Path,
        stem: &str,
    ) -> Result<(), VisionError> {
        check_mask_size(
            &self.union_mask,
            &dir.join(format!("{stem}_mask_0.png")),
            size_of(image),
            || format!("the size of the image {}", image_path.display()),
        )
    }
}

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
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
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

fn size_of(m: &Mat) -> Size {
    Size::new(m.cols(), m.rows())
}

/// How one image's result compares with its truth.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
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
    /// Labelled cables that no instance matches (instance DICE at least
    /// [`MATCH_MIN_DICE`]): why a count came out low.
    pub missed: Vec<Unmatched>,
    /// Instances that match no labelled cable: why a count came out high.
    pub unlabelled: Vec<Unmatched>,
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

/// How near the image border (px) a cable's mask must reach for the cable
/// to run out of view.
const AT_BORDER_PX: i32 = 10;

/// A cable on one side of the comparison that none on the other matches.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
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

fn count(m: &Mat) -> f64 {
    f64::from(core::count_non_zero(m).unwrap_or(0))
}

/// (|A∩B|, |A|, |B|) of two masks; zeros when they cannot be compared
/// (different sizes).
fn overlap(a: &Mat, b: &Mat) -> (f64, f64, f64) {
    let mut both = Mat::default();
    if core::bitwise_and(a, b, &mut both, &core::no_array()).is_err() {
        return (0.0, count(a), count(b));
    }
    (count(&both), count(a), count(b))
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

fn dice(a: &Mat, b: &Mat) -> f64 {
    let (i, na, nb) = overlap(a, b);
    if na + nb > 0.0 {
        2.0 * i / (na + nb)
    } else {
        1.0
    }
}

/// Distance from `p` to the nearest segment of any of `polylines`.
pub fn distance_to_polylines(p: [f64; 2], polylines: &[Vec<[f64; 2]>]) -> f64 {
    let mut best = f64::INFINITY;
    for line in polylines {
        if let [only] = line.as_slice() {
            best = best.min((p[0] - only[0]).hypot(p[1] - only[1]));
        }
        for w in line.windows(2) {
            let (a, b) = (w[0], w[1]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len2 = dx * dx + dy * dy;
            let t = if len2 > 0.0 {
                (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (cx, cy) = (a[0] + t * dx, a[1] + t * dy);
            best = best.min((p[0] - cx).hypot(p[1] - cy));
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

fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| sum / n as f64)
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
/// [`Pipeline::detect`](super::Pipeline::detect)).
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
    let (mask_offset_px, union_dice_at_offset) = best_offset(union_mask, &truth.union_mask);
    let found_lines: Vec<Vec<[f64; 2]>> = cables.iter().map(|c| c.samples_px.clone()).collect();
    let (labelled_length_px, labelled_length_found_px) =
        length_near(&truth.polylines_px, &found_lines);
    let (found_length_px, found_length_labelled_px) =
        length_near(&found_lines, &truth.polylines_px);
    Ok(ImageScore {
        union_iou,
        union_dice,
        instance_dice,
        count_right: cables.len() == truth_count,
        predicted_count: cables.len(),
        truth_count,
        centerline_px,
        grasp_error_px,
        missed,
        unlabelled,
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
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
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
    use super::*;

    #[test]
    fn polyline_lines_parse_and_bad_ones_say_where() {
        let p = Path::new("x.txt");
        assert_eq!(
            parse_polyline(p, 1, "2 1 2 3 4").unwrap(),
            vec![[1.0, 2.0], [3.0, 4.0]]
        );
        let err = parse_polyline(p, 7, "3 1 2 3 4").unwrap_err();
        assert!(
            matches!(err, VisionError::BadAnnotation { line: 7, .. }),
            "{err}"
        );
        assert!(parse_polyline(p, 1, "2 a 2 3 4").is_err());
        let err = parse_polyline(p, 2, "2 1 2 inf 4").unwrap_err();
        assert!(err.to_string().contains("`inf` is not a number"), "{err}");
        assert!(parse_polyline(p, 1, "2 1 NaN 3 4").is_err());
    }

    #[test]
    fn masks_of_another_size_are_refused_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str, rows: i32, cols: i32| {
            let mask = Mat::zeros(rows, cols, core::CV_8UC1)
                .unwrap()
                .to_mat()
                .unwrap();
            let path = dir.path().join(name);
            imgcodecs::imwrite(path.to_str().unwrap(), &mask, &core::Vector::new()).unwrap();
        };
        write("a_mask_0.png", 48, 64);
        write("a_mask_1.png", 24, 32);
        std::fs::write(dir.path().join("a.txt"), "1 1 1\n1 2 2\n").unwrap();
        let err = GroundTruth::load(dir.path(), "a").unwrap_err();
        assert!(
            matches!(&err, VisionError::TruthMaskSize { path, cols: 32, rows: 24, .. }
                if path.ends_with("a_mask_1.png")),
            "{err}"
        );

        write("a_mask_1.png", 48, 64);
        let truth = GroundTruth::load(dir.path(), "a").unwrap();
        let image = Mat::zeros(96, 128, core::CV_8UC3)
            .unwrap()
            .to_mat()
            .unwrap();
        let err = truth
            .check_fits(&image, Path::new("a.jpg"), dir.path(), "a")
            .unwrap_err();
        assert!(
            err.to_string()
                .contains("is 64x48 px, expected 128x96 px (the size of the image a.jpg)"),
            "{err}"
        );
        let image = Mat::zeros(48, 64, core::CV_8UC3).unwrap().to_mat().unwrap();
        assert!(
            truth
                .check_fits(&image, Path::new("a.jpg"), dir.path(), "a")
                .is_ok()
        );
    }

    /// Truth whose masks are the curves of `lines` drawn at OpenCV
    /// thickness `thickness_px`, moved down by `shift_px`.
    fn drawn_truth(lines: Vec<Vec<[f64; 2]>>, thickness_px: i32, shift_px: f64) -> GroundTruth {
        let shifted: Vec<Vec<[f64; 2]>> = lines
            .iter()
            .map(|l| {
                label_curve(l)
                    .iter()
                    .map(|p| [p[0], p[1] + shift_px])
                    .collect()
            })
            .collect();
        let masks: Vec<Mat> = shifted
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
        let empty = super::super::mask::zeros_u8(120, 160).unwrap();
        assert_eq!(best_offset(&empty, &empty), ([0, 0], 1.0));
        let other_size = super::super::mask::zeros_u8(60, 80).unwrap();
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
    fn distance_to_a_polyline_is_to_its_nearest_segment() {
        let lines = vec![vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]];
        assert!((distance_to_polylines([5.0, 3.0], &lines) - 3.0).abs() < 1e-12);
        assert!((distance_to_polylines([13.0, 5.0], &lines) - 3.0).abs() < 1e-12);
        assert!((distance_to_polylines([-3.0, -4.0], &lines) - 5.0).abs() < 1e-12);
    }
}
