//! Real cables over rendered backgrounds: a labelled photograph's cables,
//! cut out along their masks and laid over a rendered scene that has no
//! cables of its own, their labels carried along. No photograph of the
//! paper's scene is at hand; its cables over rendered paint stand in for
//! one, with cables that no renderer drew.

use opencv::core::{self, Mat, Scalar, Size};
use opencv::imgproc;
use opencv::prelude::*;
use rand::{Rng, RngExt};

use super::random::MIN_IN_VIEW_DIAGONALS;
use super::tube::{SHADOW_SOFTNESS_RADII, shadow_shift_px};
use super::{Light, RenderError, RenderedScene, cv, stretches_in_image, unite};
use crate::perception::vision::eval::distance_to_polylines;
use crate::perception::vision::paths::polyline_length;

/// The largest scale a photograph is laid over a background at: cables-dev's
/// wires are 4–8 px wide at 640 px, the paper's cables up to twice that.
const MAX_SCALE: f64 = 2.0;

/// A labelled photograph: its image and, per cable, its mask and centre
/// line, as a data set in the cables-dev layout holds them.
pub struct LabelledPhotograph<'a> {
    /// CV_8UC3, BGR.
    pub bgr: &'a Mat,
    /// CV_8UC1 0/255, the image's size, one per cable.
    pub masks: &'a [Mat],
    /// In the image's pixels, one per cable.
    pub centerlines_px: &'a [Vec<[f64; 2]>],
}

/// How a photograph is laid over a background: stretched to the
/// background's size, mirrored, then enlarged about a point. Mirroring and
/// enlarging keep the view filled, and a cable that left the photograph's
/// view still leaves the new one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub mirror_x: bool,
    pub mirror_y: bool,
    /// At least 1.
    pub scale: f64,
    /// The point that stays in place, in the background's pixels.
    pub centre_px: [f64; 2],
}

impl Placement {
    /// A placement drawn from `rng` over a `width_px` × `height_px`
    /// background: either mirroring, a scale from 1 to [`MAX_SCALE`], a
    /// centre anywhere in view.
    pub fn random(rng: &mut impl Rng, width_px: i32, height_px: i32) -> Self {
        Placement {
            mirror_x: rng.random_bool(0.5),
            mirror_y: rng.random_bool(0.5),
            scale: rng.random_range(1.0..=MAX_SCALE),
            centre_px: [
                rng.random_range(0.0..=f64::from(width_px - 1)),
                rng.random_range(0.0..=f64::from(height_px - 1)),
            ],
        }
    }

    /// The affine map from a `from` photograph's pixels to a `to`
    /// background's, as OpenCV's 2 × 3 matrix rows.
    fn matrix(&self, from: Size, to: Size) -> [[f64; 3]; 2] {
        let axis = |mirror: bool, from: i32, to: i32, centre: f64| {
            // Pixel centres 0..from-1 onto 0..to-1, mirrored, then scaled
            // about `centre`: x ↦ a·x + b.
            let stretch = f64::from(to - 1) / f64::from((from - 1).max(1));
            let (a, b) = if mirror {
                (-stretch, f64::from(to - 1))
            } else {
                (stretch, 0.0)
            };
            (self.scale * a, self.scale * b + (1.0 - self.scale) * centre)
        };
        let (ax, bx) = axis(self.mirror_x, from.width, to.width, self.centre_px[0]);
        let (ay, by) = axis(self.mirror_y, from.height, to.height, self.centre_px[1]);
        [[ax, 0.0, bx], [0.0, ay, by]]
    }
}

/// `background` with `photo`'s cables laid over it by `placement`: each
/// cable's pixels, the edge of their union softened by a pixel, and the
/// labels moved with them. A cable that leaves the enlarged view and comes
/// back shows the camera one cable a stretch in view, so each stretch is
/// labelled as one. A stretch with less in view than a rendered cable may
/// have is not laid over it. With `shadow_light`, the cables cast their
/// shadows on the background under that light ([`cast_shadows`]).
pub fn paste_cables(
    background: &Mat,
    photo: &LabelledPhotograph,
    placement: &Placement,
    shadow_light: Option<&Light>,
) -> Result<RenderedScene, RenderError> {
    let to = background
        .size()
        .map_err(cv("read the background's size"))?;
    let from = photo.bgr.size().map_err(cv("read the photograph's size"))?;
    let m = placement.matrix(from, to);
    let matrix = Mat::from_slice_2d(&m).map_err(cv("build the placement"))?;
    let warp = |image: &Mat, interpolation: i32| -> Result<Mat, RenderError> {
        let mut out = Mat::default();
        imgproc::warp_affine(
            image,
            &mut out,
            &matrix,
            to,
            interpolation,
            core::BORDER_CONSTANT,
            Scalar::all(0.0),
        )
        .map_err(cv("place the photograph"))?;
        Ok(out)
    };
    let mut masks = Vec::new();
    let mut centerlines_px = Vec::new();
    for (mask, line) in photo.masks.iter().zip(photo.centerlines_px) {
        let mut placed = Mat::default();
        imgproc::threshold(
            &warp(mask, imgproc::INTER_LINEAR)?,
            &mut placed,
            127.0,
            255.0,
            imgproc::THRESH_BINARY,
        )
        .map_err(cv("binarize a placed mask"))?;
        let moved: Vec<[f64; 2]> = line
            .iter()
            .map(|p| [m[0][0] * p[0] + m[0][2], m[1][1] * p[1] + m[1][2]])
            .collect();
        let stretches = stretches_in_image(&moved, to.width, to.height);
        let diagonal_px = f64::from(to.width).hypot(f64::from(to.height));
        let parts = split_by_nearest(placed, &stretches)?;
        for piece in joined_where_touching(stretches, parts)? {
            let in_view = core::count_non_zero(&piece.mask).map_err(cv("count a placed mask"))?;
            let length_px = polyline_length(&piece.centerline_px);
            if in_view > 0 && length_px >= MIN_IN_VIEW_DIAGONALS * diagonal_px {
                masks.push(piece.mask);
                centerlines_px.push(piece.centerline_px);
            }
        }
    }
    let union_mask = unite(&masks, to.width, to.height)?;
    let shadowed = shadow_light
        .map(|light| cast_shadows(background, &masks, light))
        .transpose()?;
    let background = shadowed.as_ref().unwrap_or(background);
    let bgr = blend(
        background,
        &warp(photo.bgr, imgproc::INTER_LINEAR)?,
        &union_mask,
    )?;
    Ok(RenderedScene {
        bgr,
        visible_centerlines_px: centerlines_px.iter().map(|l| vec![l.clone()]).collect(),
        centerlines_px,
        visible_masks: masks.clone(),
        masks,
        union_mask,
    })
}

/// `mask` (CV_8UC1 0/255) parted among `lines`: one mask a line, each of
/// its pixels in the mask of the line nearest to it.
fn split_by_nearest(mask: Mat, lines: &[Vec<[f64; 2]>]) -> Result<Vec<Mat>, RenderError> {
    match lines.len() {
        0 => return Ok(Vec::new()),
        1 => return Ok(vec![mask]),
        _ => {}
    }
    let mut pixels = core::Vector::<core::Point>::new();
    core::find_non_zero(&mask, &mut pixels).map_err(cv("find a placed mask's pixels"))?;
    let mut parts = Vec::with_capacity(lines.len());
    for _ in lines {
        parts.push(
            Mat::new_rows_cols_with_default(mask.rows(), mask.cols(), core::CV_8UC1, 0.into())
                .map_err(cv("allocate a mask"))?,
        );
    }
    for pixel in pixels {
        let at = [f64::from(pixel.x), f64::from(pixel.y)];
        let nearest = (0..lines.len())
            .map(|k| (k, distance_to_polylines(at, &lines[k..=k])))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |(k, _)| k);
        *parts[nearest]
            .at_2d_mut::<u8>(pixel.y, pixel.x)
            .map_err(cv("part a placed mask"))? = 255;
    }
    Ok(parts)
}

/// What the camera sees of a cable in one piece.
struct InView {
    centerline_px: Vec<[f64; 2]>,
    /// CV_8UC1 0/255.
    mask: Mat,
}

/// Consecutive stretches of one cable, each with its part of the mask,
/// joined where their parts touch: a cable that grazes the border leaves
/// the view for less than its width, and the camera sees it whole.
fn joined_where_touching(
    stretches: Vec<Vec<[f64; 2]>>,
    parts: Vec<Mat>,
) -> Result<Vec<InView>, RenderError> {
    let mut joined: Vec<InView> = Vec::new();
    for (stretch, part) in stretches.into_iter().zip(parts) {
        match joined.last_mut() {
            Some(piece) if touch(&piece.mask, &part)? => {
                piece.centerline_px.extend(stretch);
                let mut both = Mat::default();
                core::bitwise_or(&piece.mask, &part, &mut both, &core::no_array())
                    .map_err(cv("join two stretches' masks"))?;
                piece.mask = both;
            }
            _ => joined.push(InView {
                centerline_px: stretch,
                mask: part,
            }),
        }
    }
    Ok(joined)
}

/// Whether masks `a` and `b` share a pixel or touch at an edge or corner.
fn touch(a: &Mat, b: &Mat) -> Result<bool, RenderError> {
    let mut grown = Mat::default();
    imgproc::dilate_def(a, &mut grown, &Mat::default()).map_err(cv("grow a mask"))?;
    let mut shared = Mat::default();
    core::bitwise_and(&grown, b, &mut shared, &core::no_array())
        .map_err(cv("overlap two masks"))?;
    Ok(core::count_non_zero(&shared).map_err(cv("count shared pixels"))? > 0)
}

/// `background` (CV_8UC3) darkened where the cables of `masks` (CV_8UC1
/// 0/255) cast their shadows under `light`: each shifted away from the
/// light and softened as a rendered tube's is ([`super::tube`]), by its
/// radius as its mask gives it. A photograph's cut-out leaves its own
/// shadows behind on the photograph's table; without these, pasted
/// cables would be the only ones a network sees that cast none.
fn cast_shadows(background: &Mat, masks: &[Mat], light: &Light) -> Result<Mat, RenderError> {
    let size = background
        .size()
        .map_err(cv("read the background's size"))?;
    let Some(shift_per_radius) = shadow_shift_px(light, 1.0) else {
        return Ok(background.clone());
    };
    let mut darkest = Mat::zeros_size(size, core::CV_32F)
        .and_then(|m| m.to_mat())
        .map_err(cv("allocate the shadows"))?;
    for mask in masks {
        let in_mask = core::count_non_zero(mask).map_err(cv("count a cable's pixels"))?;
        if in_mask == 0 {
            continue;
        }
        // Across a band w pixels wide, a pixel's distance to the nearest
        // pixel outside it averages w/4 + 1/2.
        let inside = distance_to_zero(mask)?;
        let mean_px =
            core::sum_elems(&inside).map_err(cv("sum a cable's widths"))?[0] / f64::from(in_mask);
        let radius_px = 2.0 * (mean_px - 0.5);
        let [sx, sy] = shift_per_radius.map(|s| s * radius_px);
        // Each pixel's distance to the cable, read where its shadow is cast from.
        let mut outside_mask = Mat::default();
        core::bitwise_not(mask, &mut outside_mask, &core::no_array())
            .map_err(cv("invert a cable's mask"))?;
        let outside = distance_to_zero(&outside_mask)?;
        let shift = Mat::from_slice_2d(&[[1.0, 0.0, -sx], [0.0, 1.0, -sy]])
            .map_err(cv("build a shadow's shift"))?;
        let mut from_caster = Mat::default();
        imgproc::warp_affine(
            &outside,
            &mut from_caster,
            &shift,
            size,
            imgproc::INTER_LINEAR,
            core::BORDER_REPLICATE,
            Scalar::all(0.0),
        )
        .map_err(cv("shift a shadow"))?;
        // 1 under the cable (and above, clamped below), falling to 0 over
        // its softness beyond its edge, half a pixel short of the pixel
        // centres the distance runs to (and below 0 further out, where the
        // running maximum drops it).
        let softness_px = SHADOW_SOFTNESS_RADII * radius_px;
        let mut shade = Mat::default();
        from_caster
            .convert_to(
                &mut shade,
                core::CV_32F,
                -1.0 / softness_px,
                1.0 + 0.5 / softness_px,
            )
            .map_err(cv("soften a shadow"))?;
        let mut darker = Mat::default();
        core::max(&darkest, &shade, &mut darker).map_err(cv("add a shadow"))?;
        darkest = darker;
    }
    // What is left of the light: 1 − shadow × shade, shade at most 1.
    let mut clamped = Mat::default();
    imgproc::threshold(&darkest, &mut clamped, 1.0, 1.0, imgproc::THRESH_TRUNC)
        .map_err(cv("clamp the shadows"))?;
    let mut light_left = Mat::default();
    clamped
        .convert_to(&mut light_left, core::CV_32F, -light.shadow, 1.0)
        .map_err(cv("darken by the shadows"))?;
    let mut darkened = Mat::default();
    core::multiply(
        &converted(background, core::CV_32FC3)?,
        &as_colour(&light_left)?,
        &mut darkened,
        1.0,
        -1,
    )
    .map_err(cv("darken the background"))?;
    converted(&darkened, core::CV_8UC3)
}

/// `front` where `mask` is set and `back` elsewhere, the mask's edge
/// blurred so that the cut shows no seam a network could learn.
fn blend(back: &Mat, front: &Mat, mask: &Mat) -> Result<Mat, RenderError> {
    let mut alpha = Mat::default();
    mask.convert_to(&mut alpha, core::CV_32F, 1.0 / 255.0, 0.0)
        .map_err(cv("convert the paste's mask"))?;
    let mut soft = Mat::default();
    imgproc::gaussian_blur_def(&alpha, &mut soft, Size::new(3, 3), 0.0)
        .map_err(cv("soften the paste's edge"))?;
    let alpha3 = as_colour(&soft)?;
    let (back, front) = (
        converted(back, core::CV_32FC3)?,
        converted(front, core::CV_32FC3)?,
    );
    // back + alpha · (front − back)
    let mut difference = Mat::default();
    core::subtract(&front, &back, &mut difference, &core::no_array(), -1)
        .map_err(cv("blend the paste"))?;
    let mut weighted = Mat::default();
    core::multiply(&difference, &alpha3, &mut weighted, 1.0, -1).map_err(cv("blend the paste"))?;
    let mut blended = Mat::default();
    core::add(&back, &weighted, &mut blended, &core::no_array(), -1)
        .map_err(cv("blend the paste"))?;
    converted(&blended, core::CV_8UC3)
}

/// A BGR image converted to `typ`: CV_32FC3 to compute with, CV_8UC3
/// (rounded) to write.
fn converted(image: &Mat, typ: i32) -> Result<Mat, RenderError> {
    let mut out = Mat::default();
    image
        .convert_to(&mut out, typ, 1.0, 0.0)
        .map_err(cv("convert an image"))?;
    Ok(out)
}

/// Each pixel's distance (CV_32F) to the nearest zero pixel of `mask`.
fn distance_to_zero(mask: &Mat) -> Result<Mat, RenderError> {
    let mut distance = Mat::default();
    imgproc::distance_transform_def(mask, &mut distance, imgproc::DIST_L2, imgproc::DIST_MASK_3)
        .map_err(cv("measure distances in a mask"))?;
    Ok(distance)
}

/// A one-channel float factor (CV_32F) as three, to weigh a BGR image by.
fn as_colour(factor: &Mat) -> Result<Mat, RenderError> {
    let mut out = Mat::default();
    imgproc::cvt_color_def(factor, &mut out, imgproc::COLOR_GRAY2BGR)
        .map_err(cv("spread a factor over the colours"))?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use opencv::core::{CV_8UC1, CV_8UC3, Point, Vec3b};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    fn filled(rows: i32, cols: i32, typ: i32, value: f64) -> Mat {
        Mat::new_rows_cols_with_default(rows, cols, typ, Scalar::all(value)).unwrap()
    }

    /// A 64 × 48 photograph of one white cable, 5 px wide, from the left
    /// border to (40, 24), on black.
    fn photograph() -> (Mat, Vec<Mat>, Vec<Vec<[f64; 2]>>) {
        let mut bgr = filled(48, 64, CV_8UC3, 0.0);
        let mut mask = filled(48, 64, CV_8UC1, 0.0);
        for (image, colour) in [(&mut bgr, 255.0), (&mut mask, 255.0)] {
            imgproc::line(
                image,
                Point::new(0, 24),
                Point::new(40, 24),
                Scalar::all(colour),
                5,
                imgproc::LINE_8,
                0,
            )
            .unwrap();
        }
        (bgr, vec![mask], vec![vec![[0.0, 24.0], [40.0, 24.0]]])
    }

    /// The photograph `bgr` with its cables' `masks` and `lines` laid by
    /// `placement` over a grey background of its size.
    fn over_grey(
        bgr: &Mat,
        masks: &[Mat],
        lines: &[Vec<[f64; 2]>],
        placement: &Placement,
    ) -> RenderedScene {
        over_grey_lit(bgr, masks, lines, placement, None)
    }

    /// As [`over_grey`], the cables casting their shadows under
    /// `shadow_light` where given.
    fn over_grey_lit(
        bgr: &Mat,
        masks: &[Mat],
        lines: &[Vec<[f64; 2]>],
        placement: &Placement,
        shadow_light: Option<&Light>,
    ) -> RenderedScene {
        let photo = LabelledPhotograph {
            bgr,
            masks,
            centerlines_px: lines,
        };
        let background = filled(bgr.rows(), bgr.cols(), CV_8UC3, 100.0);
        paste_cables(&background, &photo, placement, shadow_light).unwrap()
    }

    /// The photograph laid over the background as it is.
    const AS_IS: Placement = Placement {
        mirror_x: false,
        mirror_y: false,
        scale: 1.0,
        centre_px: [0.0, 0.0],
    };

    #[test]
    fn a_pasted_cable_casts_its_shadow_away_from_the_light() {
        let (bgr, masks, lines) = photograph();
        let placement = AS_IS;
        // Light from the top of the image, halving what the cable shades.
        let light = Light {
            toward_light: [0.0, -0.6, 0.8],
            shadow: 0.5,
            ..Light::default()
        };
        let scene = over_grey_lit(&bgr, &masks, &lines, &placement, Some(&light));
        let gray = |x: i32, y: i32| scene.bgr.at_2d::<Vec3b>(y, x).unwrap()[0];
        // The cable (rows 21–27) as it was; its shadow just below it, at
        // half the light where the cable shades it whole; nothing above
        // it or beyond its end.
        assert_eq!(gray(20, 24), 255);
        assert_eq!(gray(20, 29), 50);
        assert!(gray(20, 31) > 50 && gray(20, 31) < 100, "{}", gray(20, 31));
        assert_eq!(gray(20, 34), 100);
        assert_eq!(gray(20, 18), 100);
        assert_eq!(gray(55, 29), 100);
        // The labels do not move.
        let unlit = over_grey(&bgr, &masks, &lines, &placement);
        assert_eq!(
            scene.masks[0].data_bytes().unwrap(),
            unlit.masks[0].data_bytes().unwrap()
        );
    }

    #[test]
    fn the_cable_moves_with_its_labels_and_the_background_shows_around_it() {
        let (bgr, masks, lines) = photograph();
        let placement = Placement {
            mirror_x: true,
            ..AS_IS
        };
        let scene = over_grey(&bgr, &masks, &lines, &placement);

        // Mirrored left for right: the cable now runs in from the right
        // border, and its label with it.
        assert_eq!(scene.centerlines_px, vec![vec![[63.0, 24.0], [23.0, 24.0]]]);
        let mask = &scene.masks[0];
        assert_eq!(*mask.at_2d::<u8>(24, 60).unwrap(), 255);
        assert_eq!(*mask.at_2d::<u8>(24, 5).unwrap(), 0);
        assert_eq!(*scene.bgr.at_2d::<Vec3b>(24, 50).unwrap(), Vec3b::all(255));
        assert_eq!(*scene.bgr.at_2d::<Vec3b>(10, 50).unwrap(), Vec3b::all(100));
        assert_eq!(*scene.bgr.at_2d::<Vec3b>(24, 5).unwrap(), Vec3b::all(100));
    }

    #[test]
    fn an_enlarged_photograph_keeps_its_cable_leaving_the_view_and_drops_one_out_of_it() {
        let (bgr, mut masks, mut lines) = photograph();
        // A second cable, a dot in the lower right corner.
        let mut corner = filled(48, 64, CV_8UC1, 0.0);
        imgproc::circle(
            &mut corner,
            Point::new(60, 44),
            2,
            Scalar::all(255.0),
            -1,
            imgproc::LINE_8,
            0,
        )
        .unwrap();
        masks.push(corner);
        lines.push(vec![[59.0, 44.0], [61.0, 44.0]]);
        // Twice as large about the cable's end: the corner's dot leaves
        // the view, the cable still runs in from the left border.
        let placement = Placement {
            mirror_x: false,
            mirror_y: false,
            scale: 2.0,
            centre_px: [40.0, 24.0],
        };
        let scene = over_grey(&bgr, &masks, &lines, &placement);
        assert_eq!(scene.masks.len(), 1);
        let line = &scene.centerlines_px[0];
        assert_eq!(line.first(), Some(&[0.0, 24.0]));
        assert_eq!(line.last(), Some(&[40.0, 24.0]));
        // Ten pixels wide now.
        assert_eq!(*scene.masks[0].at_2d::<u8>(20, 20).unwrap(), 255);
        assert_eq!(*scene.masks[0].at_2d::<u8>(16, 20).unwrap(), 0);
    }

    #[test]
    fn a_cable_that_comes_back_into_view_is_labelled_once_a_piece_in_view() {
        // An arch: up the left arm from (20, 44), across at y = 4, down the
        // right arm to (44, 26), 5 px wide, white on black.
        let line = vec![[20.0, 44.0], [20.0, 4.0], [44.0, 4.0], [44.0, 26.0]];
        let points: core::Vector<Point> = line
            .iter()
            .map(|p| Point::new(p[0] as i32, p[1] as i32))
            .collect();
        let mut bgr = filled(48, 64, CV_8UC3, 0.0);
        let mut mask = filled(48, 64, CV_8UC1, 0.0);
        for image in [&mut bgr, &mut mask] {
            imgproc::polylines(
                image,
                &points,
                false,
                Scalar::all(255.0),
                5,
                imgproc::LINE_8,
                0,
            )
            .unwrap();
        }
        let masks = vec![mask];
        let lines = vec![line];
        let enlarged_about = |centre_y: f64| Placement {
            mirror_x: false,
            mirror_y: false,
            scale: 2.0,
            centre_px: [30.0, centre_y],
        };

        // About (30, 40) the arch's top leaves the view: each arm is a
        // cable to the camera, x = 10 and x = 58, with its own pixels.
        let scene = over_grey(&bgr, &masks, &lines, &enlarged_about(40.0));
        assert_eq!(
            scene.centerlines_px,
            vec![
                vec![[10.0, 47.0], [10.0, 0.0]],
                vec![[58.0, 0.0], [58.0, 12.0]]
            ]
        );
        let at = |mask: &Mat, x: i32, y: i32| *mask.at_2d::<u8>(y, x).unwrap();
        assert_eq!(
            (at(&scene.masks[0], 10, 5), at(&scene.masks[0], 58, 5)),
            (255, 0)
        );
        assert_eq!(
            (at(&scene.masks[1], 10, 5), at(&scene.masks[1], 58, 5)),
            (0, 255)
        );
        assert_eq!(*scene.bgr.at_2d::<Vec3b>(5, 58).unwrap(), Vec3b::all(255));

        // About (30, 46) the right arm shows 6 px, less than a rendered
        // cable may: neither labelled nor laid over the background.
        let scene = over_grey(&bgr, &masks, &lines, &enlarged_about(46.0));
        assert_eq!(scene.centerlines_px, vec![vec![[10.0, 42.0], [10.0, 0.0]]]);
        assert_eq!(*scene.bgr.at_2d::<Vec3b>(3, 58).unwrap(), Vec3b::all(100));
        assert_eq!(*scene.bgr.at_2d::<Vec3b>(20, 10).unwrap(), Vec3b::all(255));

        // About (30, 11) the arch's top runs 3 px beyond the border, its
        // pixels still in view: one cable, as the camera sees it.
        let scene = over_grey(&bgr, &masks, &lines, &enlarged_about(11.0));
        assert_eq!(
            scene.centerlines_px,
            vec![vec![[10.0, 47.0], [10.0, 0.0], [58.0, 0.0], [58.0, 41.0]]]
        );
        assert_eq!(at(&scene.masks[0], 34, 1), 255);
    }

    #[test]
    fn random_placements_fill_the_view() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..50 {
            let p = Placement::random(&mut rng, 640, 480);
            assert!((1.0..=MAX_SCALE).contains(&p.scale));
            let m = p.matrix(Size::new(640, 480), Size::new(640, 480));
            // The photograph's corners land on or beyond the view's.
            let xs = [m[0][2], m[0][0] * 639.0 + m[0][2]];
            let ys = [m[1][2], m[1][1] * 479.0 + m[1][2]];
            assert!(xs.iter().cloned().fold(f64::MAX, f64::min) <= 1e-9);
            assert!(xs.iter().cloned().fold(f64::MIN, f64::max) >= 639.0 - 1e-9);
            assert!(ys.iter().cloned().fold(f64::MAX, f64::min) <= 1e-9);
            assert!(ys.iter().cloned().fold(f64::MIN, f64::max) >= 479.0 - 1e-9);
        }
    }
}
