//! Thinning the mask to a one-pixel, 8-connected skeleton, on a grid
//! padded by one pixel so that neighbour look-ups never leave it.

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
