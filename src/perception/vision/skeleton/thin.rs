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
    let mut grid = Grid::from_mask(mask)?;
    let mut fg: Vec<usize> = (0..grid.on.len()).filter(|&i| grid.on[i] != 0).collect();
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
    /// Pads a CV_8U mask (non-zero = cable).
    fn from_mask(mask: &Mat) -> Result<Grid, VisionError> {
        let mask = continuous(mask)?;
        let bytes = mask.data_bytes().map_err(cv("read mask"))?;
        let rows = usize::try_from(mask.rows()).unwrap_or(0);
        let cols = usize::try_from(mask.cols()).unwrap_or(0);
        let stride = cols + 2;
        let mut on = vec![0u8; stride * (rows + 2)];
        for (y, row) in bytes.chunks_exact(cols.max(1)).take(rows).enumerate() {
            let base = (y + 1) * stride + 1;
            for (x, &v) in row.iter().enumerate() {
                on[base + x] = u8::from(v != 0);
            }
        }
        let s = stride as isize;
        Ok(Grid {
            stride,
            on,
            // N, NE, E, SE, S, SW, W, NW: clockwise from north.
            offsets: [-s, -s + 1, 1, s + 1, s, s - 1, -1, -s - 1],
        })
    }

    pub(super) fn xy(&self, i: usize) -> [f64; 2] {
        [
            (i % self.stride) as f64 - 1.0,
            (i / self.stride) as f64 - 1.0,
        ]
    }

    /// The 8 neighbours' states, clockwise from north.
    fn ring(&self, i: usize) -> [u8; 8] {
        let mut r = [0u8; 8];
        for (k, off) in self.offsets.iter().enumerate() {
            r[k] = self.on[i.wrapping_add_signed(*off)];
        }
        r
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
    /// skeleton.
    fn thin(&mut self, fg: &mut Vec<usize>) {
        let mut marked = Vec::new();
        loop {
            let mut changed = false;
            for pass in 0..2 {
                marked.clear();
                for &i in fg.iter() {
                    let p = self.ring(i);
                    let b: u8 = p.iter().sum();
                    if !(2..=6).contains(&b) {
                        continue;
                    }
                    let a = (0..8).filter(|&k| p[k] == 0 && p[(k + 1) % 8] == 1).count();
                    if a != 1 {
                        continue;
                    }
                    let (n, e, s, w) = (p[0], p[2], p[4], p[6]);
                    let keep = if pass == 0 {
                        n * e * s != 0 || e * s * w != 0
                    } else {
                        n * e * w != 0 || n * s * w != 0
                    };
                    if !keep {
                        marked.push(i);
                    }
                }
                for &i in &marked {
                    self.on[i] = 0;
                }
                changed |= !marked.is_empty();
                fg.retain(|&i| self.on[i] != 0);
            }
            if !changed {
                break;
            }
        }
    }

    /// Removes skeleton pixels whose removal keeps their neighbours
    /// connected (Yokoi's 8-connectivity number is 1) and that are not end
    /// points: Zhang–Suen leaves staircases and corner pixels that would
    /// otherwise read as junctions.
    fn remove_redundant(&mut self, fg: &mut Vec<usize>) {
        loop {
            let mut changed = false;
            for &i in fg.iter() {
                let p = self.ring(i);
                let count: u8 = p.iter().sum();
                if count < 2 {
                    continue;
                }
                // Yokoi's order: x1 = E, x2 = NE, x3 = N, x4 = NW, x5 = W,
                // x6 = SW, x7 = S, x8 = SE; complements.
                let x = [p[2], p[1], p[0], p[7], p[6], p[5], p[4], p[3]].map(|v| 1 - v);
                let n8: i32 = [0usize, 2, 4, 6]
                    .iter()
                    .map(|&k| i32::from(x[k]) - i32::from(x[k] * x[(k + 1) % 8] * x[(k + 2) % 8]))
                    .sum();
                if n8 == 1 {
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

#[cfg(test)]
mod tests {
    use super::*;
    use opencv::core::{CV_8UC1, Rect, Scalar};

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

    #[test]
    fn an_empty_mask_has_no_skeleton() {
        let (xy, width_px) = thinned(&bar(0.0));
        assert!(xy.is_empty());
        assert_eq!(width_px, 0.0);
    }
}
