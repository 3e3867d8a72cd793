//! The cables' mask: the input normalised to 8-bit BGR, the classical
//! threshold on a plain background, and the network's mask made binary.
//!
//! The classical mask measures each pixel's colour distance (CIELAB, 8-bit
//! units) from the background's colour: on a plain background the image's
//! median colour, otherwise (a gradient, uneven light, a busy table) the
//! median colour of the pixel's neighbourhood, a window several cable
//! widths across. Cables are thin, so most pixels are table, near any
//! cable too. Otsu
//! on that distance splits cable from table, morphology cleans the edge and
//! blobs too small to be cable are dropped.

use std::borrow::Cow;
use std::sync::LazyLock;

use opencv::core::{self, Mat, Point, Scalar, Size};
use opencv::imgproc;
use opencv::prelude::*;

use super::background::{
    BackgroundStats, PLAIN_MIN_FRACTION, blurred_lab, plain_test_lab, share_near, shrunk,
};
use super::error::{VisionError, cv};
use super::runs;

/// Side of the square blur applied before measuring colour distance: it
/// averages sensor noise and fine texture out while keeping cables of a
/// few pixels' width. Its sigma, 0, asks OpenCV for its binomial kernel of
/// that side (1 4 6 4 1)/16, a Gaussian of σ 1 px.
const BLUR_KSIZE_PX: i32 = 5;
const BLUR_SIGMA_PX: f64 = 0.0;

/// Factor by which the image is shrunk to estimate the local background
/// colour: a median over a window several cable widths across needs only
/// a few thousand pixels.
const LOCAL_BACKGROUND_DOWNSCALE: i32 = 4;

/// Side, in pixels of the image shrunk by [`LOCAL_BACKGROUND_DOWNSCALE`],
/// of the window whose median colour is the local background: 15 (60 px
/// at full size) is several widths of the thickest cable, so the median
/// is the table's even beside a cable, and small against a gradient or a
/// light's falloff.
const LOCAL_BACKGROUND_KSIZE: i32 = 15;

/// The lowest colour distance the classical threshold may take, whatever
/// Otsu says: below it two shades of one plain table would be split.
const MIN_THRESHOLD_LAB: f64 = 12.0;

/// Above this [`BackgroundStats::ambiguous_ratio`], the classical mask is
/// not trusted even on a plain background, and `auto` runs the network
/// instead. A cable whose colour is close to the table's (or whose
/// highlight is) puts many pixels near the threshold, and the threshold
/// then cuts it into two strips along its flanks or leaves out pieces;
/// shadows and blur do the same. Where cable and table differ clearly,
/// few pixels fall between them.
pub const MAX_AMBIGUOUS_RATIO: f64 = 0.35;

/// Side of the closing that measures [`hollow_ratio`]: wide enough to
/// bridge the band of table-coloured shading that runs along a thick
/// glossy cable, narrow against the gaps between cables.
const HOLLOW_CLOSE_PX: i32 = 7;

/// Above this [`hollow_ratio`], the classical mask is not trusted even
/// on a plain background. A thick cable whose shading passes through the
/// table's colour is cut into two strips with a thin band of table
/// between them, which a closing fills; on rendered plain tables the
/// wedges of crossings add under 3.5 % (once 4.7 %), and hollow cables
/// about 10 %.
pub const MAX_HOLLOW_RATIO: f64 = 0.04;

/// Brings any supported image to 8-bit, 3-channel BGR, so the later stages
/// see one pixel format: gray and BGRA are converted, 16-bit scaled down;
/// an image already 8-bit BGR is borrowed, not copied.
pub fn to_bgr8(image: &Mat) -> Result<Cow<'_, Mat>, VisionError> {
    if image.empty() || image.rows() <= 0 || image.cols() <= 0 {
        return Err(VisionError::EmptyImage { path: None });
    }
    let channels = image.channels();
    let depth = image.depth();
    let eight_bit = match depth {
        core::CV_8U => Cow::Borrowed(image),
        core::CV_16U => {
            let mut out = Mat::default();
            image
                .convert_to(&mut out, core::CV_8U, 1.0 / 257.0, 0.0)
                .map_err(cv("scale 16-bit input"))?;
            Cow::Owned(out)
        }
        _ => return Err(VisionError::UnsupportedImage { channels, depth }),
    };
    let code = match channels {
        3 => return Ok(eight_bit),
        1 => imgproc::COLOR_GRAY2BGR,
        4 => imgproc::COLOR_BGRA2BGR,
        _ => return Err(VisionError::UnsupportedImage { channels, depth }),
    };
    let mut bgr = Mat::default();
    imgproc::cvt_color(&*eight_bit, &mut bgr, code, 0).map_err(cv("convert input to BGR"))?;
    Ok(Cow::Owned(bgr))
}

/// A matrix whose bytes are contiguous: `m` itself, or a copy of it when
/// it is a view into a larger one.
pub(crate) fn continuous(m: &Mat) -> Result<Cow<'_, Mat>, VisionError> {
    if m.is_continuous() {
        Ok(Cow::Borrowed(m))
    } else {
        let mut out = Mat::default();
        m.copy_to(&mut out).map_err(cv("copy matrix"))?;
        Ok(Cow::Owned(out))
    }
}

/// `round(sqrt(n))`, at most 255, for every `n` that is a squared distance
/// between two 8-bit Lab colours: the classical mask's distances, without a
/// square root per pixel.
fn rounded_roots() -> &'static [u8] {
    static TABLE: LazyLock<Vec<u8>> = LazyLock::new(|| {
        (0..=3 * 255 * 255)
            .map(|n: u32| f64::from(n).sqrt().round().min(255.0) as u8)
            .collect()
    });
    &TABLE
}

/// Whether the background is plain around each pixel: the plain test of
/// [`super::background::background_stats`], with each pixel's distance taken from the
/// background around it ([`local_background_lab`]) rather than from the
/// image's median. A light's falloff across a plain table, which fails
/// the global test, passes this one; prints and paint do not. The pixels
/// of `cables` (a mask of the image's size) and within `margin_px` of
/// them are left out: thick tubes and their shading cover a third of
/// some views of a plain cloth, and are not its background (scores in
/// docs/vision-record.md, "Straight cables on a plain table").
pub fn plain_locally(bgr: &Mat, cables: &Mat, margin_px: f64) -> Result<bool, VisionError> {
    let lab = plain_test_lab(bgr)?;
    let size = lab.size().map_err(cv("image size"))?;
    let local = local_background_lab(bgr, size)?;
    let side_px = 2 * margin_px.round().max(0.0) as i32 + 1;
    let grown = morphology(
        cables,
        imgproc::MORPH_DILATE,
        side_px,
        "grow the cables' mask",
    )?;
    let mut on_cable = Mat::default();
    imgproc::resize(
        &grown,
        &mut on_cable,
        size,
        0.0,
        0.0,
        imgproc::INTER_NEAREST,
    )
    .map_err(cv("shrink the cables' mask"))?;
    let on_cable = on_cable.data_bytes().map_err(cv("read the cables' mask"))?;
    let bytes = lab.data_bytes().map_err(cv("read Lab pixels"))?;
    let local_bytes = local.data_bytes().map_err(cv("read Lab pixels"))?;
    let near_fraction = share_near(
        bytes,
        |i| on_cable[i] == 0,
        |i| {
            [
                local_bytes[3 * i],
                local_bytes[3 * i + 1],
                local_bytes[3 * i + 2],
            ]
            .map(f64::from)
        },
    );
    Ok(near_fraction >= PLAIN_MIN_FRACTION)
}

/// The background's colour at every pixel, in an image of `size` (8-bit
/// CIELAB): the median of a window around it (see
/// [`LOCAL_BACKGROUND_KSIZE`]), on a shrunk copy and scaled back up.
fn local_background_lab(bgr: &Mat, size: Size) -> Result<Mat, VisionError> {
    let small = shrunk(bgr, LOCAL_BACKGROUND_DOWNSCALE)?;
    let lab = blurred_lab(&small, BLUR_KSIZE_PX, BLUR_SIGMA_PX)?;
    let mut median = Mat::default();
    imgproc::median_blur(&lab, &mut median, LOCAL_BACKGROUND_KSIZE)
        .map_err(cv("median of the local background"))?;
    let mut full = Mat::default();
    imgproc::resize(&median, &mut full, size, 0.0, 0.0, imgproc::INTER_LINEAR)
        .map_err(cv("upscale the local background"))?;
    Ok(full)
}

/// The classical mask (CV_8U, 0/255, the image's size): each pixel's colour
/// distance from the background around it (so that a light's falloff across
/// a plain table is not taken for cables), thresholded by Otsu. Returns
/// `background` (from [`super::background::background_stats`]) with the threshold used.
/// `min_blob_area_px`: connected blobs smaller than this are dropped as
/// noise.
pub fn classical_mask(
    bgr: &Mat,
    background: &BackgroundStats,
    min_blob_area_px: f64,
) -> Result<(Mat, BackgroundStats), VisionError> {
    let lab = blurred_lab(bgr, BLUR_KSIZE_PX, BLUR_SIGMA_PX)?;
    let bytes = lab.data_bytes().map_err(cv("read Lab pixels"))?;
    let local = local_background_lab(bgr, bgr.size().map_err(cv("image size"))?)?;
    let local_bytes = local.data_bytes().map_err(cv("read Lab pixels"))?;
    let rounded_root = rounded_roots();
    let distance: Vec<u8> = bytes
        .chunks_exact(3)
        .zip(local_bytes.chunks_exact(3))
        .map(|(px, bg)| {
            let squared: usize = (0..3)
                .map(|c| usize::from(px[c].abs_diff(bg[c])).pow(2))
                .sum();
            rounded_root[squared]
        })
        .collect();
    let distance_mat = Mat::new_rows_cols_with_data(bgr.rows(), bgr.cols(), &distance)
        .map_err(cv("wrap colour distance"))?;
    let mut scratch = Mat::default();
    let otsu = imgproc::threshold(
        &distance_mat,
        &mut scratch,
        0.0,
        255.0,
        imgproc::THRESH_BINARY | imgproc::THRESH_OTSU,
    )
    .map_err(cv("Otsu threshold"))?;
    let threshold_lab = otsu.max(MIN_THRESHOLD_LAB);
    let mut histogram = [0_usize; 256];
    for &d in &distance {
        histogram[usize::from(d)] += 1;
    }
    let (mut ambiguous, mut above) = (0_usize, 0_usize);
    for (d, &count) in histogram.iter().enumerate() {
        let d = d as f64;
        if d > threshold_lab {
            above += count;
        } else if d >= 0.5 * threshold_lab {
            ambiguous += count;
        }
    }
    let mut raw = Mat::default();
    imgproc::threshold(
        &distance_mat,
        &mut raw,
        threshold_lab,
        255.0,
        imgproc::THRESH_BINARY,
    )
    .map_err(cv("threshold colour distance"))?;
    let mask = clean_mask(&raw, min_blob_area_px)?;
    let stats = BackgroundStats {
        threshold_lab,
        ambiguous_ratio: ambiguous as f64 / above.max(1) as f64,
        ..background.clone()
    };
    Ok((mask, stats))
}

/// The area a closing of [`HOLLOW_CLOSE_PX`] adds to `mask` (CV_8U,
/// 0/255), over the mask's area: see [`MAX_HOLLOW_RATIO`].
pub fn hollow_ratio(mask: &Mat) -> Result<f64, VisionError> {
    let area_px = core::count_non_zero(mask).map_err(cv("mask area"))?;
    let closed = morphology(mask, imgproc::MORPH_CLOSE, HOLLOW_CLOSE_PX, "close mask")?;
    let closed_area_px = core::count_non_zero(&closed).map_err(cv("mask area"))?;
    Ok(f64::from(closed_area_px - area_px) / f64::from(area_px.max(1)))
}

/// Why the classical `mask`, with the `stats` it came with, is not to be
/// trusted, if it is not: its threshold was ambiguous, or it left cables
/// hollow. The second, dearer test runs only when the first passes.
pub fn classical_doubt(mask: &Mat, stats: &BackgroundStats) -> Result<Option<String>, VisionError> {
    if stats.ambiguous_ratio > MAX_AMBIGUOUS_RATIO {
        return Ok(Some(format!(
            "the classical threshold was ambiguous ({:.3} pixels near it per pixel above it, trusted up to {MAX_AMBIGUOUS_RATIO})",
            stats.ambiguous_ratio
        )));
    }
    let hollow = hollow_ratio(mask)?;
    Ok((hollow > MAX_HOLLOW_RATIO).then(|| {
        format!(
            "the classical mask left cables hollow (a {HOLLOW_CLOSE_PX} px closing adds {:.0}% to it, trusted up to {:.0}%)",
            100.0 * hollow,
            100.0 * MAX_HOLLOW_RATIO
        )
    }))
}

/// Opens away speckle, closes pinholes and drops blobs smaller than
/// `min_blob_area_px`.
pub fn clean_mask(raw: &Mat, min_blob_area_px: f64) -> Result<Mat, VisionError> {
    let opened = morphology(raw, imgproc::MORPH_OPEN, 3, "open mask")?;
    let closed = morphology(&opened, imgproc::MORPH_CLOSE, 3, "close mask")?;
    drop_small_blobs(&closed, min_blob_area_px)
}

/// `mask` opened or closed (`op`) with a disc `side_px` across; outside
/// the image counts as background.
fn morphology(mask: &Mat, op: i32, side_px: i32, what: &'static str) -> Result<Mat, VisionError> {
    let kernel = imgproc::get_structuring_element(
        imgproc::MORPH_ELLIPSE,
        Size::new(side_px, side_px),
        Point::new(-1, -1),
    )
    .map_err(cv("structuring element"))?;
    let border = imgproc::morphology_default_border_value().map_err(cv("morphology border"))?;
    let mut out = Mat::default();
    imgproc::morphology_ex(
        mask,
        &mut out,
        op,
        &kernel,
        Point::new(-1, -1),
        1,
        core::BORDER_CONSTANT,
        border,
    )
    .map_err(cv(what))?;
    Ok(out)
}

/// Keeps the 8-connected blobs of at least `min_area_px` pixels of a 0/255
/// mask (CV_8UC1).
fn drop_small_blobs(mask: &Mat, min_area_px: f64) -> Result<Mat, VisionError> {
    // A clone is continuous, whatever `mask` is.
    let mut out = mask.try_clone().map_err(cv("copy mask"))?;
    let cols = usize::try_from(out.cols()).unwrap_or(0);
    let bytes = out.data_typed_mut::<u8>().map_err(cv("mask pixels"))?;
    runs::clear_small_blobs(bytes, cols, min_area_px);
    Ok(out)
}

/// Makes the network's output a CV_8U 0/255 mask of `size`: 8-bit outputs
/// count as cable above 127 (or above 0 when their maximum is 1, i.e. a
/// 0/1 mask), 32-bit float outputs are probabilities cut at
/// `probability_cut`; an output of another size is resized first.
pub fn binarize_network_mask(
    raw: &Mat,
    size: Size,
    probability_cut: f64,
) -> Result<Mat, VisionError> {
    let bad = || VisionError::BadNetworkMask {
        channels: raw.channels(),
        depth: raw.depth(),
        cols: raw.cols(),
        rows: raw.rows(),
    };
    if raw.empty() || raw.channels() != 1 {
        return Err(bad());
    }
    let cut = match raw.depth() {
        core::CV_8U => {
            let mut max = 0.0;
            core::min_max_loc(raw, None, Some(&mut max), None, None, &core::no_array())
                .map_err(cv("network mask range"))?;
            if max <= 1.0 { 0.5 } else { 127.0 }
        }
        core::CV_32F => probability_cut,
        _ => return Err(bad()),
    };
    resize_and_cut(raw, size, cut)
}

/// `image` resized bilinearly to `size`, or itself when it is that size
/// already: a network's output brought to the image it was run on.
pub fn at_size(image: Mat, size: Size) -> Result<Mat, VisionError> {
    if image.size().map_err(cv("image size"))? == size {
        return Ok(image);
    }
    let mut resized = Mat::default();
    imgproc::resize(&image, &mut resized, size, 0.0, 0.0, imgproc::INTER_LINEAR)
        .map_err(cv("resize the network's output"))?;
    Ok(resized)
}

/// `mask` resized bilinearly to `size` (when it is not that size already)
/// and cut: a CV_8U mask, 255 above `cut` and 0 elsewhere. Bilinear
/// resizing then cutting at half keeps a mask's edges smooth.
pub fn resize_and_cut(mask: &Mat, size: Size, cut: f64) -> Result<Mat, VisionError> {
    let resized;
    let source = if mask.size().map_err(cv("mask size"))? == size {
        mask
    } else {
        let mut out = Mat::default();
        imgproc::resize(mask, &mut out, size, 0.0, 0.0, imgproc::INTER_LINEAR)
            .map_err(cv("resize mask"))?;
        resized = out;
        &resized
    };
    // Straight to 8 bits: a float mask thresholded in its own depth would
    // be a second image of the size, and a second pass to convert it.
    let mut binary = Mat::default();
    core::compare(source, &Scalar::all(cut), &mut binary, core::CMP_GT)
        .map_err(cv("binarize mask"))?;
    Ok(binary)
}

/// The mask's distance to its nearest background pixel, per pixel
/// (CV_32F): half the local width on a centre line.
pub fn half_widths(mask: &Mat) -> Result<Mat, VisionError> {
    let mut distance = Mat::default();
    imgproc::distance_transform(
        mask,
        &mut distance,
        imgproc::DIST_L2,
        imgproc::DIST_MASK_3,
        core::CV_32F,
    )
    .map_err(cv("measure the mask's widths"))?;
    Ok(distance)
}

/// The mask's half width at `p` (`half_widths`: its distance transform);
/// 0 outside it.
pub fn half_width_at(half_widths: &Mat, p: [f64; 2]) -> f64 {
    half_widths
        .at_2d::<f32>(p[1].round() as i32, p[0].round() as i32)
        .map_or(0.0, |h| f64::from(*h))
}

/// The mask's width (twice its half width, `half_widths`: its distance
/// transform) at each of `points_px` that lies on it.
pub fn widths_along(half_widths: &Mat, points_px: &[[f64; 2]]) -> Vec<f64> {
    points_px
        .iter()
        .filter_map(|&p| {
            let half = half_width_at(half_widths, p);
            (half > 0.0).then_some(2.0 * half)
        })
        .collect()
}

/// A CV_8U mask of `rows`×`cols` with every pixel 0.
pub fn zeros_u8(rows: i32, cols: i32) -> Result<Mat, VisionError> {
    Mat::new_rows_cols_with_default(rows, cols, core::CV_8U, Scalar::all(0.0))
        .map_err(cv("allocate mask"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::vision::background::background_stats;

    /// A 160 × 120 table of gray `bg` with a line of gray `fg` across its
    /// middle.
    fn plain_with_line(bg: f64, fg: f64, thickness_px: i32) -> Mat {
        let mut img =
            Mat::new_rows_cols_with_default(120, 160, core::CV_8UC3, Scalar::all(bg)).unwrap();
        draw_middle_line(&mut img, fg, thickness_px);
        img
    }

    fn draw_middle_line(img: &mut Mat, gray: f64, thickness_px: i32) {
        imgproc::line(
            img,
            Point::new(10, 60),
            Point::new(150, 60),
            Scalar::all(gray),
            thickness_px,
            imgproc::LINE_8,
            0,
        )
        .unwrap();
    }

    #[test]
    fn the_distance_table_rounds_square_roots_and_stops_at_255() {
        let table = rounded_roots();
        assert_eq!(table.len(), 3 * 255 * 255 + 1);
        // sqrt 2 = 1.41, sqrt 3 = 1.73, sqrt 64770 = 254.4995, sqrt 64771 = 254.5005
        assert_eq!([table[0], table[2], table[3]], [0, 1, 2]);
        assert_eq!([table[64770], table[64771]], [254, 255]);
        assert_eq!(table[3 * 255 * 255], 255);
    }

    #[test]
    fn only_blobs_below_the_area_are_dropped_even_inside_a_kept_blobs_reach() {
        let mut mask = zeros_u8(30, 30).unwrap();
        // A 5-pixel diagonal blob, and beside it a 36-pixel bar that enters
        // the diagonal's bounding box (rows 10–14, columns 10–14) at its
        // corner without touching it.
        for i in 0..5 {
            *mask.at_2d_mut::<u8>(10 + i, 10 + i).unwrap() = 255;
        }
        for row in 0..12 {
            for col in 14..17 {
                *mask.at_2d_mut::<u8>(row, col).unwrap() = 255;
            }
        }
        let kept = drop_small_blobs(&mask, 10.0).unwrap();
        assert_eq!(core::count_non_zero(&kept).unwrap(), 36);
        assert_eq!(*kept.at_2d::<u8>(12, 12).unwrap(), 0);
        assert_eq!(*kept.at_2d::<u8>(11, 14).unwrap(), 255);
        let all = drop_small_blobs(&mask, 5.0).unwrap();
        assert_eq!(core::count_non_zero(&all).unwrap(), 41);
    }

    #[test]
    fn a_dark_line_on_a_light_plain_table_is_found() {
        let img = plain_with_line(220.0, 30.0, 6);
        let (mask, stats) = classical_mask(&img, &background_stats(&img).unwrap(), 20.0).unwrap();
        assert!(stats.plain, "{stats:?}");
        let on = *mask.at_2d::<u8>(60, 80).unwrap();
        let off = *mask.at_2d::<u8>(20, 80).unwrap();
        assert_eq!((on, off), (255, 0));
    }

    #[test]
    fn a_cable_cut_into_two_strips_is_hollow_a_whole_one_is_not() {
        let whole = plain_with_line(220.0, 30.0, 12);
        let (mask, stats) =
            classical_mask(&whole, &background_stats(&whole).unwrap(), 20.0).unwrap();
        assert!(hollow_ratio(&mask).unwrap() < MAX_HOLLOW_RATIO);
        assert_eq!(classical_doubt(&mask, &stats).unwrap(), None);

        // The same cable with a band of the table's colour along its middle.
        let mut strips = whole.clone();
        draw_middle_line(&mut strips, 220.0, 2);
        let (mask, stats) =
            classical_mask(&strips, &background_stats(&strips).unwrap(), 20.0).unwrap();
        assert_eq!(*mask.at_2d::<u8>(60, 80).unwrap(), 0);
        assert!(hollow_ratio(&mask).unwrap() > MAX_HOLLOW_RATIO);
        assert!(classical_doubt(&mask, &stats).unwrap().is_some());
    }

    /// A `rows` × `cols` gray table lit from its middle: `gray(r2)` at a
    /// squared distance `r2` from the middle, in the image's widths and
    /// heights (0 in the middle, 0.5 in the corners).
    fn lit_table(rows: i32, cols: i32, gray: impl Fn(f64) -> f64) -> Mat {
        let mut img =
            Mat::new_rows_cols_with_default(rows, cols, core::CV_8UC3, Scalar::all(0.0)).unwrap();
        for y in 0..rows {
            for x in 0..cols {
                let r = (f64::from(x) / f64::from(cols) - 0.5)
                    .hypot(f64::from(y) / f64::from(rows) - 0.5);
                *img.at_2d_mut::<core::Vec3b>(y, x).unwrap() =
                    core::Vec3b::from([gray(r * r) as u8; 3]);
            }
        }
        img
    }

    #[test]
    fn a_lights_falloff_over_a_plain_table_is_not_taken_for_cables() {
        // A dark table lit from its middle: 100 there, 65 in the corners,
        // plain all the same; a dull blue cable across it, as far from
        // the table's colour as the corners are.
        let (rows, cols) = (240, 320);
        let mut img = lit_table(rows, cols, |r2| 100.0 - 35.0 * r2 / 0.5);
        imgproc::line(
            &mut img,
            Point::new(20, 120),
            Point::new(300, 120),
            Scalar::new(110.0, 70.0, 50.0, 0.0),
            6,
            imgproc::LINE_8,
            0,
        )
        .unwrap();
        let background = background_stats(&img).unwrap();
        assert!(background.plain, "{background:?}");
        let (mask, _) = classical_mask(&img, &background, 20.0).unwrap();
        assert_eq!(*mask.at_2d::<u8>(120, 160).unwrap(), 255);
        let mut off_line = mask.clone();
        imgproc::rectangle(
            &mut off_line,
            core::Rect::new(0, 105, cols, 30),
            Scalar::all(0.0),
            -1,
            imgproc::LINE_8,
            0,
        )
        .unwrap();
        assert_eq!(core::count_non_zero(&off_line).unwrap(), 0);
    }

    #[test]
    fn fine_stripes_are_no_plain_background() {
        // Bands 5 px wide in two colours 40 apart (Lab), at three angles:
        // the classical mask's blur keeps them, so the plain test must see
        // them too. (Shrunk to a quarter, as the test once was, every one
        // of them passed as plain.)
        let (rows, cols) = (240, 320);
        for angle_deg in [0.0f64, 30.0, 45.0] {
            let (sin, cos) = angle_deg.to_radians().sin_cos();
            let mut img =
                Mat::new_rows_cols_with_default(rows, cols, core::CV_8UC3, Scalar::all(0.0))
                    .unwrap();
            for y in 0..rows {
                for x in 0..cols {
                    let band = ((f64::from(x) * cos + f64::from(y) * sin) / 5.0).floor() as i64;
                    let bgr = if band.rem_euclid(2) == 0 {
                        [170, 150, 120]
                    } else {
                        [90, 110, 120]
                    };
                    *img.at_2d_mut::<core::Vec3b>(y, x).unwrap() = core::Vec3b::from(bgr);
                }
            }
            let stats = background_stats(&img).unwrap();
            assert!(!stats.plain, "{angle_deg}°: {stats:?}");
            assert!(
                !plain_locally(&img, &no_cables(&img), 0.0).unwrap(),
                "{angle_deg}°"
            );
        }
    }

    /// A 640 × 480 image of one colour, `bgr`.
    #[test]
    fn a_steep_falloff_is_plain_around_each_pixel_not_as_a_whole() {
        // A table of 200 in the middle and half that in the corners.
        let img = lit_table(240, 320, |r2| 200.0 * (1.0 - r2));
        let stats = background_stats(&img).unwrap();
        assert!(!stats.plain, "{stats:?}");
        assert!(plain_locally(&img, &no_cables(&img), 0.0).unwrap());
    }

    /// An empty cable mask the size of `img`.
    fn no_cables(img: &Mat) -> Mat {
        Mat::new_rows_cols_with_default(img.rows(), img.cols(), core::CV_8UC1, Scalar::all(0.0))
            .unwrap()
    }

    #[test]
    fn thick_tubes_over_a_plain_cloth_leave_it_plain_off_their_mask() {
        // Three upright tubes 24 px wide, shaded from white on their lit
        // side to gray, over a dark cloth: a fifth of the view.
        let mut img = lit_table(240, 320, |_| 30.0);
        let mut tubes = no_cables(&img);
        for x0 in [60, 150, 240] {
            for y in 0..240 {
                for dx in 0..24 {
                    let gray = 240.0 - 5.0 * f64::from(dx);
                    *img.at_2d_mut::<core::Vec3b>(y, x0 + dx).unwrap() =
                        core::Vec3b::from([gray as u8; 3]);
                    *tubes.at_2d_mut::<u8>(y, x0 + dx).unwrap() = 255;
                }
            }
        }
        assert!(!plain_locally(&img, &no_cables(&img), 0.0).unwrap());
        assert!(plain_locally(&img, &tubes, 24.0).unwrap());
    }

    #[test]
    fn gray_bgra_and_16_bit_inputs_become_bgr8() {
        for typ in [core::CV_8UC1, core::CV_8UC4, core::CV_16UC3, core::CV_16UC1] {
            let img = Mat::new_rows_cols_with_default(4, 5, typ, Scalar::all(100.0)).unwrap();
            let bgr = to_bgr8(&img).unwrap();
            assert_eq!(bgr.typ(), core::CV_8UC3, "type {typ}");
        }
        let bgr8 = Mat::new_rows_cols_with_default(4, 5, core::CV_8UC3, Scalar::all(9.0)).unwrap();
        assert!(matches!(to_bgr8(&bgr8).unwrap(), Cow::Borrowed(_)));
        let float =
            Mat::new_rows_cols_with_default(4, 5, core::CV_32FC3, Scalar::all(0.5)).unwrap();
        assert!(matches!(
            to_bgr8(&float),
            Err(VisionError::UnsupportedImage { .. })
        ));
        assert!(matches!(
            to_bgr8(&Mat::default()),
            Err(VisionError::EmptyImage { .. })
        ));
    }

    #[test]
    fn network_masks_of_any_scale_become_0_255() {
        let size = Size::new(8, 6);
        let ones = Mat::new_rows_cols_with_default(3, 4, core::CV_8UC1, Scalar::all(1.0)).unwrap();
        let m = binarize_network_mask(&ones, size, 0.5).unwrap();
        assert_eq!(m.size().unwrap(), size);
        assert_eq!(*m.at_2d::<u8>(2, 2).unwrap(), 255);
        let probs =
            Mat::new_rows_cols_with_default(6, 8, core::CV_32FC1, Scalar::all(0.3)).unwrap();
        let m = binarize_network_mask(&probs, size, 0.5).unwrap();
        assert_eq!(*m.at_2d::<u8>(2, 2).unwrap(), 0);
        let m = binarize_network_mask(&probs, size, 0.25).unwrap();
        assert_eq!(*m.at_2d::<u8>(2, 2).unwrap(), 255);
        let three = Mat::new_rows_cols_with_default(6, 8, core::CV_8UC3, Scalar::all(0.0)).unwrap();
        assert!(matches!(
            binarize_network_mask(&three, size, 0.5),
            Err(VisionError::BadNetworkMask { .. })
        ));
    }
}
