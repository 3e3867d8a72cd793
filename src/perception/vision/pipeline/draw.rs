//! Drawing what was found: paths as 0/255 masks, each cable's own mask
//! in the image's pixels, and their union.

use opencv::core::{self, Mat, Point, Rect, Scalar, Vector};
use opencv::imgproc;
use opencv::prelude::*;

use super::output::CableInstance;
use super::work_area::resize_span;
use crate::perception::vision::error::{VisionError, cv};
use crate::perception::vision::mask;

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

/// The pixels of `mask` within `thickness` of the path.
pub(super) fn path_mask(
    mask: &Mat,
    points_px: &[[f64; 2]],
    thickness: i32,
) -> Result<Mat, VisionError> {
    let drawn = draw_paths(mask.rows(), mask.cols(), &[points_px], thickness)?;
    let mut own = Mat::default();
    core::bitwise_and(&drawn, mask, &mut own, &core::no_array()).map_err(cv("instance mask"))?;
    Ok(own)
}

/// A `rows` × `cols` 0/255 mask of `paths` drawn `thickness` px wide
/// (points rounded to whole pixels).
pub(crate) fn draw_paths(
    rows: i32,
    cols: i32,
    paths: &[&[[f64; 2]]],
    thickness: i32,
) -> Result<Mat, VisionError> {
    let mut drawn = mask::zeros_u8(rows, cols)?;
    let curves: Vector<Vector<Point>> = paths
        .iter()
        .map(|path| {
            path.iter()
                .map(|p| Point::new(p[0].round() as i32, p[1].round() as i32))
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
