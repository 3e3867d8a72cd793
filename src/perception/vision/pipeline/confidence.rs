//! How much a detection looks like a cable, from its mask, the image's
//! lightness inside it and, when the network made the mask, from how sure
//! the network was of it: a cable is long against its width and equally
//! wide along its length, as wide as the image's other cables, shaded as
//! a tube is, and the network marks it well above its threshold; a splash
//! of paint is short, a brushed stroke swells and thins, paint dries
//! flat, and the network is less sure of either. The task grasps the most
//! confident cable, and the pipeline drops detections below
//! [`VisionConfig::min_confidence`].

use opencv::core::{self, Mat, Size};
use opencv::prelude::*;

use super::config::MaskMethod;
#[cfg(doc)]
use super::config::VisionConfig;
use crate::perception::vision::background::BackgroundStats;
use crate::perception::vision::error::VisionError;
use crate::perception::vision::mask;
use crate::perception::vision::paths::median;

/// Lengths, in widths, from which a detection is long enough to be a
/// cable rather than a scrap or a splash.
const CABLE_LENGTH_WIDTHS: f64 = 10.0;
/// The relative spread of a cable's width along it (median absolute
/// deviation over the median) at which its confidence halves: a rendered
/// or photographed wire keeps its width within about a tenth.
const WIDTH_SPREAD_HALF: f64 = 0.3;
/// The factor off the image's typical width at which confidence halves.
const WIDTH_RATIO_HALF: f64 = 2.0;

/// The spread (standard deviation, gray levels) of the image's lightness
/// inside a detection from which it is as shaded as a cable: light falls
/// off across a tube and sheen runs along it, while a stroke of paint is
/// one flat colour. Below it confidence falls with the square of the
/// spread.
const SHADED_SPREAD_GRAY: f64 = 5.0;

/// The share of the image near the background's colour from which the
/// background holds too little paint for strokes to pass as cables: tubes
/// on dark cloth that cover more than the plain test allows (the network
/// is asked there) lie on such a background, beside one another in
/// several widths.
const STROKELESS_NEAR_FRACTION: f64 = 0.8;

/// Whether a mask made by `mask_used` on `background` may hold paint
/// strokes as long and even as cables, so that a detection's width is
/// weighed against the image's other cables': the network's mask, unless
/// the background is mostly of one colour.
pub(super) fn strokes_possible(mask_used: MaskMethod, background: &BackgroundStats) -> bool {
    mask_used == MaskMethod::Network && background.near_fraction < STROKELESS_NEAR_FRACTION
}

/// The network's probabilities of a mask (CV_32F, the mask's size) and
/// the threshold it was cut at.
pub(crate) struct Belief {
    probability: Mat,
    threshold: f64,
}

impl Belief {
    /// The belief behind a network's raw output cut at `threshold`, resized
    /// to `size`: `None` for an output that is already a mask (8-bit).
    pub(super) fn of(raw: Mat, size: Size, threshold: f64) -> Result<Option<Self>, VisionError> {
        if raw.depth() != core::CV_32F {
            return Ok(None);
        }
        Ok(Some(Belief {
            probability: mask::at_size(raw, size)?,
            threshold,
        }))
    }

    /// How far above its threshold the network's probability stands on
    /// average along `points_px`, as a share of the way to 1: near 1 along
    /// a cable, lower along paint it half took for one. Points off the
    /// probabilities count as 0.
    fn along(&self, points_px: &[[f64; 2]]) -> f64 {
        if points_px.is_empty() || self.threshold >= 1.0 {
            return 0.0;
        }
        let sum: f64 = points_px
            .iter()
            .map(|p| {
                let (x, y) = (p[0].round() as i32, p[1].round() as i32);
                self.probability
                    .at_2d::<f32>(y, x)
                    .map_or(0.0, |v| f64::from(*v))
            })
            .sum();
        let mean = sum / points_px.len() as f64;
        ((mean - self.threshold) / (1.0 - self.threshold)).clamp(0.0, 1.0)
    }
}

/// The distance to the mask's edge (px) beyond which a pixel is inside
/// a detection rather than on its rim, where cable and background blend:
/// past the pixels that touch the background, sideways or diagonally.
const RIM_PX: f64 = 1.5;

/// The spread (standard deviation, gray levels) of `gray`'s lightness
/// inside the mask across the path `points_px`: on lines across it at
/// every other point, out to the mask's half width there, over the
/// pixels further than [`RIM_PX`] from its edge (`half_widths`: the
/// mask's distance transform). `None` where fewer than two are left.
pub(super) fn lightness_spread(
    gray: &Mat,
    half_widths: &Mat,
    points_px: &[[f64; 2]],
) -> Option<f64> {
    // Read as slices: some thousand pixels a detection, where `at_2d`'s
    // checks would cost more than the reading.
    let (cols, rows) = (gray.cols(), gray.rows());
    if (half_widths.cols(), half_widths.rows()) != (cols, rows) {
        return None;
    }
    let lightness = gray.data_typed::<u8>().ok()?;
    let half_width = half_widths.data_typed::<f32>().ok()?;
    let index = |q: [f64; 2]| {
        let (x, y) = (q[0].round() as i32, q[1].round() as i32);
        (x >= 0 && y >= 0 && x < cols && y < rows).then(|| y as usize * cols as usize + x as usize)
    };
    let (mut count, mut sum, mut sum_sq) = (0.0, 0.0, 0.0);
    let last = points_px.len().checked_sub(1)?;
    for i in (0..=last).step_by(2) {
        let (before, after) = (points_px[i.saturating_sub(2)], points_px[(i + 2).min(last)]);
        let along = [after[0] - before[0], after[1] - before[1]];
        let norm = along[0].hypot(along[1]);
        let p = points_px[i];
        let Some(centre) = index(p).filter(|_| norm > 0.0) else {
            continue;
        };
        let across = [-along[1] / norm, along[0] / norm];
        let reach = half_width[centre].floor() as i32;
        for step in -reach..=reach {
            let q = [
                p[0] + f64::from(step) * across[0],
                p[1] + f64::from(step) * across[1],
            ];
            if let Some(at) = index(q).filter(|&at| f64::from(half_width[at]) > RIM_PX) {
                let v = f64::from(lightness[at]);
                (count, sum, sum_sq) = (count + 1.0, sum + v, sum_sq + v * v);
            }
        }
    }
    (count >= 2.0).then(|| (sum_sq / count - (sum / count).powi(2)).max(0.0).sqrt())
}

/// The confidence in [0, 1] that the path `points_px` (in `half_widths`'
/// pixels), `length_px` long, is a cable; with the network's `belief`,
/// times how sure it was along the path (see [`Belief::along`]).
/// `typical_width_px`, the image's cables' width, where the mask may hold
/// long even strokes of another width (see [`strokes_possible`]); `None`
/// where what stands out is cables, and tubes of several widths may lie
/// together. `lightness_spread`, where strokes are possible: see
/// [`lightness_spread`] and [`SHADED_SPREAD_GRAY`].
pub(super) fn confidence(
    half_widths: &Mat,
    belief: Option<&Belief>,
    points_px: &[[f64; 2]],
    length_px: f64,
    typical_width_px: Option<f64>,
    lightness_spread: Option<f64>,
) -> f64 {
    let mut widths = mask::widths_along(half_widths, points_px);
    // Not `<= 0.0`: a NaN width has no confidence either.
    let positive = |w: f64| w.partial_cmp(&0.0) == Some(std::cmp::Ordering::Greater);
    let Some(width) = median(&mut widths) else {
        return 0.0;
    };
    if typical_width_px.is_some_and(|w| !positive(w)) {
        return 0.0;
    }
    let mut deviations: Vec<f64> = widths.iter().map(|w| (w - width).abs()).collect();
    let spread = median(&mut deviations).unwrap_or(0.0) / width;
    let long = (length_px / (CABLE_LENGTH_WIDTHS * width)).min(1.0);
    let even = 0.5_f64.powf((spread / WIDTH_SPREAD_HALF).powi(2));
    let like_others = typical_width_px.map_or(1.0, |typical| {
        0.5_f64.powf((width / typical).log(WIDTH_RATIO_HALF).powi(2))
    });
    let believed = belief.map_or(1.0, |b| b.along(points_px));
    let shaded = lightness_spread.map_or(1.0, |s| (s / SHADED_SPREAD_GRAY).powi(2).min(1.0));
    long * even * like_others * believed * shaded
}

#[cfg(test)]
mod tests {
    use opencv::core::{CV_8UC1, Point, Scalar};
    use opencv::imgproc;

    use super::*;
    use crate::perception::vision::mask::half_widths;

    fn mask_with(draw: impl Fn(&mut Mat)) -> Mat {
        let mut mask =
            Mat::new_rows_cols_with_default(200, 300, CV_8UC1, Scalar::all(0.0)).unwrap();
        draw(&mut mask);
        mask
    }

    fn line(mask: &mut Mat, from: (i32, i32), to: (i32, i32), width: i32) {
        imgproc::line(
            mask,
            Point::new(from.0, from.1),
            Point::new(to.0, to.1),
            Scalar::all(255.0),
            width,
            imgproc::LINE_8,
            0,
        )
        .unwrap();
    }

    fn along(from: [f64; 2], to: [f64; 2]) -> Vec<[f64; 2]> {
        (0..=100)
            .map(|i| {
                let t = f64::from(i) / 100.0;
                [
                    from[0] + t * (to[0] - from[0]),
                    from[1] + t * (to[1] - from[1]),
                ]
            })
            .collect()
    }

    /// The confidence of a path along `mask`, shape alone, among cables
    /// 9 px wide.
    fn among_9_px(mask: &Mat, points_px: &[[f64; 2]], length_px: f64) -> f64 {
        confidence(
            &half_widths(mask).unwrap(),
            None,
            points_px,
            length_px,
            Some(9.0),
            None,
        )
    }

    #[test]
    fn a_long_even_cable_is_confident_and_a_splash_or_a_swelling_stroke_is_not() {
        let points = along([20.0, 100.0], [280.0, 100.0]);
        let cable = mask_with(|m| line(m, (20, 100), (280, 100), 9));
        let c = among_9_px(&cable, &points, 260.0);
        assert!(c > 0.9, "{c}");

        // A stroke swelling from 3 to 21 px and back.
        let stroke = mask_with(|m| {
            for x in (20..280).step_by(4) {
                let w = 3 + ((f64::from(x) / 20.0).sin().abs() * 18.0) as i32;
                line(m, (x, 100), (x + 4, 100), w);
            }
        });
        let s = among_9_px(&stroke, &points, 260.0);
        assert!(s < 0.6 * c, "{s} against {c}");

        // A splash: as wide as a cable, three widths long.
        let short = along([100.0, 100.0], [127.0, 100.0]);
        let splash = mask_with(|m| line(m, (100, 100), (127, 100), 9));
        let p = among_9_px(&splash, &short, 27.0);
        assert!(p < 0.4, "{p}");

        // Four times as wide as the image's other cables.
        let wide = mask_with(|m| line(m, (20, 100), (280, 100), 36));
        let w = among_9_px(&wide, &points, 260.0);
        assert!(w < 0.5 * c, "{w} against {c}");
        // Twice as wide: halved among the network's strokes, as much a
        // cable on a plain background's classical mask.
        let tube = half_widths(&mask_with(|m| line(m, (20, 100), (280, 100), 18))).unwrap();
        let among_strokes = confidence(&tube, None, &points, 260.0, Some(9.0), None);
        let on_plain = confidence(&tube, None, &points, 260.0, None, None);
        assert!(on_plain > 0.9, "{on_plain}");
        assert!(
            among_strokes < 0.6 * on_plain,
            "{among_strokes} against {on_plain}"
        );
    }

    #[test]
    fn widths_are_weighed_against_strokes_only_in_the_networks_mask_on_a_busy_background() {
        let background = |near_fraction: f64| BackgroundStats {
            background_lab: [20.0, 128.0, 128.0],
            near_fraction,
            edge_fraction: None,
            off_hue_fraction: None,
            plain: false,
            threshold_lab: 0.0,
            ambiguous_ratio: 0.0,
        };
        // A Pollock-like print: a third of it near its median colour.
        assert!(strokes_possible(MaskMethod::Network, &background(0.3)));
        // Thick tubes on black cloth, covering more than the plain test
        // allows: the cloth is still most of the image.
        assert!(!strokes_possible(MaskMethod::Network, &background(0.85)));
        assert!(!strokes_possible(MaskMethod::Classical, &background(0.3)));
    }

    #[test]
    fn paint_as_flat_as_a_stroke_is_less_confident_than_a_shaded_cable() {
        // Two detections on a gray image: an 11 px tube, lighter along its
        // middle than at its sides, and an 11 px stroke of one flat gray
        // with a little noise, whose mask spills a pixel onto the
        // background on each side.
        let (cable, stroke) = ((20, 60), (20, 140));
        let mask = mask_with(|m| {
            line(m, cable, (280, cable.1), 11);
            line(m, stroke, (280, stroke.1), 13);
        });
        let mut gray =
            Mat::new_rows_cols_with_default(200, 300, CV_8UC1, Scalar::all(90.0)).unwrap();
        for dy in -5_i32..=5 {
            let shade = 200.0 - 20.0 * f64::from(dy * dy) / 5.0;
            imgproc::line(
                &mut gray,
                Point::new(cable.0, cable.1 + dy),
                Point::new(280, cable.1 + dy),
                Scalar::all(shade),
                1,
                imgproc::LINE_8,
                0,
            )
            .unwrap();
        }
        let mut noise =
            Mat::new_rows_cols_with_default(200, 300, CV_8UC1, Scalar::all(0.0)).unwrap();
        core::randu(&mut noise, &Scalar::all(0.0), &Scalar::all(4.0)).unwrap();
        imgproc::line(
            &mut gray,
            Point::new(stroke.0, stroke.1),
            Point::new(280, stroke.1),
            Scalar::all(150.0),
            11,
            imgproc::LINE_8,
            0,
        )
        .unwrap();
        let mut noisy = Mat::default();
        core::add(&gray, &noise, &mut noisy, &core::no_array(), -1).unwrap();

        let spread = |at: (i32, i32)| {
            let points = along([f64::from(at.0), f64::from(at.1)], [280.0, f64::from(at.1)]);
            lightness_spread(&noisy, &half_widths(&mask).unwrap(), &points).unwrap()
        };
        let (shaded, flat) = (spread(cable), spread(stroke));
        assert!(shaded > SHADED_SPREAD_GRAY, "{shaded}");
        // The mask's rim, where the background shows, does not count.
        assert!(flat < 2.0, "{flat}");

        let widths = half_widths(&mask).unwrap();
        let points = along([20.0, 60.0], [280.0, 60.0]);
        let with = |spread| confidence(&widths, None, &points, 260.0, Some(11.0), spread);
        assert!((with(Some(shaded)) - with(None)).abs() < 1e-9);
        assert!(with(Some(flat)) < 0.15 * with(None), "{}", with(Some(flat)));
        // Halfway to shaded enough: a quarter as confident.
        let half = with(Some(0.5 * SHADED_SPREAD_GRAY));
        assert!((half - 0.25 * with(None)).abs() < 1e-9, "{half}");
        // A path whose mask is only its rim has no inside to measure.
        let thin = mask_with(|m| line(m, (20, 100), (280, 100), 1));
        let points = along([20.0, 100.0], [280.0, 100.0]);
        assert_eq!(
            lightness_spread(&noisy, &half_widths(&thin).unwrap(), &points),
            None
        );
    }

    #[test]
    fn a_path_off_the_mask_has_no_confidence() {
        let empty = mask_with(|_| {});
        let points = along([20.0, 100.0], [280.0, 100.0]);
        assert_eq!(among_9_px(&empty, &points, 260.0), 0.0);
        let cable = mask_with(|m| line(m, (20, 100), (280, 100), 9));
        assert_eq!(
            confidence(
                &half_widths(&cable).unwrap(),
                None,
                &points,
                260.0,
                Some(0.0),
                None
            ),
            0.0
        );
    }

    #[test]
    fn a_cable_the_network_was_unsure_of_is_less_confident() {
        let points = along([20.0, 100.0], [280.0, 100.0]);
        let cable = mask_with(|m| line(m, (20, 100), (280, 100), 9));
        let widths = half_widths(&cable).unwrap();
        let size = Size::new(300, 200);
        let sure = |p: f64| {
            let probability =
                Mat::new_rows_cols_with_default(200, 300, core::CV_32FC1, Scalar::all(p)).unwrap();
            Belief::of(probability, size, 0.5).unwrap().unwrap()
        };
        let shape_alone = confidence(&widths, None, &points, 260.0, Some(9.0), None);
        let certain = confidence(&widths, Some(&sure(1.0)), &points, 260.0, Some(9.0), None);
        assert!((certain - shape_alone).abs() < 1e-9);
        // At 0.8, three fifths of the way from the threshold to 1.
        let unsure = confidence(&widths, Some(&sure(0.8)), &points, 260.0, Some(9.0), None);
        assert!((unsure - 0.6 * shape_alone).abs() < 1e-6, "{unsure}");
        // A mask, not probabilities: no belief to weigh.
        assert!(Belief::of(cable.clone(), size, 0.5).unwrap().is_none());
        // Probabilities of another size are resized to the mask's.
        let small =
            Mat::new_rows_cols_with_default(50, 75, core::CV_32FC1, Scalar::all(0.8)).unwrap();
        let resized = Belief::of(small, size, 0.5).unwrap().unwrap();
        let at_size = confidence(&widths, Some(&resized), &points, 260.0, Some(9.0), None);
        assert!((at_size - unsure).abs() < 1e-6, "{at_size}");
    }
}
