//! What both instance methods (skeleton and superpixels) do with the pixel
//! paths they find, before splines are fitted: paths that run along the
//! image border are cut there, pieces that continue each other across a
//! gap (a mask broken at a ferrule, a glint, a crossing or paint of the
//! cable's colour) are joined into one cable, and short scraps are dropped.

use opencv::core::{Mat, Vec3b};
use opencv::imgproc;
use opencv::prelude::*;

use super::error::{VisionError, cv};
use super::spline::arc_lengths_px;

/// Two paths whose ends lie at most this many cable widths (plus
/// [`JOIN_GAP_EXTRA_PX`]) apart, and continue each other, are one cable
/// broken by a gap in the mask: at a ferrule, a glint, a shadow, or where
/// a crossing was resolved wrongly.
pub const JOIN_GAP_WIDTHS: f64 = 4.0;
/// The same on a painted background, where the mask loses a cable for
/// longer stretches: paint of the cable's own colour runs across it, and
/// the network for busy scenes cuts it there.
pub const PAINTED_JOIN_GAP_WIDTHS: f64 = 6.0;
/// Added to the short gap so that thin cables' masks, broken for a few
/// pixels, still join.
pub const JOIN_GAP_EXTRA_PX: f64 = 4.0;
/// Paths continue each other when neither end, nor the step between them,
/// turns by more than this.
const JOIN_MAX_BEND_RAD: f64 = 0.45;
/// Ends further apart, up to this many cable widths, are joined when they
/// continue each other to within [`LONG_GAP_MAX_BEND_RAD`] and, given the
/// image, are of one colour (see [`UNDER_MAX_DELTA_E`]): a cable the mask
/// lost for a stretch, against paint or print of its own colour or in a
/// glint. So straight and so alike, two ends are rarely two cables.
const LONG_GAP_WIDTHS: f64 = 15.0;
const LONG_GAP_MAX_BEND_RAD: f64 = 0.25;
/// Across a gap longer than this many cable widths, the step from one end
/// to the other must also continue both ends. A shorter gap has no
/// direction of its own: where the mask narrows to a neck (a cable over a
/// stroke of paint, a binder's punched edge), its skeleton's ends hook
/// aside and lie beside each other as often as in line.
const GAP_DIRECTION_MIN_WIDTHS: f64 = 1.0;
/// Paths that turn by up to this also continue each other when the middle
/// of the step lies on another cable (within half a width of its centre
/// line, plus [`UNDER_EXTRA_PX`]) and, given the image, the two ends'
/// colours differ by at most [`UNDER_MAX_DELTA_E`]: the cable passes under
/// the other, its mask cut at the crossing by a shadow, and a cable may
/// bend through a crossing (the skeleton pairs crossing branches up to the
/// same bend).
const JOIN_UNDER_MAX_BEND_RAD: f64 = 0.9;
const UNDER_EXTRA_PX: f64 = 1.0;
/// Colour difference (CIE76 ΔE, OpenCV's 8-bit Lab) up to which two ends
/// can be one cable passing under another. An end's colour is read from
/// one to three widths back from it, clear of the crossing's shadow.
const UNDER_MAX_DELTA_E: f64 = 25.0;
/// An end's direction is taken over this many cable widths of its path
/// (at least [`JOIN_TANGENT_MIN_PX`]): long enough to ignore the ragged
/// last pixels, short enough to follow a bend.
const JOIN_TANGENT_WIDTHS: f64 = 2.0;
const JOIN_TANGENT_MIN_PX: f64 = 8.0;
/// Skeleton pixels this close to the mask's border, in cable widths (plus
/// [`BORDER_CUT_EXTRA_PX`]), may follow the border rather than a cable:
/// where two cables leave the view side by side, the network's mask often
/// joins them with a band along the border, whose skeleton runs 2–3 px in.
/// A cable half out of view keeps its skeleton further in.
const BORDER_CUT_WIDTHS: f64 = 0.25;
const BORDER_CUT_EXTRA_PX: f64 = 2.0;
/// A path that runs along the border and turns by more than this there
/// (its direction over [`JOIN_TANGENT_WIDTHS`] before and after) is two
/// cables: the annotated wires of cables-dev turn by at most 45° over 16 px
/// either side of any point.
const BORDER_CUT_TURN_RAD: f64 = std::f64::consts::FRAC_PI_2;
/// A path's end that runs along the border and turns from the path by more
/// than this is a hook of the thinning, not cable.
const BORDER_HOOK_TURN_RAD: f64 = std::f64::consts::FRAC_PI_4;

/// One cable's centreline as points along it (skeleton pixels, or the
/// superpixel walk's), from one end to the other (gaps where it crosses
/// another cable).
#[derive(Clone, Debug, PartialEq)]
pub struct CablePath {
    /// Pixel centres, in image coordinates (x right, y down).
    pub points_px: Vec<[f64; 2]>,
    /// Length along the points.
    pub length_px: f64,
}

/// What an instance method found in a mask.
#[derive(Clone, Debug, PartialEq)]
pub struct FoundPaths {
    /// One path per cable, at least the minimum length, in a deterministic
    /// order (by their first point).
    pub paths: Vec<CablePath>,
    /// The cables' typical width: mask area over skeleton length.
    pub width_px: f64,
    /// Junctions whose branches were paired (crossings resolved), when
    /// the method has such a stage (the skeleton's); 0 means the mask held
    /// no crossing and the pairing had nothing to do.
    pub junctions: Option<usize>,
}

/// Length along `points` (pixels, or whatever unit they are in).
pub fn polyline_length(points: &[[f64; 2]]) -> f64 {
    points
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

/// The unit vector from `a` to `b`, if they differ.
pub(super) fn unit(a: [f64; 2], b: [f64; 2]) -> Option<[f64; 2]> {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let n = dx.hypot(dy);
    (n > 0.0).then(|| [dx / n, dy / n])
}

/// The angle between two directions (not necessarily unit).
pub(super) fn angle_rad(a: [f64; 2], b: [f64; 2]) -> f64 {
    let norms = a[0].hypot(a[1]) * b[0].hypot(b[1]);
    if norms == 0.0 {
        return 0.0;
    }
    ((a[0] * b[0] + a[1] * b[1]) / norms)
        .clamp(-1.0, 1.0)
        .acos()
}

/// The unit direction in which `points` leaves its last point, over about
/// `span_px` of it; `None` for a path too short to say.
fn end_direction(points: &[[f64; 2]], span_px: f64) -> Option<[f64; 2]> {
    let end = *points.last()?;
    let mut travelled = 0.0;
    let mut from = end;
    for w in points.windows(2).rev() {
        travelled += (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        from = w[0];
        if travelled >= span_px {
            break;
        }
    }
    let (dx, dy) = (end[0] - from[0], end[1] - from[1]);
    let norm = dx.hypot(dy);
    (norm > 1.0).then(|| [dx / norm, dy / norm])
}

/// How much of a path, for cables `width_px` wide, gives an end's direction
/// (see [`JOIN_TANGENT_WIDTHS`]).
pub(super) fn tangent_span_px(width_px: f64) -> f64 {
    (JOIN_TANGENT_WIDTHS * width_px).max(JOIN_TANGENT_MIN_PX)
}

/// Joins paths that continue each other across a short gap of up to
/// `join_gap_widths` cable widths (see [`JOIN_GAP_WIDTHS`]) or a longer
/// one (see [`LONG_GAP_WIDTHS`]), or bend under another cable (see
/// [`JOIN_UNDER_MAX_BEND_RAD`]), by shape alone without the BGR `image`,
/// best-aligned pair first, until no pair does.
/// Each path's ends are looked at in both directions, so the result may
/// run either way.
pub fn join_continuations(
    mut paths: Vec<Vec<[f64; 2]>>,
    image: Option<&Mat>,
    width_px: f64,
    join_gap_widths: f64,
) -> Result<Vec<Vec<[f64; 2]>>, VisionError> {
    let max_gap_px = join_gap_widths * width_px + JOIN_GAP_EXTRA_PX;
    let long_gap_px = LONG_GAP_WIDTHS * width_px;
    let reach_px = max_gap_px.max(long_gap_px);
    let span_px = tangent_span_px(width_px);
    loop {
        // Every path's two ends: (path, reversed?, end point, outward direction).
        let mut ends = Vec::new();
        for (i, path) in paths.iter().enumerate() {
            let mut backwards = path.clone();
            backwards.reverse();
            for (reversed, oriented) in [(false, path), (true, &backwards)] {
                if let (Some(&point), Some(direction)) =
                    (oriented.last(), end_direction(oriented, span_px))
                {
                    ends.push((i, reversed, point, direction));
                }
            }
        }
        let mut best: Option<(f64, usize, bool, usize, bool)> = None;
        for &(i, ri, pa, da) in &ends {
            for &(j, rj, pb, db) in &ends {
                if i >= j {
                    continue;
                }
                let gap = [pb[0] - pa[0], pb[1] - pa[1]];
                let gap_px = gap[0].hypot(gap[1]);
                if gap_px > reach_px {
                    continue;
                }
                let onward = [-db[0], -db[1]];
                let mut bend = angle_rad(da, onward);
                if gap_px > GAP_DIRECTION_MIN_WIDTHS * width_px.max(2.0) {
                    bend = bend.max(angle_rad(da, gap)).max(angle_rad(gap, onward));
                }
                // Only a pair better than the best so far is worth the
                // look under a cable, which reads the image.
                if best.is_some_and(|b| bend >= b.0) {
                    continue;
                }
                let ends_pair = [&paths[i][..], &paths[j][..]];
                let joins = if gap_px > max_gap_px {
                    bend <= LONG_GAP_MAX_BEND_RAD
                        && ends_alike(image, ends_pair, [ri, rj], width_px)?
                } else {
                    bend <= JOIN_MAX_BEND_RAD
                        || (bend <= JOIN_UNDER_MAX_BEND_RAD
                            && passes_under(&paths, [i, j], pa, pb, width_px)
                            && ends_alike(image, ends_pair, [ri, rj], width_px)?)
                };
                if joins {
                    best = Some((bend, i, ri, j, rj));
                }
            }
        }
        let Some((_, i, ri, j, rj)) = best else {
            return Ok(paths);
        };
        // Path i leaves through the joined end; path j enters through its.
        let mut second = paths.swap_remove(j);
        let first = &mut paths[i];
        if ri {
            first.reverse();
        }
        if !rj {
            second.reverse();
        }
        first.extend(second);
    }
}

/// Whether the middle of the step from `a` to `b` lies on a path other
/// than those numbered `ends` (see [`JOIN_UNDER_MAX_BEND_RAD`]).
fn passes_under(
    paths: &[Vec<[f64; 2]>],
    ends: [usize; 2],
    a: [f64; 2],
    b: [f64; 2],
    width_px: f64,
) -> bool {
    let middle = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    let reach_px = 0.5 * width_px + UNDER_EXTRA_PX;
    paths.iter().enumerate().any(|(k, path)| {
        !ends.contains(&k)
            && path
                .iter()
                .any(|q| (q[0] - middle[0]).hypot(q[1] - middle[1]) <= reach_px)
    })
}

/// Whether two paths' joined ends (the first point of a path whose
/// `reversed` is set, else its last) have alike colours in `image` (see
/// [`UNDER_MAX_DELTA_E`]); always without an image, never when an end is
/// too short to show its colour.
fn ends_alike(
    image: Option<&Mat>,
    paths: [&[[f64; 2]]; 2],
    reversed: [bool; 2],
    width_px: f64,
) -> Result<bool, VisionError> {
    let Some(image) = image else {
        return Ok(true);
    };
    let mut colours = [None; 2];
    for ((colour, path), reversed) in colours.iter_mut().zip(paths).zip(reversed) {
        let from_end: Vec<[f64; 2]> = if reversed {
            path.to_vec()
        } else {
            path.iter().rev().copied().collect()
        };
        let stretch: Vec<[f64; 2]> = from_end
            .iter()
            .zip(arc_lengths_px(&from_end))
            .filter(|&(_, s_px)| (width_px..=3.0 * width_px).contains(&s_px))
            .map(|(p, _)| *p)
            .collect();
        *colour = median_colour_lab(image, &stretch)?;
    }
    Ok(match colours {
        [Some(a), Some(b)] => delta_e(a, b) <= UNDER_MAX_DELTA_E,
        _ => false,
    })
}

/// The middle of `values` (the upper one of an even count), sorted in
/// place; `None` when empty.
pub(super) fn median(values: &mut [f64]) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied()
}

/// The pixel (row, column) of `image` that `p` rounds to, if inside it.
pub(super) fn pixel_in(image: &Mat, p: [f64; 2]) -> Option<(i32, i32)> {
    let (x, y) = (p[0].round(), p[1].round());
    ((0.0..f64::from(image.cols())).contains(&x) && (0.0..f64::from(image.rows())).contains(&y))
        .then_some((y as i32, x as i32))
}

/// The colour of a BGR image under those of `points` whose pixel lies
/// inside it (a path's end may round to a row or column past the
/// border), in OpenCV's 8-bit Lab: the per-channel median, which a glint
/// or a speck of the background does not move. `None` for no such points.
pub(super) fn median_colour_lab(
    image: &Mat,
    points: &[[f64; 2]],
) -> Result<Option<[f64; 3]>, VisionError> {
    let mut channels = [Vec::new(), Vec::new(), Vec::new()];
    for (row, col) in points.iter().filter_map(|&p| pixel_in(image, p)) {
        let bgr = image
            .at_2d::<Vec3b>(row, col)
            .map_err(cv("a cable's colour"))?;
        for (channel, value) in channels.iter_mut().zip(bgr.0) {
            channel.push(value);
        }
    }
    if channels[0].is_empty() {
        return Ok(None);
    }
    let median = [Vec3b::from(channels.map(|mut c| {
        c.sort_unstable();
        c[c.len() / 2]
    }))];
    let pixel = Mat::from_slice(&median).map_err(cv("a cable's colour"))?;
    let mut lab = Mat::default();
    imgproc::cvt_color_def(&pixel, &mut lab, imgproc::COLOR_BGR2Lab)
        .map_err(cv("a cable's colour to Lab"))?;
    let lab = lab
        .at_2d::<Vec3b>(0, 0)
        .map_err(cv("a cable's colour to Lab"))?;
    Ok(Some(lab.0.map(f64::from)))
}

/// The CIE76 colour difference of two Lab colours.
pub(super) fn delta_e(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// Whether `p` lies within `margin_px` of the border of a mask of `size_px`
/// (columns, rows).
pub(super) fn near_border(p: [f64; 2], size_px: [f64; 2], margin_px: f64) -> bool {
    p[0] < margin_px
        || p[1] < margin_px
        || p[0] > size_px[0] - 1.0 - margin_px
        || p[1] > size_px[1] - 1.0 - margin_px
}

/// `path` cut where it runs within `margin_px` of the border of a mask of
/// `size_px` (columns, rows) and turns there (see [`BORDER_CUT_TURN_RAD`]):
/// two cables that leave the view side by side, joined by the mask along
/// the border, come apart; an end that hooks along the border is trimmed
/// off. A cable that grazes the border, or leaves it at a slant, turns
/// less and stays whole. A path that lies along the border all the way is
/// dropped: it is the band, or a cable all but out of view.
fn cut_at_border(
    path: Vec<[f64; 2]>,
    size_px: [f64; 2],
    margin_px: f64,
    span_px: f64,
) -> Vec<Vec<[f64; 2]>> {
    let near = |p: &[f64; 2]| near_border(*p, size_px, margin_px);
    let (Some(first), Some(last)) = (
        path.iter().position(|p| !near(p)),
        path.iter().rposition(|p| !near(p)),
    ) else {
        return Vec::new();
    };
    // How far the path turns from `before` (ending where a run along the
    // border starts) to `after` (starting where it ends).
    let turn_rad = |before: &[[f64; 2]], after: &[[f64; 2]]| {
        let mut onward = after.to_vec();
        onward.reverse();
        match (
            end_direction(before, span_px),
            end_direction(&onward, span_px),
        ) {
            (Some(into), Some(back)) => angle_rad(into, [-back[0], -back[1]]),
            _ => 0.0,
        }
    };
    let keep_start = turn_rad(&path[..=first], &path[first..]) <= BORDER_HOOK_TURN_RAD;
    let keep_end = turn_rad(&path[..=last], &path[last + 1..]) <= BORDER_HOOK_TURN_RAD;

    let mut pieces = vec![if keep_start {
        path[..=first].to_vec()
    } else {
        vec![path[first]]
    }];
    let mut i = first + 1;
    while i <= last {
        if !near(&path[i]) {
            pieces.last_mut().expect("never empty").push(path[i]);
            i += 1;
            continue;
        }
        let end = i + path[i..]
            .iter()
            .position(|p| !near(p))
            .expect("last is not near");
        if turn_rad(&path[first..i], &path[end..=last]) > BORDER_CUT_TURN_RAD {
            pieces.push(Vec::new());
        } else {
            pieces
                .last_mut()
                .expect("never empty")
                .extend_from_slice(&path[i..end]);
        }
        i = end;
    }
    if keep_end {
        pieces
            .last_mut()
            .expect("never empty")
            .extend_from_slice(&path[last + 1..]);
    }
    pieces
}

/// The cables from pixel paths in `mask`, whichever method found them:
/// paths cut where they run along the mask's border (see
/// [`BORDER_CUT_WIDTHS`]), pieces that continue each other joined (see
/// [`join_continuations`] across up to `join_gap_widths`, given the BGR
/// `image` the mask was found in, if any), each run from its end with the
/// smaller (x, y) and kept if at least `min_length_px` long, sorted by
/// their first point.
pub(super) fn finish_paths(
    paths: Vec<Vec<[f64; 2]>>,
    mask: &Mat,
    image: Option<&Mat>,
    width_px: f64,
    min_length_px: f64,
    join_gap_widths: f64,
) -> Result<FoundPaths, VisionError> {
    let size_px = [f64::from(mask.cols()), f64::from(mask.rows())];
    let margin_px = BORDER_CUT_WIDTHS * width_px + BORDER_CUT_EXTRA_PX;
    let span_px = tangent_span_px(width_px);
    let paths = paths
        .into_iter()
        .flat_map(|path| cut_at_border(path, size_px, margin_px, span_px))
        .collect();
    let paths = join_continuations(paths, image, width_px, join_gap_widths)?;

    let mut out: Vec<CablePath> = paths
        .into_iter()
        .filter_map(|mut points_px| {
            let (first, last) = (*points_px.first()?, *points_px.last()?);
            if (last[0], last[1]) < (first[0], first[1]) {
                points_px.reverse();
            }
            let length_px = polyline_length(&points_px);
            (length_px >= min_length_px).then_some(CablePath {
                points_px,
                length_px,
            })
        })
        .collect();
    out.sort_by(|a, b| {
        let (pa, pb) = (a.points_px[0], b.points_px[0]);
        (pa[0], pa[1])
            .partial_cmp(&(pb[0], pb[1]))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    Ok(FoundPaths {
        paths: out,
        width_px,
        junctions: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::vision::curves::segment_px;
    use opencv::core::{CV_8UC3, Point, Scalar};

    #[test]
    fn pieces_of_one_cable_across_a_gap_are_joined_in_order() {
        // Given out of order and one of them backwards, 20 px apart, 8 px wide.
        let pieces = vec![
            segment_px([200.0, 100.0], [120.0, 100.0]),
            segment_px([0.0, 100.0], [100.0, 100.0]),
        ];
        let joined = join_continuations(pieces, None, 8.0, JOIN_GAP_WIDTHS).unwrap();
        assert_eq!(joined.len(), 1);
        let path = &joined[0];
        assert_eq!(path.len(), 101 + 81);
        // One direction throughout: x never steps back.
        let steps: Vec<f64> = path.windows(2).map(|w| w[1][0] - w[0][0]).collect();
        assert!(steps.iter().all(|&d| d > 0.0) || steps.iter().all(|&d| d < 0.0));
    }

    #[test]
    fn ends_that_meet_at_an_angle_or_lie_far_apart_stay_separate() {
        let corner = vec![
            segment_px([0.0, 100.0], [100.0, 100.0]),
            segment_px([110.0, 110.0], [110.0, 200.0]),
        ];
        assert_eq!(
            join_continuations(corner, None, 8.0, JOIN_GAP_WIDTHS)
                .unwrap()
                .len(),
            2
        );
        // In line, but more than 15 widths apart.
        let far = vec![
            segment_px([0.0, 100.0], [100.0, 100.0]),
            segment_px([230.0, 100.0], [330.0, 100.0]),
        ];
        assert_eq!(
            join_continuations(far, None, 8.0, JOIN_GAP_WIDTHS)
                .unwrap()
                .len(),
            2
        );
        // Side by side, parallel: their ends are close, but one does not
        // lead into the other.
        let parallel = vec![
            segment_px([0.0, 100.0], [100.0, 100.0]),
            segment_px([105.0, 112.0], [200.0, 112.0]),
        ];
        assert_eq!(
            join_continuations(parallel, None, 8.0, JOIN_GAP_WIDTHS)
                .unwrap()
                .len(),
            2
        );
    }

    #[test]
    fn ends_offset_sideways_across_a_gap_under_a_width_are_joined() {
        // 12 px wide: the second piece starts 4 px on and 6 px aside, as
        // the skeleton's ends hook where the mask narrows to a neck. The
        // step between the ends turns by 0.98 rad from both.
        let pieces = vec![
            segment_px([0.0, 100.0], [100.0, 100.0]),
            segment_px([104.0, 106.0], [200.0, 106.0]),
        ];
        assert_eq!(
            join_continuations(pieces, None, 12.0, JOIN_GAP_WIDTHS)
                .unwrap()
                .len(),
            1
        );
    }

    #[test]
    fn a_wider_short_gap_joins_ends_that_bend_too_much_for_a_long_gap() {
        // 8 px wide, 44 px apart, bending by 0.3 rad: over four widths
        // (and 4 px), within six, and too bent for the long gap's rule.
        let onward = [144.0 + 100.0 * 0.3_f64.cos(), 100.0 + 100.0 * 0.3_f64.sin()];
        let pieces = vec![
            segment_px([0.0, 100.0], [100.0, 100.0]),
            segment_px([144.0, 100.0], onward),
        ];
        let joined =
            |gap_widths| join_continuations(pieces.clone(), None, 8.0, gap_widths).unwrap();
        assert_eq!(joined(JOIN_GAP_WIDTHS).len(), 2);
        assert_eq!(joined(PAINTED_JOIN_GAP_WIDTHS).len(), 1);
    }

    /// `paths` drawn 8 px wide on a gray image, each in its colour.
    fn drawn(paths: &[(&Vec<[f64; 2]>, Scalar)]) -> Mat {
        let mut image =
            Mat::new_rows_cols_with_default(240, 400, CV_8UC3, Scalar::all(128.0)).unwrap();
        for (path, bgr) in paths {
            for p in path.iter() {
                let centre = Point::new(p[0].round() as i32, p[1].round() as i32);
                imgproc::circle(&mut image, centre, 4, *bgr, -1, imgproc::LINE_8, 0).unwrap();
            }
        }
        image
    }

    #[test]
    fn a_cable_lost_for_a_stretch_is_joined_when_straight_on_and_of_one_colour() {
        // 80 px (10 widths) apart, in line.
        let before = segment_px([20.0, 100.0], [120.0, 100.0]);
        let after = segment_px([200.0, 100.0], [300.0, 100.0]);
        // The same, turning by 0.4 rad (23°) across the gap.
        let bent = segment_px([200.0, 100.0], [200.0 + 92.0, 100.0 + 39.0]);
        let (blue, red) = (
            Scalar::new(200.0, 60.0, 30.0, 0.0),
            Scalar::new(30.0, 40.0, 210.0, 0.0),
        );
        for (second, bgr, pieces) in [(&after, blue, 1), (&after, red, 2), (&bent, blue, 2)] {
            let image = drawn(&[(&before, blue), (second, bgr)]);
            let paths = vec![before.clone(), second.clone()];
            let found = join_continuations(paths, Some(&image), 8.0, JOIN_GAP_WIDTHS).unwrap();
            assert_eq!(found.len(), pieces);
        }
    }

    /// Two pieces 24 px apart that turn by 0.6 rad (34°) between them, and
    /// a cable across the middle of the gap.
    fn bent_under() -> [Vec<[f64; 2]>; 3] {
        let turn_rad: f64 = 0.6;
        let before = segment_px([100.0, 0.0], [100.0, 88.0]);
        let from = [100.0 + 24.0 * (turn_rad / 2.0).sin(), 112.0];
        let to = [
            from[0] + 90.0 * turn_rad.sin(),
            from[1] + 90.0 * turn_rad.cos(),
        ];
        let across = segment_px([0.0, 100.0], [250.0, 100.0]);
        [before, segment_px(from, to), across]
    }

    #[test]
    fn a_cable_bending_under_another_is_joined_across_it() {
        let [before, after, across] = bent_under();
        let joined = |paths: Vec<Vec<[f64; 2]>>| {
            join_continuations(paths, None, 8.0, JOIN_GAP_WIDTHS).unwrap()
        };
        // Nothing between them: a corner, two cables.
        assert_eq!(joined(vec![before.clone(), after.clone()]).len(), 2);
        // A cable across the gap's middle: one cable passing under it.
        let found = joined(vec![before.clone(), across.clone(), after.clone()]);
        assert_eq!(found.len(), 2);
        assert!(found.contains(&across));
        // The other cable only near the gap, not across it: still a corner.
        let beside = segment_px([0.0, 130.0], [80.0, 130.0]);
        assert_eq!(joined(vec![before, beside, after]).len(), 3);
    }

    #[test]
    fn a_cable_is_joined_under_another_only_to_a_piece_of_its_colour() {
        let [before, after, across] = bent_under();
        let (blue, red) = (
            Scalar::new(200.0, 60.0, 30.0, 0.0),
            Scalar::new(30.0, 40.0, 210.0, 0.0),
        );
        for (after_bgr, pieces) in [(blue, 2), (red, 3)] {
            let image = drawn(&[
                (&before, blue),
                (&after, after_bgr),
                (&across, Scalar::all(20.0)),
            ]);
            let paths = vec![before.clone(), across.clone(), after.clone()];
            let found = join_continuations(paths, Some(&image), 8.0, JOIN_GAP_WIDTHS).unwrap();
            assert_eq!(found.len(), pieces);
        }
    }

    #[test]
    fn a_colour_is_read_only_under_points_inside_the_image() {
        let blue = Scalar::new(200.0, 60.0, 30.0, 0.0);
        let image = Mat::new_rows_cols_with_default(10, 10, CV_8UC3, blue).unwrap();
        let inside = median_colour_lab(&image, &[[0.0, 0.0], [9.0, 9.0]]).unwrap();
        // A path's end that rounds to row -1 or column 10 is left out.
        let with_outside =
            median_colour_lab(&image, &[[0.0, -0.6], [0.0, 0.0], [9.0, 9.0], [9.6, 5.0]]).unwrap();
        assert!(inside.is_some());
        assert_eq!(with_outside, inside);
        assert_eq!(
            median_colour_lab(&image, &[[-1.0, 4.0], [4.0, 10.0]]).unwrap(),
            None
        );
    }

    /// A 640 × 480 mask's border cut at 6 px, directions over 16 px.
    fn cut(path: Vec<[f64; 2]>) -> Vec<Vec<[f64; 2]>> {
        cut_at_border(path, [640.0, 480.0], 6.0, 16.0)
    }

    #[test]
    fn two_cables_joined_along_the_border_are_cut_apart() {
        // Into the right border, 30 px along it, and back out.
        let mut path = segment_px([500.0, 100.0], [637.0, 200.0]);
        path.extend(segment_px([637.0, 201.0], [637.0, 230.0]));
        path.extend(segment_px([637.0, 231.0], [500.0, 330.0]));
        let pieces = cut(path);
        assert_eq!(pieces.len(), 2);
        for piece in &pieces {
            assert!(piece.iter().all(|p| p[0] < 634.0));
            assert!(polyline_length(piece) > 150.0);
        }
    }

    #[test]
    fn a_hook_along_the_border_is_trimmed_off_a_cable_end() {
        let mut path = segment_px([300.0, 100.0], [637.0, 100.0]);
        path.extend(segment_px([637.0, 101.0], [637.0, 130.0]));
        let pieces = cut(path.clone());
        assert_eq!(pieces.len(), 1);
        let end = *pieces[0].last().unwrap();
        assert!(end[0] < 634.0 && (end[1] - 100.0).abs() < 0.5, "{end:?}");
        // The same, walked from the hook.
        path.reverse();
        let mut pieces = cut(path);
        assert_eq!(pieces.len(), 1);
        pieces[0].reverse();
        assert_eq!(*pieces[0].last().unwrap(), end);
    }

    #[test]
    fn a_cable_leaving_at_a_slant_keeps_its_ends() {
        // The last 40 px lie within 6 px of the top border, the first 45 px
        // within 6 px of the left.
        let mut path = segment_px([1.0, 300.0], [40.0, 200.0]);
        path.extend(segment_px([41.0, 199.0], [400.0, 1.0]));
        assert_eq!(cut(path.clone()), vec![path]);
    }

    #[test]
    fn a_cable_grazing_the_border_stays_whole() {
        // A 146 px arc whose leftmost point lies 4 px from the border.
        let path: Vec<[f64; 2]> = (0..=260)
            .map(|i| {
                let a = 2.5 + 1.3 * f64::from(i) / 260.0;
                [150.0 + 146.0 * a.cos(), 240.0 + 146.0 * a.sin()]
            })
            .collect();
        let pieces = cut(path.clone());
        assert_eq!(pieces, vec![path]);
        // Lying along the border all the way, it is dropped.
        assert!(cut(segment_px([3.0, 100.0], [3.0, 300.0])).is_empty());
    }
}
