//! Thinning the mask to a one-pixel, 8-connected skeleton (Zhang–Suen,
//! then a clean-up of the staircases and corner pixels it leaves), on a
//! grid padded by one pixel so that neighbour look-ups never leave it.
//!
//! The thinning is our own rather than OpenCV's `ximgproc::thinning`,
//! which gives the same skeleton (on the mask made 0/255 and padded by a
//! background pixel, as the grid is) but at OpenCV 4.6 scans the whole
//! image in every pass where this scans only the pixels still on: the
//! instance stage took 34–37 ms instead of 3 ms on the held-out
//! photographs (`eval-vision`, release build), the whole pipeline three
//! to four times as long.

use opencv::core::Mat;
use opencv::prelude::*;

use crate::perception::vision::error::{VisionError, cv};
use crate::perception::vision::mask::continuous;
use crate::perception::vision::runs::runs;

/// A mask's skeleton, and the cables' typical width it gives.
pub(super) struct Skeleton {
    /// The grid, holding the skeleton's pixels.
    pub grid: Grid,
    /// The skeleton's pixels, as indices into the grid.
    pub pixels: Vec<usize>,
    /// Mask area over skeleton length: the cables' typical width (0 for
    /// an empty mask).
    pub width_px: f64,
}

/// The skeleton of a CV_8U mask (non-zero = cable).
pub(super) fn skeleton(mask: &Mat) -> Result<Skeleton, VisionError> {
    let (mut grid, mut fg) = Grid::from_mask(mask)?;
    let area = fg.len() as f64;
    grid.thin(&mut fg);
    grid.remove_redundant(&mut fg);
    let width_px = if fg.is_empty() {
        0.0
    } else {
        area / fg.len() as f64
    };
    Ok(Skeleton {
        grid,
        pixels: fg,
        width_px,
    })
}

/// Thinning and graph on a grid padded by one pixel, so that neighbour
/// look-ups never leave it.
pub(super) struct Grid {
    stride: usize,
    pub(super) on: Vec<u8>,
    offsets: [isize; 8],
}

impl Grid {
    /// Pads a CV_8U mask (non-zero = cable), and lists its pixels on, in
    /// the grid's order.
    fn from_mask(mask: &Mat) -> Result<(Grid, Vec<usize>), VisionError> {
        let mask = continuous(mask)?;
        // A mask of more channels is refused here, not read past the grid.
        let bytes = mask.data_typed::<u8>().map_err(cv("read mask"))?;
        let rows = usize::try_from(mask.rows()).unwrap_or(0);
        let cols = usize::try_from(mask.cols()).unwrap_or(0);
        let stride = cols + 2;
        let mut on = vec![0u8; stride * (rows + 2)];
        let mut fg = Vec::new();
        for run in runs(bytes, cols).0 {
            let base = (run.row + 1) * stride + 1;
            on[base + run.start..base + run.end].fill(1);
            fg.extend(base + run.start..base + run.end);
        }
        let s = stride as isize;
        let grid = Grid {
            stride,
            on,
            // N, NE, E, SE, S, SW, W, NW: clockwise from north.
            offsets: [-s, -s + 1, 1, s + 1, s, s - 1, -1, -s - 1],
        };
        Ok((grid, fg))
    }

    pub(super) fn xy(&self, i: usize) -> [f64; 2] {
        [
            (i % self.stride) as f64 - 1.0,
            (i / self.stride) as f64 - 1.0,
        ]
    }

    /// The 8 neighbours' states as one byte: bit k is neighbour k,
    /// clockwise from north, so that each rule below is one look-up.
    fn ring_code(&self, i: usize) -> usize {
        self.offsets.iter().enumerate().fold(0, |code, (k, off)| {
            code | usize::from(self.on[i.wrapping_add_signed(*off)]) << k
        })
    }

    pub(super) fn neighbours(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.offsets
            .iter()
            .map(move |off| i.wrapping_add_signed(*off))
            .filter(|&j| self.on[j] != 0)
    }

    pub(super) fn degree(&self, i: usize) -> usize {
        self.neighbours(i).count()
    }

    /// Zhang–Suen thinning of the pixels in `fg`, which is left holding the
    /// skeleton. A pixel whose 8 neighbours are all on is never taken, so
    /// it is set aside until one of them goes: each pass then visits the
    /// mask's edge rather than all of it.
    fn thin(&mut self, fg: &mut Vec<usize>) {
        let mut inside = vec![false; self.on.len()];
        let mut edge = Vec::with_capacity(fg.len());
        for &i in fg.iter() {
            if self.ring_code(i) == ALL_ON {
                inside[i] = true;
            } else {
                edge.push(i);
            }
        }
        let mut marked = Vec::new();
        loop {
            let mut changed = false;
            for taken in &ZHANG_SUEN_TAKES {
                marked.clear();
                marked.extend(edge.iter().copied().filter(|&i| taken[self.ring_code(i)]));
                for &i in &marked {
                    self.on[i] = 0;
                }
                for &i in &marked {
                    for off in self.offsets {
                        let j = i.wrapping_add_signed(off);
                        if inside[j] {
                            inside[j] = false;
                            edge.push(j);
                        }
                    }
                }
                changed |= !marked.is_empty();
                edge.retain(|&i| self.on[i] != 0);
            }
            if !changed {
                break;
            }
        }
        fg.retain(|&i| self.on[i] != 0);
    }

    /// Removes skeleton pixels whose removal keeps their neighbours
    /// connected (Yokoi's 8-connectivity number is 1) and that are not end
    /// points: Zhang–Suen leaves staircases and corner pixels that would
    /// otherwise read as junctions.
    fn remove_redundant(&mut self, fg: &mut Vec<usize>) {
        loop {
            let mut changed = false;
            for &i in fg.iter() {
                if REDUNDANT[self.ring_code(i)] {
                    self.on[i] = 0;
                    changed = true;
                }
            }
            fg.retain(|&i| self.on[i] != 0);
            if !changed {
                break;
            }
        }
    }
}

/// A ring code with all 8 neighbours on.
const ALL_ON: usize = 0xff;

/// Which rings (see [`Grid::ring_code`]) each of Zhang–Suen's two
/// sub-passes takes a pixel off in.
const ZHANG_SUEN_TAKES: [[bool; 256]; 2] = [zhang_suen_table(0), zhang_suen_table(1)];

/// Which rings make a pixel redundant (see [`Grid::remove_redundant`]).
const REDUNDANT: [bool; 256] = redundant_table();

/// Neighbour k of a ring code, 0 or 1.
const fn bit(code: usize, k: usize) -> u32 {
    ((code >> (k % 8)) & 1) as u32
}

/// Zhang–Suen's rule for sub-pass `pass`: 2 to 6 neighbours on, one
/// step from off to on going round, and neither N, E and S all on nor
/// E, S and W (first sub-pass), or neither N, E and W nor N, S and W
/// (second).
const fn zhang_suen_table(pass: usize) -> [bool; 256] {
    let mut table = [false; 256];
    let mut code: usize = 0;
    while code < 256 {
        let on = code.count_ones();
        let mut steps = 0;
        let mut k = 0;
        while k < 8 {
            if bit(code, k) == 0 && bit(code, k + 1) == 1 {
                steps += 1;
            }
            k += 1;
        }
        let (n, e, s, w) = (bit(code, 0), bit(code, 2), bit(code, 4), bit(code, 6));
        let kept = if pass == 0 {
            n * e * s != 0 || e * s * w != 0
        } else {
            n * e * w != 0 || n * s * w != 0
        };
        table[code] = on >= 2 && on <= 6 && steps == 1 && !kept;
        code += 1;
    }
    table
}

/// Yokoi's rule: at least 2 neighbours on and an 8-connectivity number
/// of 1, summed over the 4-neighbours E, N, W, S of the complement
/// (x1 = E, x2 = NE, x3 = N, x4 = NW, x5 = W, x6 = SW, x7 = S, x8 = SE).
const fn redundant_table() -> [bool; 256] {
    let mut table = [false; 256];
    let mut code: usize = 0;
    while code < 256 {
        // Yokoi's x1..x8 as neighbour indices (clockwise from north).
        let order = [2, 1, 0, 7, 6, 5, 4, 3];
        let mut x = [0i32; 8];
        let mut k = 0;
        while k < 8 {
            x[k] = 1 - bit(code, order[k]) as i32;
            k += 1;
        }
        let mut n8 = 0;
        let mut k = 0;
        while k < 8 {
            n8 += x[k] - x[k] * x[(k + 1) % 8] * x[(k + 2) % 8];
            k += 2;
        }
        table[code] = code.count_ones() >= 2 && n8 == 1;
        code += 1;
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;
    use opencv::core::{CV_8UC1, Point, Rect, Scalar};
    use opencv::imgproc;

    /// A 30 × 40 mask holding a bar 9 px tall across its whole width
    /// (rows 10 to 18), its pixels `value`.
    fn bar(value: f64) -> Mat {
        let mut mask = Mat::new_rows_cols_with_default(30, 40, CV_8UC1, Scalar::all(0.0)).unwrap();
        Mat::roi_mut(&mut mask, Rect::new(0, 10, 40, 9))
            .unwrap()
            .set_to_def(&Scalar::all(value))
            .unwrap();
        mask
    }

    /// The skeleton's pixels as (x, y), and its width.
    fn thinned(mask: &Mat) -> (Vec<[f64; 2]>, f64) {
        let s = skeleton(mask).unwrap();
        let xy = s.pixels.iter().map(|&i| s.grid.xy(i)).collect();
        (xy, s.width_px)
    }

    #[test]
    fn a_cable_running_out_of_the_image_thins_at_the_border_as_elsewhere() {
        // The grid's border of background lets the outermost rows and
        // columns thin like any other (OpenCV's thinning never thins them:
        // the bar's ends would stay 9 px tall).
        let (xy, width_px) = thinned(&bar(255.0));
        assert!(!xy.is_empty());
        assert!(xy.iter().all(|p| p[1] == 14.0), "{xy:?}");
        assert!(xy.len() > 30, "{} pixels", xy.len());
        assert!((width_px - 9.0 * 40.0 / xy.len() as f64).abs() < 1e-9);
    }

    #[test]
    fn any_non_zero_pixel_is_cable() {
        // (OpenCV's thinning reads 255 as blob and 1 as background.)
        assert_eq!(thinned(&bar(1.0)), thinned(&bar(255.0)));
        assert_eq!(thinned(&bar(128.0)), thinned(&bar(255.0)));
    }

    /// Random blobs: thick lines and discs, as a mask's cables and scraps.
    fn random_mask(seed: u64) -> Mat {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut mask = Mat::new_rows_cols_with_default(60, 80, CV_8UC1, Scalar::all(0.0)).unwrap();
        for _ in 0..rng.random_range(1..6) {
            let from = Point::new(rng.random_range(-10..90), rng.random_range(-10..70));
            let to = Point::new(rng.random_range(-10..90), rng.random_range(-10..70));
            let width_px = rng.random_range(1..12);
            imgproc::line(
                &mut mask,
                from,
                to,
                Scalar::all(255.0),
                width_px,
                imgproc::LINE_8,
                0,
            )
            .unwrap();
            let radius_px = rng.random_range(1..8);
            imgproc::circle(
                &mut mask,
                to,
                radius_px,
                Scalar::all(255.0),
                -1,
                imgproc::LINE_8,
                0,
            )
            .unwrap();
        }
        mask
    }

    #[test]
    fn a_mask_of_three_channels_is_refused() {
        let mask =
            Mat::new_rows_cols_with_default(60, 80, opencv::core::CV_8UC3, Scalar::all(255.0))
                .unwrap();
        assert!(matches!(
            skeleton(&mask),
            Err(VisionError::OpenCv {
                stage: "read mask",
                ..
            })
        ));
    }

    #[test]
    fn the_thinning_is_opencvs_zhang_suen() {
        // OpenCV's needs the mask as 0/255 and padded by a background
        // pixel (it never thins the outermost rows and columns).
        for seed in 0..200 {
            let mask = random_mask(seed);
            let (mut grid, mut fg) = Grid::from_mask(&mask).unwrap();
            let on: Vec<usize> = (0..grid.on.len()).filter(|&i| grid.on[i] != 0).collect();
            assert_eq!(fg, on, "the pixels listed are those on, in order");
            grid.thin(&mut fg);
            let mut padded = Mat::default();
            opencv::core::copy_make_border(
                &mask,
                &mut padded,
                1,
                1,
                1,
                1,
                opencv::core::BORDER_CONSTANT,
                Scalar::all(0.0),
            )
            .unwrap();
            let mut theirs = Mat::default();
            opencv::ximgproc::thinning(&padded, &mut theirs, opencv::ximgproc::THINNING_ZHANGSUEN)
                .unwrap();
            let theirs: Vec<usize> = theirs
                .data_bytes()
                .unwrap()
                .iter()
                .enumerate()
                .filter(|(_, v)| **v != 0)
                .map(|(i, _)| i)
                .collect();
            assert_eq!(fg, theirs, "seed {seed}");
        }
    }

    #[test]
    fn corners_of_a_staircase_are_redundant_and_ends_and_runs_are_not() {
        // Bits clockwise from north: N 0, NE 1, E 2, SE 3, S 4, SW 5, W 6, NW 7.
        let ring = |ks: &[usize]| ks.iter().map(|k| 1 << k).sum::<usize>();
        assert!(REDUNDANT[ring(&[0, 2])], "a corner: N and E");
        assert!(!REDUNDANT[ring(&[0])], "an end");
        assert!(!REDUNDANT[ring(&[0, 4])], "a straight run: N and S");
        assert!(!REDUNDANT[ring(&[1, 5])], "a diagonal run: NE and SW");
        assert!(!REDUNDANT[ring(&[0, 3, 6])], "a junction of three branches");
    }

    #[test]
    fn an_empty_mask_has_no_skeleton() {
        let (xy, width_px) = thinned(&bar(0.0));
        assert!(xy.is_empty());
        assert_eq!(width_px, 0.0);
    }
}
