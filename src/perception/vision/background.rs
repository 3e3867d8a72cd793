//! The background behind the cables: its colour, and whether it is
//! plain, busy (paint, prints, mosaics, a wood's grain), painted (busy
//! and of many colours) or dark. These tests, on the image shrunk and
//! blurred, choose the mask, the network and the scale it looks at, and
//! how the later stages judge scraps and straight detections.

use opencv::core::{self, Mat, Size};
use opencv::imgproc;
use opencv::prelude::*;

use super::error::{VisionError, cv};

/// Factor by which the image is shrunk, and the blur applied there, to
/// decide whether the background is plain, so that the test sees the
/// texture the classical mask will: shrinking by 2 blurs by about 0.6 px,
/// and σ 0.5 px at half size is 1 px at full size, together about the
/// mask's 1 px. Shrunk to a quarter and blurred 5 × 5 there (as it once
/// was), stripes, checkers and ripples of periods up to about 16 px
/// averaged out to one colour and passed as plain, and the classical mask
/// then took their bands for dozens of cables.
const PLAIN_TEST_DOWNSCALE: i32 = 2;
const PLAIN_TEST_BLUR_KSIZE_PX: i32 = 3;
const PLAIN_TEST_BLUR_SIGMA_PX: f64 = 0.5;

/// Colour distance (CIELAB, 8-bit units) within which a pixel counts as
/// "background coloured" in the plain-background test. A uniform table
/// under even light stays within ~10 of its median; wood grain, cloth
/// weave and prints spread well beyond.
pub const PLAIN_NEAR_LAB: f64 = 14.0;

/// Fraction of the (downscaled, blurred) image that must lie within
/// [`PLAIN_NEAR_LAB`] of the median colour for the background to count as
/// plain: cables rarely cover more than 10 % of a view. The cables-dev
/// photographs (wood, cloth, prints, paper with a table's edge in view)
/// score 0.52 to 0.84, and on the white-paper training ones that score
/// highest (00005, 00010, 00011) the network does better than the
/// classical mask: this keeps them 0.06 below plain. See
/// docs/vision-record.md, "Which background is plain".
pub const PLAIN_MIN_FRACTION: f64 = 0.90;

/// A background with less than this fraction of the (downscaled, blurred)
/// image within [`PLAIN_NEAR_LAB`] of its median colour is busy: paint,
/// prints, mosaics. It sits below what photographs of cables on wood,
/// cloth and paper score (docs/vision-record.md, "Busy scenes: the
/// paper's kind", gives the figures).
pub const BUSY_MAX_NEAR_FRACTION: f64 = 0.4;

/// A background that is not plain is busy too where at least this share
/// of the pixels lie on an edge ([`EDGE_THRESHOLDS`]): paint on a bare
/// canvas, whose broad stretches of one colour put it above
/// [`BUSY_MAX_NEAR_FRACTION`], is dense with edges; a table, a cloth or
/// paper with cables on it is not, nor a table under a light that falls
/// off (docs/vision-record.md, "Paint on a bare canvas is busy").
pub const BUSY_MIN_EDGE_FRACTION: f64 = 0.08;

/// A busy background is painted (paint, prints, mosaics of many colours)
/// where at least this share of its pixels differ from its median colour
/// in hue alone (a\*, b\*) by more than [`PLAIN_NEAR_LAB`]. A wooden
/// table's grain, busy by its lightness, is of one hue and stays under it,
/// as do the cables on it; paint and prints of several colours lie above
/// (docs/vision-record.md, "Painted, not only busy", gives the figures).
pub const PAINTED_MIN_OFF_HUE_FRACTION: f64 = 0.08;

/// Canny's two thresholds on the plain test's lightness (8-bit, L·255/100)
/// for [`BUSY_MIN_EDGE_FRACTION`]: OpenCV's common 1 : 3, at a step that
/// a stroke of paint or a cable's outline makes and a table's grain does
/// not.
const EDGE_THRESHOLDS: [f64; 2] = [50.0, 150.0];

/// The network looks closer at a background with less than this fraction
/// near its median colour: busy ones, and paint, print and mosaic scenes
/// with broad patches of one colour. It lies under what photographs of
/// cables on wood, cloth and paper score, where looking closer gains
/// nothing and costs time (docs/vision-record.md, "Closer on dark
/// backgrounds too").
pub const CLOSE_MAX_NEAR_FRACTION: f64 = 0.5;

/// A background whose median lightness (8-bit CIELAB, L·255/100) is under
/// this is dark: black cloth, a dark table (L* under 40), where the
/// network tells a tube from the cloth better when it looks closer.
pub const DARK_MAX_LIGHTNESS: f64 = 102.0;

/// What the classical mask learnt about the background.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BackgroundStats {
    /// The background's colour estimate: the image's per-channel median in
    /// 8-bit CIELAB (L·255/100, a+128, b+128).
    pub background_lab: [f64; 3],
    /// Fraction of pixels within [`PLAIN_NEAR_LAB`] of that colour.
    pub near_fraction: f64,
    /// Fraction of pixels on an edge (see [`BUSY_MIN_EDGE_FRACTION`]),
    /// measured only where it decides [`BackgroundStats::busy`]: neither
    /// plain nor busy by its share near the median colour.
    pub edge_fraction: Option<f64>,
    /// Fraction of pixels whose hue alone lies farther than
    /// [`PLAIN_NEAR_LAB`] from that colour's, measured only where the
    /// background is busy (see [`PAINTED_MIN_OFF_HUE_FRACTION`]).
    pub off_hue_fraction: Option<f64>,
    /// Whether the background counts as plain (`near_fraction >=
    /// PLAIN_MIN_FRACTION`).
    pub plain: bool,
    /// The colour distance the mask was thresholded at (0 when only the
    /// background was estimated).
    pub threshold_lab: f64,
    /// Pixels whose colour distance lies from half the threshold up to it,
    /// per pixel above it (0 when only the background was estimated): see
    /// [`super::mask::MAX_AMBIGUOUS_RATIO`].
    pub ambiguous_ratio: f64,
}

impl BackgroundStats {
    /// Whether the background is busy: paint, prints, mosaics, or a
    /// wooden table's grain of one hue (see [`BUSY_MAX_NEAR_FRACTION`],
    /// [`BUSY_MIN_EDGE_FRACTION`] and [`BackgroundStats::painted`]).
    pub fn busy(&self) -> bool {
        self.near_fraction < BUSY_MAX_NEAR_FRACTION
            || self
                .edge_fraction
                .is_some_and(|edges| edges >= BUSY_MIN_EDGE_FRACTION)
    }

    /// Whether the background is busy and of many colours: paint, prints,
    /// mosaics, which a network for busy scenes sees
    /// ([`PAINTED_MIN_OFF_HUE_FRACTION`]); not a table's grain.
    pub fn painted(&self) -> bool {
        self.busy()
            && self
                .off_hue_fraction
                .is_some_and(|off_hue| off_hue >= PAINTED_MIN_OFF_HUE_FRACTION)
    }

    /// Whether the network should look closer at the image: its
    /// background is busy, far from one colour
    /// ([`CLOSE_MAX_NEAR_FRACTION`]) or dark ([`DARK_MAX_LIGHTNESS`]).
    pub fn closer_look(&self) -> bool {
        self.busy()
            || self.near_fraction < CLOSE_MAX_NEAR_FRACTION
            || self.background_lab[0] < DARK_MAX_LIGHTNESS
    }
}

/// 8-bit CIELAB of a BGR image after a Gaussian blur (`ksize_px` square,
/// `sigma_px`).
pub(super) fn blurred_lab(bgr: &Mat, ksize_px: i32, sigma_px: f64) -> Result<Mat, VisionError> {
    let mut blurred = Mat::default();
    imgproc::gaussian_blur(
        bgr,
        &mut blurred,
        Size::new(ksize_px, ksize_px),
        sigma_px,
        sigma_px,
        core::BORDER_REPLICATE,
    )
    .map_err(cv("blur"))?;
    let mut lab = Mat::default();
    imgproc::cvt_color(&blurred, &mut lab, imgproc::COLOR_BGR2Lab, 0)
        .map_err(cv("convert to Lab"))?;
    Ok(lab)
}

/// `bgr` shrunk by `factor` (area averaging), at least 1 × 1.
pub(super) fn shrunk(bgr: &Mat, factor: i32) -> Result<Mat, VisionError> {
    let size = Size::new((bgr.cols() / factor).max(1), (bgr.rows() / factor).max(1));
    let mut small = Mat::default();
    imgproc::resize(bgr, &mut small, size, 0.0, 0.0, imgproc::INTER_AREA)
        .map_err(cv("shrink the image"))?;
    Ok(small)
}

/// Per-channel medians of interleaved 3-channel bytes.
fn median3(bytes: &[u8]) -> [f64; 3] {
    let mut hist = [[0usize; 256]; 3];
    for px in bytes.chunks_exact(3) {
        for c in 0..3 {
            hist[c][usize::from(px[c])] += 1;
        }
    }
    let n = bytes.len() / 3;
    let mut out = [0.0; 3];
    for c in 0..3 {
        let mut seen = 0;
        for (v, count) in hist[c].iter().enumerate() {
            seen += count;
            if 2 * seen >= n {
                out[c] = v as f64;
                break;
            }
        }
    }
    out
}

fn lab_distance(px: &[u8], bg: [f64; 3]) -> f64 {
    let d0 = f64::from(px[0]) - bg[0];
    let d1 = f64::from(px[1]) - bg[1];
    let d2 = f64::from(px[2]) - bg[2];
    (d0 * d0 + d1 * d1 + d2 * d2).sqrt()
}

/// The image as the plain-background tests see it: shrunk and blurred
/// (see [`PLAIN_TEST_DOWNSCALE`]), in 8-bit CIELAB.
pub(super) fn plain_test_lab(bgr: &Mat) -> Result<Mat, VisionError> {
    let small = shrunk(bgr, PLAIN_TEST_DOWNSCALE)?;
    blurred_lab(&small, PLAIN_TEST_BLUR_KSIZE_PX, PLAIN_TEST_BLUR_SIGMA_PX)
}

/// Estimates the background colour and decides whether it is plain, on a
/// downscaled copy of the image (see [`PLAIN_TEST_DOWNSCALE`]).
pub fn background_stats(bgr: &Mat) -> Result<BackgroundStats, VisionError> {
    let lab = plain_test_lab(bgr)?;
    let bytes = lab.data_bytes().map_err(cv("read Lab pixels"))?;
    let background_lab = median3(bytes);
    let near_fraction = share_near(bytes, |_| true, |_| background_lab);
    let mut stats = BackgroundStats {
        background_lab,
        near_fraction,
        edge_fraction: None,
        off_hue_fraction: None,
        plain: near_fraction >= PLAIN_MIN_FRACTION,
        threshold_lab: 0.0,
        ambiguous_ratio: 0.0,
    };
    if !stats.plain && !stats.busy() {
        stats.edge_fraction = Some(edge_fraction(&lab)?);
    }
    if stats.busy() {
        stats.off_hue_fraction = Some(off_hue_fraction(bytes, background_lab));
    }
    Ok(stats)
}

/// The share of the Lab pixels in `bytes` whose hue (a\*, b\*) lies
/// farther than [`PLAIN_NEAR_LAB`] from `background_lab`'s.
fn off_hue_fraction(bytes: &[u8], background_lab: [f64; 3]) -> f64 {
    let off_hue = bytes
        .chunks_exact(3)
        .filter(|px| {
            let da = f64::from(px[1]) - background_lab[1];
            let db = f64::from(px[2]) - background_lab[2];
            da * da + db * db > PLAIN_NEAR_LAB * PLAIN_NEAR_LAB
        })
        .count();
    off_hue as f64 / (bytes.len() / 3).max(1) as f64
}

/// The share of `lab`'s pixels on an edge of its lightness (OpenCV's
/// Canny at [`EDGE_THRESHOLDS`]).
fn edge_fraction(lab: &Mat) -> Result<f64, VisionError> {
    let mut lightness = Mat::default();
    core::extract_channel(lab, &mut lightness, 0).map_err(cv("the lightness channel"))?;
    let mut edges = Mat::default();
    let [low, high] = EDGE_THRESHOLDS;
    imgproc::canny(&lightness, &mut edges, low, high, 3, false).map_err(cv("edges"))?;
    let on_edge = core::count_non_zero(&edges).map_err(cv("count edge pixels"))?;
    Ok(f64::from(on_edge) / (f64::from(edges.rows()) * f64::from(edges.cols())).max(1.0))
}

/// The share of the Lab pixels in `bytes` that are `counted` (pixel `i`
/// when `counted(i)`) within [`PLAIN_NEAR_LAB`] of their background,
/// `background(i)`; 0 for no pixels.
pub(super) fn share_near(
    bytes: &[u8],
    counted: impl Fn(usize) -> bool,
    background: impl Fn(usize) -> [f64; 3],
) -> f64 {
    let (mut n, mut near) = (0_usize, 0_usize);
    for (i, px) in bytes
        .chunks_exact(3)
        .enumerate()
        .filter(|(i, _)| counted(*i))
    {
        n += 1;
        if lab_distance(px, background(i)) <= PLAIN_NEAR_LAB {
            near += 1;
        }
    }
    if n == 0 { 0.0 } else { near as f64 / n as f64 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use opencv::core::{Point, Scalar};

    fn flat_640x480(bgr: [f64; 3]) -> Mat {
        let [b, g, r] = bgr;
        Mat::new_rows_cols_with_default(480, 640, core::CV_8UC3, Scalar::new(b, g, r, 0.0)).unwrap()
    }

    /// A 640 × 480 pale canvas with `strokes` short strokes of paint 2–4 px
    /// wide in five colours, spread over it in a fixed pattern.
    fn paint_on_canvas(strokes: i32) -> Mat {
        let mut img = flat_640x480([225.0, 228.0, 232.0]);
        let colours = [
            [40.0, 40.0, 40.0],
            [30.0, 60.0, 200.0],
            [200.0, 120.0, 40.0],
            [60.0, 170.0, 90.0],
            [120.0, 120.0, 130.0],
        ];
        for i in 0..strokes {
            let from = Point::new((i * 97) % 640, (i * 61) % 480);
            let angle_rad = f64::from(i) * 2.399;
            let length_px = f64::from(30 + (i * 7) % 40);
            let to = Point::new(
                from.x + (length_px * angle_rad.cos()) as i32,
                from.y + (length_px * angle_rad.sin()) as i32,
            );
            let [b, g, r] = colours[i as usize % colours.len()];
            imgproc::line(
                &mut img,
                from,
                to,
                Scalar::new(b, g, r, 0.0),
                2 + i % 3,
                imgproc::LINE_8,
                0,
            )
            .unwrap();
        }
        img
    }

    #[test]
    fn paint_on_a_bare_canvas_is_busy_and_a_sheet_on_a_table_not() {
        // Broad bare stretches keep the canvas over half near its colour,
        // so the share near it alone would take it for neither busy nor
        // worth a closer look; its edges make it both.
        let paint = background_stats(&paint_on_canvas(400)).unwrap();
        assert!(
            (CLOSE_MAX_NEAR_FRACTION..PLAIN_MIN_FRACTION).contains(&paint.near_fraction),
            "{paint:?}"
        );
        assert!(
            paint.edge_fraction.unwrap() >= BUSY_MIN_EDGE_FRACTION,
            "{paint:?}"
        );
        assert!(paint.busy() && paint.closer_look(), "{paint:?}");
        // A sheet of paper over the left 40 % of a wooden-brown table.
        let mut table = flat_640x480([80.0, 120.0, 170.0]);
        imgproc::rectangle(
            &mut table,
            core::Rect::new(0, 0, 256, 480),
            Scalar::all(235.0),
            imgproc::FILLED,
            imgproc::LINE_8,
            0,
        )
        .unwrap();
        imgproc::line(
            &mut table,
            Point::new(10, 60),
            Point::new(150, 60),
            Scalar::all(30.0),
            8,
            imgproc::LINE_8,
            0,
        )
        .unwrap();
        let sheet = background_stats(&table).unwrap();
        assert!(
            (CLOSE_MAX_NEAR_FRACTION..PLAIN_MIN_FRACTION).contains(&sheet.near_fraction),
            "{sheet:?}"
        );
        assert!(
            sheet.edge_fraction.unwrap() < BUSY_MIN_EDGE_FRACTION,
            "{sheet:?}"
        );
        assert!(!sheet.busy() && !sheet.closer_look(), "{sheet:?}");
        // Where the share near its colour decides, the edges are not counted.
        let bare = background_stats(&paint_on_canvas(0)).unwrap();
        assert!(bare.plain && bare.edge_fraction.is_none(), "{bare:?}");
        let dense = background_stats(&paint_on_canvas(3000)).unwrap();
        assert!(dense.busy() && dense.edge_fraction.is_none(), "{dense:?}");
    }

    #[test]
    fn paint_of_many_colours_is_painted_and_a_wooden_grain_only_busy() {
        for strokes in [400, 3000] {
            let paint = background_stats(&paint_on_canvas(strokes)).unwrap();
            assert!(paint.painted(), "{strokes} strokes: {paint:?}");
        }
        let bare = background_stats(&paint_on_canvas(0)).unwrap();
        assert!(!bare.painted(), "{bare:?}");
        // A brown table whose grain waves its lightness by a third either
        // way, in bands 12 px apart: busy, and of one hue.
        let mut wood = flat_640x480([0.0; 3]);
        for y in 0..480 {
            for x in 0..640 {
                let along = f64::from(y) + 8.0 * (f64::from(x) / 40.0).sin();
                let shade = 1.0 + 0.35 * (std::f64::consts::TAU * along / 12.0).sin();
                let bgr = [60.0, 110.0, 170.0].map(|c: f64| (c * shade).round() as u8);
                *wood.at_2d_mut::<core::Vec3b>(y, x).unwrap() = core::Vec3b::from(bgr);
            }
        }
        let grain = background_stats(&wood).unwrap();
        assert!(grain.busy() && !grain.painted(), "{grain:?}");
    }
}
