//! What lies in front of the cables: opaque polygons drawn over them (a
//! board over a stretch of the simulated cable, the parts of the arm's
//! hand), each in its colour with a little texture, and what of a cable
//! they leave visible.

use opencv::core::{self, Mat, Vec3f};
use opencv::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::background::smooth_noise;
use super::{RenderError, cv, pixels_mut};
use crate::perception::vision::paths::polyline_length;

/// Something opaque in front of the cables: a simple polygon of the image,
/// its edges anti-aliased, filled with one colour whose brightness a
/// smooth texture varies.
#[derive(Clone, Debug, PartialEq)]
pub struct OccluderSpec {
    /// Its corners in order, at least three.
    pub outline_px: Vec<[f64; 2]>,
    pub bgr: [u8; 3],
    /// The texture moves its brightness by up to ± this fraction (0: flat).
    pub texture: f64,
    /// The size of the texture's mottles.
    pub grain_px: f64,
    /// Fixes the texture, so that an occluder that stays put looks the
    /// same in every image.
    pub texture_seed: u64,
}

/// What the simulated camera sees in front of the cable. The default is
/// nothing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Occlusion {
    /// A board lying over a stretch of the cable.
    pub board: Option<Board>,
    /// The arm's hand drawn where the TCP is (see `hand`), covering the
    /// cable as it comes down over it.
    pub arm_in_view: bool,
}

/// A board lying over a stretch of the cable, placed along the cable as
/// the image shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct Board {
    /// The share of the cable's length in the image that it hides, 0 to 1.
    pub hidden_fraction: f64,
    /// Where the hidden stretch lies: 0 at the start of the cable's image
    /// (its left end in the simulated cell), 1 at its end.
    pub position: f64,
    pub bgr: [u8; 3],
    pub texture_seed: u64,
}

/// A board's texture: the mottles of cardboard or pressboard.
const BOARD_TEXTURE: f64 = 0.07;
const BOARD_GRAIN_PX: f64 = 5.0;
/// A board reaches this far beyond the cable each side, as a fraction of
/// the stretch it hides, and at least this many cable diameters: a board
/// is wider than the cable under it.
const BOARD_MARGIN_OF_LENGTH: f64 = 0.25;
const BOARD_MIN_MARGIN_DIAMETERS: f64 = 2.5;

/// The board over `centerline_px` (the cable as the image shows it, of
/// radius `radius_px`): a rectangle along the chord of the hidden stretch,
/// its ends across the chord where the stretch begins and ends (past the
/// cable's rounded end where the stretch reaches it), wide enough to hide
/// the stretch's bow. `None` when it hides nothing.
pub(super) fn board_over(
    centerline_px: &[[f64; 2]],
    radius_px: f64,
    board: &Board,
) -> Option<OccluderSpec> {
    let length = polyline_length(centerline_px);
    let hidden = board.hidden_fraction.clamp(0.0, 1.0) * length;
    if !(hidden.is_finite() && hidden > 0.0) {
        return None;
    }
    let start = board.position.clamp(0.0, 1.0) * (length - hidden);
    let end = start + hidden;
    let stretch = stretch_of(centerline_px, start, end);
    let (&a, &b) = (stretch.first()?, stretch.last()?);
    let along =
        direction(a, b).or_else(|| direction(*centerline_px.first()?, *centerline_px.last()?))?;
    let across = [-along[1], along[0]];
    let project = |p: [f64; 2], axis: [f64; 2]| (p[0] - a[0]) * axis[0] + (p[1] - a[1]) * axis[1];
    let (low, high) = stretch.iter().fold((0.0_f64, 0.0_f64), |(low, high), &p| {
        let v = project(p, across);
        (low.min(v), high.max(v))
    });
    let margin =
        (BOARD_MARGIN_OF_LENGTH * hidden).max(BOARD_MIN_MARGIN_DIAMETERS * 2.0 * radius_px);
    let at_an_end = 1e-9 * length;
    let cap = radius_px + 1.0;
    let u0 = if start <= at_an_end { -cap } else { 0.0 };
    let u1 = project(b, along) + if end >= length - at_an_end { cap } else { 0.0 };
    let (v0, v1) = (low - radius_px - margin, high + radius_px + margin);
    let corner = |u: f64, v: f64| {
        [
            a[0] + u * along[0] + v * across[0],
            a[1] + u * along[1] + v * across[1],
        ]
    };
    Some(OccluderSpec {
        outline_px: vec![
            corner(u0, v0),
            corner(u1, v0),
            corner(u1, v1),
            corner(u0, v1),
        ],
        bgr: board.bgr,
        texture: BOARD_TEXTURE,
        grain_px: BOARD_GRAIN_PX,
        texture_seed: board.texture_seed,
    })
}

/// The part of `points` between `from` and `to` of its length, its ends
/// interpolated.
fn stretch_of(points: &[[f64; 2]], from: f64, to: f64) -> Vec<[f64; 2]> {
    let mut stretch = Vec::new();
    let mut walked = 0.0;
    for pair in points.windows(2) {
        let [p, q] = [pair[0], pair[1]];
        let step = (q[0] - p[0]).hypot(q[1] - p[1]);
        if step > 0.0 && walked + step >= from && walked <= to {
            let at = |s: f64| {
                let t = ((s - walked) / step).clamp(0.0, 1.0);
                [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]
            };
            if stretch.is_empty() {
                stretch.push(at(from));
            }
            stretch.push(at(to));
        }
        walked += step;
    }
    stretch
}

/// The unit vector from `a` to `b`, if they differ.
fn direction(a: [f64; 2], b: [f64; 2]) -> Option<[f64; 2]> {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let norm = dx.hypot(dy);
    (norm > 0.0).then(|| [dx / norm, dy / norm])
}

pub(super) fn check(index: usize, occluder: &OccluderSpec) -> Result<(), RenderError> {
    let bad = |reason| Err(RenderError::BadOccluder { index, reason });
    if occluder.outline_px.len() < 3 {
        return bad("its outline has fewer than three corners");
    }
    if !occluder.outline_px.iter().flatten().all(|v| v.is_finite()) {
        return bad("its outline has a corner that is not finite");
    }
    if !(occluder.texture.is_finite() && occluder.texture >= 0.0) {
        return bad("its texture is not a finite number ≥ 0");
    }
    if !(occluder.grain_px.is_finite() && occluder.grain_px > 0.0) {
        return bad("its grain is not positive and finite");
    }
    Ok(())
}

/// Draws `occluders` in order over `image` (CV_32FC3).
pub(super) fn draw_all(image: &mut Mat, occluders: &[OccluderSpec]) -> Result<(), RenderError> {
    if occluders.is_empty() {
        return Ok(());
    }
    let (width, height) = (image.cols(), image.rows());
    let pixels = pixels_mut(image)?;
    for occluder in occluders {
        draw(pixels, width, height, occluder)?;
    }
    Ok(())
}

/// The pixels whose centre lies within any of `outlines` (CV_8UC1, 0/255).
pub(super) fn covered_pixels(
    width: i32,
    height: i32,
    outlines: &[&[[f64; 2]]],
) -> Result<Mat, RenderError> {
    let mut covered = Mat::new_rows_cols_with_default(height, width, core::CV_8UC1, 0.into())
        .map_err(cv("allocate the covered pixels"))?;
    let bytes = covered
        .data_bytes_mut()
        .map_err(cv("mark the covered pixels"))?;
    for outline in outlines {
        let Some([x0, y0, x1, y1]) = pixel_box(outline, width, height) else {
            continue;
        };
        for y in y0..=y1 {
            for x in x0..=x1 {
                if depth_inside(outline, [f64::from(x), f64::from(y)]) >= 0.0 {
                    bytes[(y * width + x) as usize] = 255;
                }
            }
        }
    }
    Ok(covered)
}

/// The pixels around `outline`, a pixel wider (a pixel a little outside
/// still takes part of its anti-aliased edge), cut to the image: first
/// and last column and row; `None` when it misses the image.
fn pixel_box(outline: &[[f64; 2]], width: i32, height: i32) -> Option<[i32; 4]> {
    let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in outline {
        for axis in 0..2 {
            min[axis] = min[axis].min(p[axis]);
            max[axis] = max[axis].max(p[axis]);
        }
    }
    let x0 = (min[0].floor() - 1.0).max(0.0);
    let y0 = (min[1].floor() - 1.0).max(0.0);
    let x1 = (max[0].ceil() + 1.0).min(f64::from(width - 1));
    let y1 = (max[1].ceil() + 1.0).min(f64::from(height - 1));
    (x0 <= x1 && y0 <= y1).then_some([x0 as i32, y0 as i32, x1 as i32, y1 as i32])
}

fn draw(
    pixels: &mut [Vec3f],
    width: i32,
    height: i32,
    occluder: &OccluderSpec,
) -> Result<(), RenderError> {
    let outline = &occluder.outline_px;
    let Some([x0, y0, x1, y1]) = pixel_box(outline, width, height) else {
        return Ok(());
    };
    let (box_width, box_height) = (x1 - x0 + 1, y1 - y0 + 1);
    let texture = if occluder.texture > 0.0 {
        let cells = |side: i32| {
            ((f64::from(side) / occluder.grain_px).ceil() as i32 + 1).clamp(2, side.max(2))
        };
        let mut rng = ChaCha8Rng::seed_from_u64(occluder.texture_seed);
        let noise = smooth_noise(
            box_width,
            box_height,
            cells(box_width),
            cells(box_height),
            1,
            &mut rng,
        )?;
        noise
            .data_typed::<f32>()
            .map_err(cv("read an occluder's texture"))?
            .to_vec()
    } else {
        Vec::new()
    };
    let colour = occluder.bgr.map(f64::from);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let depth = depth_inside(outline, [f64::from(x), f64::from(y)]);
            let coverage = (depth + 0.5).clamp(0.0, 1.0);
            if coverage <= 0.0 {
                continue;
            }
            let i = (y * width + x) as usize;
            let grain = texture
                .get(((y - y0) * box_width + (x - x0)) as usize)
                .map_or(0.0, |&v| f64::from(v));
            let shade = 1.0 + occluder.texture * grain;
            let pixel = &mut pixels[i];
            for c in 0..3 {
                let lit = (colour[c] * shade) as f32;
                pixel[c] = pixel[c] * (1.0 - coverage as f32) + lit * coverage as f32;
            }
        }
    }
    Ok(())
}

/// How far `point` lies inside `outline` (negative: outside), in pixels.
fn depth_inside(outline: &[[f64; 2]], point: [f64; 2]) -> f64 {
    let [px, py] = point;
    let mut inside = false;
    let mut nearest = f64::INFINITY;
    for (i, &a) in outline.iter().enumerate() {
        let b = outline[(i + 1) % outline.len()];
        if (a[1] > py) != (b[1] > py) && px < a[0] + (py - a[1]) * (b[0] - a[0]) / (b[1] - a[1]) {
            inside = !inside;
        }
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let length2 = dx * dx + dy * dy;
        let t = if length2 > 0.0 {
            (((px - a[0]) * dx + (py - a[1]) * dy) / length2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        nearest = nearest.min((px - a[0] - t * dx).hypot(py - a[1] - t * dy));
    }
    if inside { nearest } else { -nearest }
}

/// The stretches of `line` that none of `outlines` covers (at least two
/// points each), in order along it.
pub(super) fn visible_stretches(line: &[[f64; 2]], outlines: &[&[[f64; 2]]]) -> Vec<Vec<[f64; 2]>> {
    let mut stretches: Vec<Vec<[f64; 2]>> = Vec::new();
    let mut open = false;
    for &point in line {
        let covered = outlines
            .iter()
            .any(|outline| depth_inside(outline, point) >= 0.0);
        match stretches.last_mut() {
            _ if covered => {
                open = false;
                continue;
            }
            Some(stretch) if open => stretch.push(point),
            _ => stretches.push(vec![point]),
        }
        open = true;
    }
    stretches.retain(|stretch| stretch.len() >= 2);
    stretches
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(length_px: usize) -> Vec<[f64; 2]> {
        (0..=length_px).map(|i| [10.0 + i as f64, 50.0]).collect()
    }

    fn board(hidden_fraction: f64, position: f64) -> Board {
        Board {
            hidden_fraction,
            position,
            bgr: [150, 170, 185],
            texture_seed: 1,
        }
    }

    #[test]
    fn a_board_hides_its_share_where_its_position_puts_it() {
        let line = straight(200);
        let occluder = board_over(&line, 2.0, &board(0.3, 0.5)).expect("a board");
        let visible = visible_stretches(&line, &[occluder.outline_px.as_slice()]);
        // 60 px hidden in the middle: 70 px visible each side.
        assert_eq!(visible.len(), 2);
        for (stretch, expected) in visible.iter().zip([70.0, 70.0]) {
            let length = polyline_length(stretch);
            assert!((length - expected).abs() <= 1.0, "{length}");
        }
        assert!((visible[0][0][0] - 10.0).abs() < 1e-9);
        // At the start: the rest is one stretch, and the cable's end is
        // hidden beyond its centre line.
        let occluder = board_over(&line, 2.0, &board(0.3, 0.0)).expect("a board");
        assert!(depth_inside(&occluder.outline_px, [10.0 - 2.5, 50.0]) > 0.0);
        let visible = visible_stretches(&line, &[occluder.outline_px.as_slice()]);
        assert_eq!(visible.len(), 1);
        assert!((polyline_length(&visible[0]) - 140.0).abs() <= 1.0);
    }

    #[test]
    fn a_whole_board_hides_all_and_an_empty_one_nothing() {
        let line = straight(100);
        let occluder = board_over(&line, 2.0, &board(1.0, 0.7)).expect("a board");
        assert!(visible_stretches(&line, &[occluder.outline_px.as_slice()]).is_empty());
        assert!(board_over(&line, 2.0, &board(0.0, 0.7)).is_none());
        assert_eq!(visible_stretches(&line, &[]), vec![line.clone()]);
    }

    #[test]
    fn depth_inside_is_the_distance_to_the_nearest_edge_signed() {
        let square = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        assert!((depth_inside(&square, [5.0, 3.0]) - 3.0).abs() < 1e-12);
        assert!((depth_inside(&square, [-2.0, 5.0]) + 2.0).abs() < 1e-12);
        assert!((depth_inside(&square, [13.0, 14.0]) + 5.0).abs() < 1e-12);
    }
}
