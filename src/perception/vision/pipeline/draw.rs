//! Drawing what was found: paths as 0/255 masks, each cable's own mask
//! in the image's pixels, and their union.

use opencv::core::{self, Mat, Point, Rect, Scalar, Vector};
use opencv::imgproc;
use opencv::prelude::*;

use super::output::CableInstance;
use super::work_area::resize_span;
use crate::perception::vision::error::{VisionError, cv};
use crate::perception::vision::mask;
use crate::perception::vision::paths::median;

/// A cable's working-size mask `own`, of region `roi` of an image of
/// extent `full`, in the full image: inside `roi`, what resizing the whole
/// of `own` to `roi`'s size and cutting it at half gives (its edges follow
/// the cable rather than the working pixels' steps); zero elsewhere. Only
/// a box around the cable is resized, so that the cost grows with the
/// cable rather than with the camera's resolution.
pub(super) fn mask_in_image(own: &Mat, roi: Rect, full: Rect) -> Result<Mat, VisionError> {
    let mut out = mask::zeros_u8(full.height, full.width)?;
    let found = imgproc::bounding_rect(own).map_err(cv("cable mask extent"))?;
    if found.width <= 0 || found.height <= 0 {
        return Ok(out);
    }
    let (x, image_x) = resize_span(found.x, found.width, own.cols(), roi.width);
    let (y, image_y) = resize_span(found.y, found.height, own.rows(), roi.height);
    let part = Mat::roi(own, Rect::new(x.0, y.0, x.1 - x.0, y.1 - y.0))
        .and_then(|m| m.try_clone())
        .map_err(cv("box around a cable"))?;
    let size = core::Size::new(image_x.1 - image_x.0, image_y.1 - image_y.0);
    let resized = mask::resize_and_cut(&part, size, 127.0)?;
    let to = Rect::new(
        roi.x + image_x.0,
        roi.y + image_y.0,
        size.width,
        size.height,
    );
    let mut dst = Mat::roi_mut(&mut out, to).map_err(cv("box around a cable in the image"))?;
    resized
        .copy_to(&mut dst)
        .map_err(cv("place a cable's mask in the image"))?;
    Ok(out)
}

/// How far past its own half width a pixel may lie from a cable's path
/// and still be the cable's own: the rim where cable and background blend.
const OWN_RIM_PX: f64 = 1.5;

/// Each path's own pixels of `mask`, in the mask's pixels: those of a
/// band `band_px` wide along the path (wide enough for the image's
/// thicker cables), save those that lie within another cable's own width
/// of its path and not within this one's. A cable's own width is the
/// median of the mask's widths along its path (`half_widths`: the mask's
/// distance transform) plus [`OWN_RIM_PX`] on each side.
/// Where a thick and a thin cable cross, the thick one's pixels beyond
/// the thin one's rim are the thick one's alone, and the crossing itself
/// is both cables'. Every pixel of a band stays some cable's, so the
/// union is the bands' union. Each cable is worked on in a box around its
/// band, so that the cost grows with the cables rather than the image.
pub(super) fn cable_masks(
    mask: &Mat,
    half_widths: &Mat,
    paths: &[&[[f64; 2]]],
    band_px: i32,
) -> Result<Vec<Mat>, VisionError> {
    let full = Rect::new(0, 0, mask.cols(), mask.rows());
    // How many cables hold each pixel as their own (0 or 1 each).
    let mut owners = mask::zeros_u8(full.height, full.width)?;
    let mut parts = Vec::with_capacity(paths.len());
    for path in paths {
        let own_width_px = median(&mut mask::widths_along(half_widths, path)).unwrap_or(0.0);
        let own_px = ((own_width_px + 2.0 * OWN_RIM_PX).round() as i32).max(1);
        let Some(rect) = box_around(path, band_px.max(own_px), full) else {
            parts.push(None);
            continue;
        };
        let drawn = |thickness| draw_paths_in(rect, &[path], thickness);
        let mut band = Mat::default();
        let mask_part = Mat::roi(mask, rect).map_err(cv("box around a cable"))?;
        core::bitwise_and(&drawn(band_px)?, &mask_part, &mut band, &core::no_array())
            .map_err(cv("a cable's band"))?;
        let mut own = Mat::default();
        core::bitwise_and(&drawn(own_px)?, &band, &mut own, &core::no_array())
            .map_err(cv("a cable's own width"))?;
        let mut owners_part = Mat::roi_mut(&mut owners, rect).map_err(cv("box around a cable"))?;
        let so_far = owners_part.try_clone().map_err(cv("box around a cable"))?;
        core::add(&so_far, &Scalar::all(1.0), &mut owners_part, &own, -1)
            .map_err(cv("count the cables' own pixels"))?;
        parts.push(Some((rect, band, own)));
    }
    parts
        .into_iter()
        .map(|part| {
            let mut cable = mask::zeros_u8(full.height, full.width)?;
            let Some((rect, band, own)) = part else {
                return Ok(cable);
            };
            // The band's pixels that are this cable's own or that no other
            // cable holds as its own.
            for row in 0..rect.height {
                let band_row = band.at_row::<u8>(row).map_err(cv("a cable's mask"))?;
                let own_row = own.at_row::<u8>(row).map_err(cv("a cable's mask"))?;
                let owners_row = owners
                    .at_row::<u8>(rect.y + row)
                    .map_err(cv("a cable's mask"))?;
                let owners_row = &owners_row[rect.x as usize..][..rect.width as usize];
                let cable_row = cable
                    .at_row_mut::<u8>(rect.y + row)
                    .map_err(cv("a cable's mask"))?;
                let cable_row = &mut cable_row[rect.x as usize..][..rect.width as usize];
                for (((out, &b), &o), &n) in cable_row
                    .iter_mut()
                    .zip(band_row)
                    .zip(own_row)
                    .zip(owners_row)
                {
                    let others = n - u8::from(o != 0);
                    *out = if o != 0 || others == 0 { b } else { 0 };
                }
            }
            Ok(cable)
        })
        .collect()
}

/// The box within `full` that holds everything drawn along `points_px`
/// `thickness` px wide; `None` where that lies outside it.
fn box_around(points_px: &[[f64; 2]], thickness: i32, full: Rect) -> Option<Rect> {
    let reach = thickness / 2 + 2;
    let xs = points_px.iter().map(|p| p[0].round() as i32);
    let ys = points_px.iter().map(|p| p[1].round() as i32);
    let (x0, x1) = (xs.clone().min()? - reach, xs.max()? + reach);
    let (y0, y1) = (ys.clone().min()? - reach, ys.max()? + reach);
    let (x0, y0) = (x0.max(full.x), y0.max(full.y));
    let (x1, y1) = (
        x1.min(full.x + full.width - 1),
        y1.min(full.y + full.height - 1),
    );
    (x1 >= x0 && y1 >= y0).then(|| Rect::new(x0, y0, x1 - x0 + 1, y1 - y0 + 1))
}

/// A `rows` × `cols` 0/255 mask of `paths` drawn `thickness` px wide
/// (points rounded to whole pixels).
pub(crate) fn draw_paths(
    rows: i32,
    cols: i32,
    paths: &[&[[f64; 2]]],
    thickness: i32,
) -> Result<Mat, VisionError> {
    draw_paths_in(Rect::new(0, 0, cols, rows), paths, thickness)
}

/// The part `rect` of the mask that [`draw_paths`] draws: the same
/// pixels, the points rounded before they are moved into the box.
fn draw_paths_in(rect: Rect, paths: &[&[[f64; 2]]], thickness: i32) -> Result<Mat, VisionError> {
    let mut drawn = mask::zeros_u8(rect.height, rect.width)?;
    let curves: Vector<Vector<Point>> = paths
        .iter()
        .map(|path| {
            path.iter()
                .map(|p| Point::new(p[0].round() as i32 - rect.x, p[1].round() as i32 - rect.y))
                .collect()
        })
        .collect();
    imgproc::polylines(
        &mut drawn,
        &curves,
        false,
        Scalar::all(255.0),
        thickness,
        imgproc::LINE_8,
        0,
    )
    .map_err(cv("draw paths"))?;
    Ok(drawn)
}

/// The union of the `cables`' own masks in an image of extent `full`:
/// CV_8U 0/255.
pub fn union_mask(cables: &[CableInstance], full: Rect) -> Result<Mat, VisionError> {
    let mut union_mask = mask::zeros_u8(full.height, full.width)?;
    for own in cables.iter().filter_map(|c| c.mask.as_ref()) {
        union_mask
            .set_to(&Scalar::all(255.0), own)
            .map_err(cv("union of the cables' masks"))?;
    }
    Ok(union_mask)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::vision::curves::segment_px;

    fn count(mask: &Mat) -> i32 {
        core::count_non_zero(mask).unwrap()
    }

    fn differing(a: &Mat, b: &Mat) -> i32 {
        let mut differ = Mat::default();
        core::compare(a, b, &mut differ, core::CMP_NE).unwrap();
        count(&differ)
    }

    fn set(mask: &Mat, x: i32, y: i32) -> bool {
        *mask.at_2d::<u8>(y, x).unwrap() != 0
    }

    #[test]
    fn a_thin_cable_crossing_a_thick_one_keeps_the_crossing_and_no_more_of_it() {
        // A 21 px cable across, a 7 px one down; the band is wide enough
        // for the thick one, so the thin one's band takes in 16 px of the
        // thick one on each side of its path.
        let thick = segment_px([20.0, 100.0], [280.0, 100.0]);
        let thin = segment_px([150.0, 20.0], [150.0, 180.0]);
        let mut mask = draw_paths(200, 300, &[&thick], 21).unwrap();
        let thin_drawn = draw_paths(200, 300, &[&thin], 7).unwrap();
        let mask_copy = mask.clone();
        core::bitwise_or(&mask_copy, &thin_drawn, &mut mask, &core::no_array()).unwrap();
        let band_px = 33;
        let owns = cable_masks(
            &mask,
            &mask::half_widths(&mask).unwrap(),
            &[&thick, &thin],
            band_px,
        )
        .unwrap();
        let (thick_own, thin_own) = (&owns[0], &owns[1]);
        // The crossing is both cables'.
        for (x, y) in [(150, 100), (152, 92), (148, 108)] {
            assert!(set(thick_own, x, y) && set(thin_own, x, y), "({x}, {y})");
        }
        // The thick cable beside the crossing is the thick one's alone, and
        // the thin one beyond the thick one's rim the thin one's alone.
        for (x, y) in [(160, 100), (140, 95), (164, 108)] {
            assert!(set(thick_own, x, y) && !set(thin_own, x, y), "({x}, {y})");
        }
        for (x, y) in [(150, 115), (151, 84)] {
            assert!(set(thin_own, x, y) && !set(thick_own, x, y), "({x}, {y})");
        }
        // Every pixel of a band is still some cable's: the union is the
        // bands' union.
        let bands = draw_paths(200, 300, &[&thick, &thin], band_px).unwrap();
        let mut in_bands = Mat::default();
        core::bitwise_and(&bands, &mask, &mut in_bands, &core::no_array()).unwrap();
        let mut union = Mat::default();
        core::bitwise_or(thick_own, thin_own, &mut union, &core::no_array()).unwrap();
        assert_eq!(differing(&union, &in_bands), 0);
    }

    #[test]
    fn a_lone_cable_keeps_its_whole_band_where_its_box_meets_the_edge() {
        // Worked on in a box around it, cut by the image's edges: the same
        // pixels as the band drawn over the whole mask.
        let mask = draw_paths(120, 160, &[&segment_px([0.0, 3.0], [159.0, 119.0])], 9).unwrap();
        let half_widths = mask::half_widths(&mask).unwrap();
        for path in [
            segment_px([0.0, 3.0], [159.0, 119.0]),
            segment_px([0.3, 2.6], [60.5, 47.5]),
            vec![[156.0, 117.0], [159.0, 119.0]],
        ] {
            let owns = cable_masks(&mask, &half_widths, &[&path], 15).unwrap();
            let mut band = Mat::default();
            core::bitwise_and(
                &draw_paths(120, 160, &[&path], 15).unwrap(),
                &mask,
                &mut band,
                &core::no_array(),
            )
            .unwrap();
            assert!(count(&band) > 0);
            assert_eq!(differing(&owns[0], &band), 0, "{:?}", path.first());
        }
        // A path with no points has no pixels.
        let owns = cable_masks(&mask, &half_widths, &[&[]], 15).unwrap();
        assert_eq!(count(&owns[0]), 0);
    }

    #[test]
    fn a_cable_mask_resized_in_a_box_around_it_is_the_whole_resize() {
        // The box is resized alone, so its pixels must be those of the
        // whole working mask resized: at whole multiples, at ratios such as
        // 480 : 2048 whose box sides must fall on whole image pixels, at
        // none (640 : 641, the whole mask), shrunk, and inside a region of
        // interest; for cables reaching the working mask's edges and
        // corner, a lone pixel and no cable.
        let cables: [&[[f64; 2]]; 3] = [
            &[[0.0, 5.0], [200.0, 90.0], [350.0, 300.0]],
            &[[639.0, 479.0], [600.0, 440.0]],
            &[[410.0, 30.0], [410.0, 30.0]],
        ];
        let mut owns: Vec<Mat> = cables
            .iter()
            .map(|&c| draw_paths(480, 640, &[c], 7).unwrap())
            .collect();
        owns.push(draw_paths(480, 640, &[&[[77.0, 99.0]]], 1).unwrap());
        owns.push(mask::zeros_u8(480, 640).unwrap());
        for (cols, rows) in [
            (1920, 1440),
            (2448, 2048),
            (641, 481),
            (320, 240),
            (1000, 750),
        ] {
            for (roi, full) in [
                (Rect::new(0, 0, cols, rows), Rect::new(0, 0, cols, rows)),
                (
                    Rect::new(7, 3, cols, rows),
                    Rect::new(0, 0, cols + 20, rows + 9),
                ),
            ] {
                for own in &owns {
                    let whole = mask::resize_and_cut(own, roi.size(), 127.0).unwrap();
                    let mut expected = mask::zeros_u8(full.height, full.width).unwrap();
                    whole
                        .copy_to(&mut Mat::roi_mut(&mut expected, roi).unwrap())
                        .unwrap();
                    let boxed = mask_in_image(own, roi, full).unwrap();
                    let mut differ = Mat::default();
                    core::compare(&boxed, &expected, &mut differ, core::CMP_NE).unwrap();
                    assert_eq!(
                        core::count_non_zero(&differ).unwrap(),
                        0,
                        "{cols} x {rows} in {full:?}"
                    );
                }
            }
        }
    }
}
