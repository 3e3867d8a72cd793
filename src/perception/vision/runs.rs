//! A mask's runs, each row's stretches of set pixels, and the 8-connected
//! blobs they make, each run joined to the runs it touches in the row
//! above by union–find.
//!
//! A cable mask is mostly empty: its runs are found skipping eight empty
//! bytes at a time, and its blobs from its few thousand runs in a fraction
//! of the time OpenCV's `connectedComponentsWithStats` takes to label every
//! pixel (docs/vision-record.md, "The mask's runs"). A test holds the
//! blobs to OpenCV's.

/// A row's stretch of set pixels: `start..end` of row `row`.
pub(super) struct Run {
    pub row: usize,
    pub start: usize,
    pub end: usize,
}

/// Clears, in `bytes` (a mask of `cols` bytes a row, set where not 0),
/// every 8-connected blob of fewer than `min_area_px` set pixels.
pub(super) fn clear_small_blobs(bytes: &mut [u8], cols: usize, min_area_px: f64) {
    let (runs, row_first) = runs(bytes, cols);
    let mut blob: Vec<usize> = (0..runs.len()).collect();
    for row in 1..row_first.len() - 1 {
        let above = row_first[row - 1]..row_first[row];
        let mut touching = above.start;
        for here in row_first[row]..row_first[row + 1] {
            // Runs above that end before this one's column to the left
            // cannot touch it nor any later run of this row.
            while touching < above.end && runs[touching].end < runs[here].start {
                touching += 1;
            }
            let mut k = touching;
            while k < above.end && runs[k].start <= runs[here].end {
                join(&mut blob, k, here);
                k += 1;
            }
        }
    }
    let mut area = vec![0usize; runs.len()];
    for (i, run) in runs.iter().enumerate() {
        area[root(&mut blob, i)] += run.end - run.start;
    }
    for (i, run) in runs.iter().enumerate() {
        if (area[root(&mut blob, i)] as f64) < min_area_px {
            bytes[run.row * cols + run.start..run.row * cols + run.end].fill(0);
        }
    }
}

/// The runs of a mask of `cols` bytes a row (set where not 0), row by row
/// and left to right, and where each row's runs begin in them (one entry
/// more than rows: the end; a lone 0 where `cols` is 0).
pub(super) fn runs(bytes: &[u8], cols: usize) -> (Vec<Run>, Vec<usize>) {
    let mut runs = Vec::new();
    let mut row_first = vec![0];
    if cols == 0 {
        return (runs, row_first);
    }
    for (row, pixels) in bytes.chunks_exact(cols).enumerate() {
        let mut x = 0;
        while x < cols {
            // Most of a cable mask is empty: skip it eight bytes at a time.
            while let Some(eight) = pixels.get(x..x + 8)
                && let Ok(word) = <[u8; 8]>::try_from(eight)
                && u64::from_ne_bytes(word) == 0
            {
                x += 8;
            }
            while x < cols && pixels[x] == 0 {
                x += 1;
            }
            let start = x;
            while x < cols && pixels[x] != 0 {
                x += 1;
            }
            if start < x {
                runs.push(Run { row, start, end: x });
            }
        }
        row_first.push(runs.len());
    }
    (runs, row_first)
}

/// The blob of run `i`: its root, halving the path on the way.
fn root(blob: &mut [usize], mut i: usize) -> usize {
    while blob[i] != i {
        blob[i] = blob[blob[i]];
        i = blob[i];
    }
    i
}

/// Makes runs `a` and `b` one blob.
fn join(blob: &mut [usize], a: usize, b: usize) {
    let (a, b) = (root(blob, a), root(blob, b));
    blob[a.max(b)] = a.min(b);
}

#[cfg(test)]
mod tests {
    use super::*;
    use opencv::core::{self, CV_8UC1, Mat, Scalar};
    use opencv::imgproc;
    use opencv::prelude::*;
    use rand::{RngExt, SeedableRng};

    /// The mask with OpenCV's 8-connected components of fewer than
    /// `min_area_px` pixels cleared.
    fn opencv_cleared(mask: &Mat, min_area_px: f64) -> Vec<u8> {
        let (mut labels, mut stats, mut centroids) =
            (Mat::default(), Mat::default(), Mat::default());
        imgproc::connected_components_with_stats(
            mask,
            &mut labels,
            &mut stats,
            &mut centroids,
            8,
            core::CV_32S,
        )
        .unwrap();
        let labels = labels.data_typed::<i32>().unwrap();
        mask.data_bytes()
            .unwrap()
            .iter()
            .zip(labels)
            .map(|(&b, &label)| {
                let area = *stats.at_2d::<i32>(label, imgproc::CC_STAT_AREA).unwrap();
                if label > 0 && f64::from(area) < min_area_px {
                    0
                } else {
                    b
                }
            })
            .collect()
    }

    /// A mask of speckles at `density` (single pixels, diagonal pairs,
    /// clumps) and a few thick lines, set to any value but 0.
    fn mask(cols: i32, rows: i32, density: f64, seed: u64) -> Mat {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut mask =
            Mat::new_rows_cols_with_default(rows, cols, CV_8UC1, Scalar::all(0.0)).unwrap();
        for b in mask.data_bytes_mut().unwrap() {
            if rng.random_bool(density) {
                *b = rng.random_range(1..=255);
            }
        }
        for _ in 0..3 {
            let mut end = || core::Point::new(rng.random_range(0..cols), rng.random_range(0..rows));
            let (from, to) = (end(), end());
            imgproc::line(
                &mut mask,
                from,
                to,
                Scalar::all(255.0),
                3,
                imgproc::LINE_8,
                0,
            )
            .unwrap();
        }
        mask
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]
        #[test]
        fn the_blobs_cleared_are_opencvs(
            cols in 1..=120i32,
            rows in 1..=90i32,
            density in 0.0..0.6f64,
            min_area_px in 0.0..40.0f64,
            seed: u64,
        ) {
            let mask = mask(cols, rows, density, seed);
            let mut ours = mask.data_bytes().unwrap().to_vec();
            clear_small_blobs(&mut ours, cols as usize, min_area_px);
            proptest::prop_assert!(ours == opencv_cleared(&mask, min_area_px));
        }
    }

    #[test]
    fn blobs_that_touch_at_a_corner_are_one() {
        // 2-pixel runs meeting corner to corner, the row above to the left
        // and then to the right: 6 pixels, one blob.
        #[rustfmt::skip]
        let mut bytes = vec![
            1, 1, 0, 0,
            0, 0, 1, 1,
            1, 1, 0, 0,
        ];
        clear_small_blobs(&mut bytes, 4, 6.0);
        assert_eq!(bytes, [1, 1, 0, 0, 0, 0, 1, 1, 1, 1, 0, 0]);
        clear_small_blobs(&mut bytes, 4, 7.0);
        assert_eq!(bytes, [0; 12]);
        // One column apart, they are two blobs of 2.
        #[rustfmt::skip]
        let mut apart = vec![
            1, 1, 0, 0, 0,
            0, 0, 0, 1, 1,
        ];
        clear_small_blobs(&mut apart, 5, 3.0);
        assert_eq!(apart, [0; 10]);
    }
}
