//! The image shrunk to the network's input size by area averaging: each
//! output pixel the mean of the source pixels it covers, weighted by how
//! much of each it covers.
//!
//! OpenCV's `resize` with `INTER_AREA` does this, and its result is the one
//! the network was trained on. At a whole-number factor on both axes
//! (0.5: 640 × 480 to 320 × 240) it is quick. At any other (0.375: 640 ×
//! 480 to 240 × 176, the default) OpenCV 4.6 takes a general path that
//! took a tenth of the whole pipeline's time. This computes the same
//! bytes as that path, the same single-precision sums in the same order,
//! in about half its time (docs/vision-record.md, "The network's input
//! shrunk faster"); a test holds it to OpenCV's bytes.

use opencv::core::{Mat, Size, ToInputArray};
use opencv::imgproc;
use opencv::prelude::*;

/// `bgr` (CV_8UC3) shrunk by area averaging to `size`, its bytes (B, G, R
/// by row) left in `out`: OpenCV's `INTER_AREA` where it is quick or where
/// `size` is not smaller, this module's own otherwise.
pub(super) fn shrink_by_area(
    bgr: &(impl MatTraitConst + ToInputArray),
    size: Size,
    out: &mut Vec<u8>,
) -> opencv::Result<()> {
    let factor = |from: i32, to: i32| 1.0 / (f64::from(to) / f64::from(from));
    let (factor_x, factor_y) = (
        factor(bgr.cols(), size.width),
        factor(bgr.rows(), size.height),
    );
    let whole = |f: f64| (f - f.round()).abs() < f64::EPSILON;
    out.clear();
    if factor_x < 1.0 || factor_y < 1.0 || (whole(factor_x) && whole(factor_y)) {
        let mut small = Mat::default();
        imgproc::resize(bgr, &mut small, size, 0.0, 0.0, imgproc::INTER_AREA)?;
        out.extend_from_slice(small.data_bytes()?);
        return Ok(());
    }
    let owned;
    let bytes = if bgr.is_continuous() {
        bgr.data_bytes()?
    } else {
        owned = bgr.try_clone()?;
        owned.data_bytes()?
    };
    let (cols, rows) = (bgr.cols() as usize, bgr.rows() as usize);
    let (width, height) = (size.width as usize, size.height as usize);
    let across = Shares::new(cols, width, factor_x);
    let down = Shares::new(rows, height, factor_y);
    let row_len = 3 * width;
    // A source row as floats, padded so that every output pixel reads as
    // many source pixels and one float more (its shares, four at a time).
    let mut source_row = vec![0f32; 3 * (cols + across.taps) + 1];
    // That row averaged across, kept for the next output row, whose first
    // source row is often the last one's.
    let mut across_row = vec![0f32; row_len];
    let mut across_of = usize::MAX;
    let mut sum = vec![0f32; row_len];
    out.resize(row_len * height, 0);
    for (y, out_row) in out.chunks_exact_mut(row_len).enumerate() {
        // 0 plus the first share is that share exactly, as OpenCV sets it.
        sum.fill(0.0);
        for (k, &weight_y) in down.weights(y).iter().enumerate() {
            let source_y = down.first[y] + k;
            if weight_y == 0.0 {
                // Padding: no share of a row past this output pixel's.
                continue;
            }
            if across_of != source_y {
                let row = &bytes[3 * cols * source_y..3 * cols * (source_y + 1)];
                for (f, &b) in source_row.iter_mut().zip(row) {
                    *f = f32::from(b);
                }
                average_across(&source_row, &across, &mut across_row);
                across_of = source_y;
            }
            for (s, &a) in sum.iter_mut().zip(&across_row) {
                *s += weight_y * a;
            }
        }
        for (o, &s) in out_row.iter_mut().zip(&sum) {
            *o = nearest_byte(s);
        }
    }
    Ok(())
}

/// `v` (0 to a little over 255) to the nearest byte, ties to even, as
/// OpenCV's `saturate_cast` rounds. Adding and taking away 2²³ rounds a
/// float under 2²³ so, without the call to `rintf` that
/// `round_ties_even` makes on a CPU without SSE 4.1.
fn nearest_byte(v: f32) -> u8 {
    const TWO_TO_23: f32 = 8_388_608.0;
    ((v.max(0.0) + TWO_TO_23) - TWO_TO_23).min(255.0) as u8
}

/// One row of B, G, R floats averaged across into `out` (3 per output
/// pixel), each output pixel's shares summed from its first source pixel.
/// The fourth lane of each sum carries the next pixel's blue, unused: it
/// lets each share be one four-wide multiply and add. A padding share of 0
/// adds 0 and leaves the sum as it was.
fn average_across(row: &[f32], across: &Shares, out: &mut [f32]) {
    match across.taps {
        1 => average_across_by::<1>(row, across, out),
        2 => average_across_by::<2>(row, across, out),
        3 => average_across_by::<3>(row, across, out),
        4 => average_across_by::<4>(row, across, out),
        _ => average_across_by::<0>(row, across, out),
    }
}

/// [`average_across`] with `TAPS` shares per output pixel known when
/// compiled (0: as many as `across` has), so that the loop over them
/// unrolls.
fn average_across_by<const TAPS: usize>(row: &[f32], across: &Shares, out: &mut [f32]) {
    let taps = if TAPS == 0 { across.taps } else { TAPS };
    for ((pixel, &first), weights) in out
        .chunks_exact_mut(3)
        .zip(&across.first)
        .zip(across.all_weights.chunks_exact(across.taps))
    {
        let mut acc = [0f32; 4];
        let source = &row[3 * first..3 * (first + taps) + 1];
        for k in 0..taps {
            let weight = weights[k];
            for c in 0..4 {
                acc[c] += source[3 * k + c] * weight;
            }
        }
        pixel.copy_from_slice(&acc[..3]);
    }
}

/// Along one axis, the source pixels each output pixel covers, and by how
/// much: output pixel `i` covers source pixels `first[i]..` with the
/// weights `weights(i)`, which sum to 1, padded with zeros to `taps` each.
/// The weights are single precision, computed in double from where the
/// output pixel's cell begins and ends, as OpenCV's are, with its
/// tolerance of a thousandth of a pixel.
struct Shares {
    first: Vec<usize>,
    taps: usize,
    all_weights: Vec<f32>,
}

impl Shares {
    fn new(source_len: usize, len: usize, factor: f64) -> Self {
        let last = source_len as i64 - 1;
        let mut first = Vec::with_capacity(len);
        let mut weights: Vec<Vec<f32>> = Vec::with_capacity(len);
        for i in 0..len {
            let from = i as f64 * factor;
            let to = from + factor;
            let cell = factor.min(source_len as f64 - from);
            let end = (to.floor() as i64).min(last);
            let start = (from.ceil() as i64).min(end);
            let mut own = Vec::new();
            let mut begin = start;
            if start as f64 - from > 1e-3 {
                begin = start - 1;
                own.push(((start as f64 - from) / cell) as f32);
            }
            for _ in start..end {
                own.push((1.0 / cell) as f32);
            }
            if to - end as f64 > 1e-3 {
                let part = (to - end as f64).min(1.0).min(cell);
                own.push((part / cell) as f32);
            }
            first.push(begin as usize);
            weights.push(own);
        }
        let taps = weights.iter().map(Vec::len).max().unwrap_or(0);
        let all_weights = weights
            .into_iter()
            .flat_map(|mut own| {
                own.resize(taps, 0.0);
                own
            })
            .collect();
        Shares {
            first,
            taps,
            all_weights,
        }
    }

    fn weights(&self, i: usize) -> &[f32] {
        &self.all_weights[i * self.taps..(i + 1) * self.taps]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use opencv::core::{CV_8UC3, Rect, Scalar};
    use rand::{RngExt, SeedableRng};

    /// A `cols` × `rows` BGR image of noise over smooth gradients, so that
    /// averages fall on and near halves.
    fn image(cols: i32, rows: i32, seed: u64) -> Mat {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut img =
            Mat::new_rows_cols_with_default(rows, cols, CV_8UC3, Scalar::all(0.0)).unwrap();
        let bytes = img.data_bytes_mut().unwrap();
        for (i, b) in bytes.iter_mut().enumerate() {
            *b = if rng.random_bool(0.5) {
                rng.random()
            } else {
                ((i / 3) % 256) as u8
            };
        }
        img
    }

    fn opencv_area(bgr: &Mat, size: Size) -> Vec<u8> {
        let mut small = Mat::default();
        imgproc::resize(bgr, &mut small, size, 0.0, 0.0, imgproc::INTER_AREA).unwrap();
        small.data_bytes().unwrap().to_vec()
    }

    #[test]
    fn the_bytes_are_opencvs_at_every_network_size() {
        // The network's sizes (multiples of 16) for 640 × 480 at scales
        // from 0.25 to 0.875, then odd sizes and factors.
        let cases = [
            (640, 480, 160, 128),
            (640, 480, 240, 176),
            (640, 480, 320, 240),
            (640, 480, 400, 304),
            (640, 480, 480, 368),
            (640, 480, 560, 416),
            (1280, 720, 480, 272),
            (101, 77, 33, 50),
            (97, 61, 96, 20),
            (5, 5, 3, 2),
            (7, 3, 1, 1),
            // One source pixel to each output pixel on one axis.
            (16, 50, 16, 16),
            (50, 16, 16, 16),
        ];
        for (seed, (cols, rows, width, height)) in cases.into_iter().enumerate() {
            let img = image(cols, rows, seed as u64);
            let size = Size::new(width, height);
            let mut ours = Vec::new();
            shrink_by_area(&img, size, &mut ours).unwrap();
            let theirs = opencv_area(&img, size);
            let differ = ours.iter().zip(&theirs).filter(|(a, b)| a != b).count();
            assert_eq!(
                ours.len(),
                theirs.len(),
                "{cols}x{rows} to {width}x{height}"
            );
            assert_eq!(
                differ, 0,
                "{cols}x{rows} to {width}x{height}: {differ} bytes differ"
            );
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]
        /// Any size to any other, smaller or larger on either axis: the
        /// sizes above are chosen, these are not.
        #[test]
        fn the_bytes_are_opencvs_at_any_size(
            cols in 1..=200i32,
            rows in 1..=200i32,
            width_share in 0.0..2.0f64,
            height_share in 0.0..2.0f64,
            seed: u64,
        ) {
            let size = Size::new(
                ((f64::from(cols) * width_share) as i32).max(1),
                ((f64::from(rows) * height_share) as i32).max(1),
            );
            let img = image(cols, rows, seed);
            let mut ours = Vec::new();
            shrink_by_area(&img, size, &mut ours).unwrap();
            proptest::prop_assert!(ours == opencv_area(&img, size), "{cols}x{rows} to {size:?}");
        }
    }

    #[test]
    fn a_view_into_a_larger_image_shrinks_as_its_copy() {
        let whole = image(700, 500, 7);
        let view = Mat::roi(&whole, Rect::new(30, 10, 640, 480)).unwrap();
        assert!(!view.is_continuous());
        let size = Size::new(240, 176);
        let (mut from_view, mut from_copy) = (Vec::new(), Vec::new());
        shrink_by_area(&view, size, &mut from_view).unwrap();
        shrink_by_area(&view.try_clone().unwrap(), size, &mut from_copy).unwrap();
        assert_eq!(from_view, from_copy);
        assert_eq!(from_view, opencv_area(&view.try_clone().unwrap(), size));
    }
}
