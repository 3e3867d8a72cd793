//! The finger's ArUco marker, drawn where its pose puts it, supersampled so
//! that its corners sit where the geometry says.

use nalgebra::{Matrix3, Vector3};
use opencv::core::{self, Mat, Point2f, Scalar, Size};
use opencv::prelude::*;
use opencv::{aruco, imgproc};

use super::{MarkerSpec, RenderError, cv, pixels_mut};

/// How light the marker's white and how dark its black, in gray levels:
/// printed paper and toner, not ideal white and black.
const MARKER_WHITE: f64 = 235.0;
const MARKER_BLACK: f64 = 25.0;

/// The marker is drawn at this many times the image's resolution and
/// averaged down, as a sensor's pixels integrate light: its edges then sit
/// where the geometry puts them to a hundredth of a pixel, which a pose
/// from its corners needs.
const MARKER_SUPERSAMPLING: i32 = 4;

/// Warps the marker's image (with its white margin) onto `image` through
/// the homography its corners fix, its edges blended by the warped
/// coverage. Returns the outline of what it covers: the plate's corners.
pub(super) fn draw_marker(
    image: &mut Mat,
    marker: &MarkerSpec,
) -> Result<[[f64; 2]; 4], RenderError> {
    if !marker.corners_px.iter().flatten().all(|v| v.is_finite()) {
        return Err(RenderError::BadMarker {
            reason: "a corner is not finite",
        });
    }
    let dictionary =
        aruco::get_predefined_dictionary(marker.dictionary).map_err(cv("load the dictionary"))?;
    // The data bits and a black border one bit wide.
    let modules = dictionary.marker_size() + 2;
    let side_px = (0..4)
        .map(|i| {
            let [a, b] = [marker.corners_px[i], marker.corners_px[(i + 1) % 4]];
            (a[0] - b[0]).hypot(a[1] - b[1])
        })
        .fold(0.0, f64::max);
    // Source pixels about as large as the supersampled image's, so that
    // bilinear sampling neither aliases nor blurs the edges.
    let module_px = ((f64::from(MARKER_SUPERSAMPLING) * side_px / f64::from(modules)).ceil()
        as i32)
        .clamp(2, 128);
    let mut bits = Mat::default();
    aruco::draw_marker(&dictionary, marker.id, modules * module_px, &mut bits, 1)
        .map_err(cv("draw the marker"))?;
    let mut plate = Mat::default();
    core::copy_make_border(
        &bits,
        &mut plate,
        module_px,
        module_px,
        module_px,
        module_px,
        core::BORDER_CONSTANT,
        Scalar::all(255.0),
    )
    .map_err(cv("add the marker's margin"))?;
    let mut plate_gray = Mat::default();
    plate
        .convert_to(
            &mut plate_gray,
            core::CV_32F,
            (MARKER_WHITE - MARKER_BLACK) / 255.0,
            MARKER_BLACK,
        )
        .map_err(cv("shade the marker"))?;

    // Pixel centres are at integer coordinates, so the black square's
    // edges lie half a pixel before its first and after its last pixel.
    let lo = module_px as f32 - 0.5;
    let hi = ((modules + 1) * module_px) as f32 - 0.5;
    let source = [
        Point2f::new(lo, lo),
        Point2f::new(hi, lo),
        Point2f::new(hi, hi),
        Point2f::new(lo, hi),
    ];
    let target = marker
        .corners_px
        .map(|[x, y]| Point2f::new(x as f32, y as f32));
    let homography = imgproc::get_perspective_transform_slice_def(source, target)
        .map_err(cv("find the marker's homography"))?;
    let image_from_plate = Matrix3::from_fn(|r, c| {
        homography
            .at_2d::<f64>(r as i32, c as i32)
            .copied()
            .unwrap_or(f64::NAN)
    });

    // The box of the image the plate covers, a pixel wider.
    let plate_side = f64::from((modules + 2) * module_px) - 0.5;
    let mut box_min = [f64::INFINITY; 2];
    let mut box_max = [f64::NEG_INFINITY; 2];
    let mut outline_px = [[0.0; 2]; 4];
    for (corner_px, [x, y]) in outline_px.iter_mut().zip([
        [-0.5, -0.5],
        [plate_side, -0.5],
        [plate_side, plate_side],
        [-0.5, plate_side],
    ]) {
        let p = image_from_plate * Vector3::new(x, y, 1.0);
        if p.z.is_nan() || p.z <= 0.0 {
            return Err(RenderError::BadMarker {
                reason: "its corners do not make a marker seen from the front",
            });
        }
        *corner_px = [p.x / p.z, p.y / p.z];
        for axis in 0..2 {
            box_min[axis] = box_min[axis].min(corner_px[axis]);
            box_max[axis] = box_max[axis].max(corner_px[axis]);
        }
    }
    let (width, height) = (image.cols(), image.rows());
    let x0 = (box_min[0].floor() - 1.0).max(0.0);
    let y0 = (box_min[1].floor() - 1.0).max(0.0);
    let x1 = (box_max[0].ceil() + 1.0).min(f64::from(width - 1));
    let y1 = (box_max[1].ceil() + 1.0).min(f64::from(height - 1));
    if x0 > x1 || y0 > y1 {
        return Ok(outline_px);
    }
    let (x0, y0) = (x0 as i32, y0 as i32);
    let (box_width, box_height) = (x1 as i32 - x0 + 1, y1 as i32 - y0 + 1);

    // Into the box at the supersampled resolution: image coordinate X falls
    // at S (X − x0 + ½) − ½, so that averaging S × S blocks gives the
    // box's pixels.
    let s = f64::from(MARKER_SUPERSAMPLING);
    let super_from_image = Matrix3::new(
        s,
        0.0,
        s * (0.5 - f64::from(x0)) - 0.5,
        0.0,
        s,
        s * (0.5 - f64::from(y0)) - 0.5,
        0.0,
        0.0,
        1.0,
    );
    let super_from_plate = super_from_image * image_from_plate;
    let rows: Vec<[f64; 3]> = (0..3)
        .map(|r| [0, 1, 2].map(|c| super_from_plate[(r, c)]))
        .collect();
    let super_from_plate = Mat::from_slice_2d(&rows).map_err(cv("hold the homography"))?;
    let super_size = Size::new(
        box_width * MARKER_SUPERSAMPLING,
        box_height * MARKER_SUPERSAMPLING,
    );
    let warp = |source: &Mat, step| -> Result<Mat, RenderError> {
        let mut warped = Mat::default();
        imgproc::warp_perspective(
            source,
            &mut warped,
            &super_from_plate,
            super_size,
            imgproc::INTER_LINEAR,
            core::BORDER_CONSTANT,
            Scalar::all(0.0),
        )
        .map_err(cv(step))?;
        let mut area = Mat::default();
        imgproc::resize(
            &warped,
            &mut area,
            Size::new(box_width, box_height),
            0.0,
            0.0,
            imgproc::INTER_AREA,
        )
        .map_err(cv(step))?;
        Ok(area)
    };
    // Outside the plate both warps read the zero border, so the warped
    // gray is already weighted by the coverage.
    let gray = warp(&plate_gray, "warp the marker")?;
    let ones = Mat::new_rows_cols_with_default(plate.rows(), plate.cols(), core::CV_32F, 1.into())
        .map_err(cv("allocate the marker's coverage"))?;
    let coverage = warp(&ones, "warp the marker's coverage")?;
    let gray = gray.data_typed::<f32>().map_err(cv("read the marker"))?;
    let coverage = coverage
        .data_typed::<f32>()
        .map_err(cv("read the marker's coverage"))?;
    let pixels = pixels_mut(image)?;
    for by in 0..box_height {
        for bx in 0..box_width {
            let i = (by * box_width + bx) as usize;
            let a = coverage[i];
            if a > 0.0 {
                let pixel = &mut pixels[((y0 + by) * width + x0 + bx) as usize];
                for c in 0..3 {
                    pixel[c] = pixel[c] * (1.0 - a) + gray[i];
                }
            }
        }
    }
    Ok(outline_px)
}
