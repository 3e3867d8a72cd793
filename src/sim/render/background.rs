//! The backgrounds, as CV_32FC3 images in gray levels (0–255): each kind
//! draws its colours, scales and layout from the render's generator.

use std::f64::consts::{PI, TAU};

use opencv::core::{self, Mat, Point, Rect, Scalar, Size, Vec3f};
use opencv::imgproc;
use opencv::prelude::*;
use rand::{Rng, RngExt};

use super::{Background, RenderError, cv, pixels_mut};

/// Draws `background` at the given size.
pub(super) fn draw(
    background: &Background,
    width: i32,
    height: i32,
    rng: &mut impl Rng,
) -> Result<Mat, RenderError> {
    match background {
        Background::Plain { bgr } => filled(width, height, bgr.map(f64::from)),
        Background::Gradient => gradient(width, height, rng),
        Background::Noise => noise(width, height, rng),
        Background::Stripes => stripes(width, height, rng),
        Background::Checker => checker(width, height, rng),
        Background::Wood => wood(width, height, rng),
        Background::Printed => printed(width, height, rng),
        Background::Sheets => sheets(width, height, rng),
        Background::Pollock => pollock(width, height, rng),
        Background::Mosaic => mosaic(width, height, rng),
    }
}

fn filled(width: i32, height: i32, bgr: [f64; 3]) -> Result<Mat, RenderError> {
    Mat::new_rows_cols_with_default(
        height,
        width,
        core::CV_32FC3,
        Scalar::new(bgr[0], bgr[1], bgr[2], 0.0),
    )
    .map_err(cv("allocate the background"))
}

/// A random colour of middling saturation with its lightness in `lightness`.
fn colour(rng: &mut impl Rng, lightness: std::ops::Range<f64>) -> [f64; 3] {
    let level = rng.random_range(lightness);
    let tint = rng.random_range(0.0..60.0);
    [0; 3].map(|_| (level + rng.random_range(-tint..=tint)).clamp(0.0, 255.0))
}

/// `base` moved by up to `by` gray levels per channel.
fn near(rng: &mut impl Rng, base: [f64; 3], by: f64) -> [f64; 3] {
    base.map(|c| (c + rng.random_range(-by..=by)).clamp(0.0, 255.0))
}

fn mix(a: [f64; 3], b: [f64; 3], t: f64) -> Vec3f {
    Vec3f::from([0, 1, 2].map(|c| (a[c] + (b[c] - a[c]) * t) as f32))
}

/// Fills every pixel with `shade(x, y)`.
fn per_pixel(
    width: i32,
    height: i32,
    mut shade: impl FnMut(f64, f64) -> Vec3f,
) -> Result<Mat, RenderError> {
    let mut image = filled(width, height, [0.0; 3])?;
    let pixels = pixels_mut(&mut image)?;
    for (y, row) in pixels.chunks_exact_mut(width as usize).enumerate() {
        for (x, pixel) in row.iter_mut().enumerate() {
            *pixel = shade(x as f64, y as f64);
        }
    }
    Ok(image)
}

fn gradient(width: i32, height: i32, rng: &mut impl Rng) -> Result<Mat, RenderError> {
    let a = colour(rng, 90.0..240.0);
    let b = near(rng, a, 40.0);
    let (sin, cos) = rng.random_range(0.0..TAU).sin_cos();
    let extent = (f64::from(width) * cos).abs() + (f64::from(height) * sin).abs();
    let (cx, cy) = (f64::from(width) / 2.0, f64::from(height) / 2.0);
    per_pixel(width, height, |x, y| {
        mix(a, b, 0.5 + ((x - cx) * cos + (y - cy) * sin) / extent)
    })
}

/// Random values at a coarse grid of `cells_x` × `cells_y`, smoothly
/// enlarged to the image: CV_32FC`channels`, values in [-1, 1].
pub(super) fn smooth_noise(
    width: i32,
    height: i32,
    cells_x: i32,
    cells_y: i32,
    channels: i32,
    rng: &mut impl Rng,
) -> Result<Mat, RenderError> {
    let count = (cells_x * cells_y * channels) as usize;
    let values: Vec<f32> = (0..count).map(|_| rng.random_range(-1.0..=1.0)).collect();
    let coarse = Mat::from_slice(&values)
        .and_then(|m| m.reshape(channels, cells_y).and_then(|m| m.try_clone()))
        .map_err(cv("shape the coarse noise"))?;
    let mut fine = Mat::default();
    imgproc::resize(
        &coarse,
        &mut fine,
        Size::new(width, height),
        0.0,
        0.0,
        imgproc::INTER_CUBIC,
    )
    .map_err(cv("enlarge the coarse noise"))?;
    Ok(fine)
}

/// Mottled colour: a base colour moved by noise at three scales, each
/// channel on its own, plus grain.
fn noise(width: i32, height: i32, rng: &mut impl Rng) -> Result<Mat, RenderError> {
    let base = colour(rng, 60.0..220.0);
    let mut image = filled(width, height, base)?;
    let scale_px = rng.random_range(8.0..40.0);
    for (octave, amplitude) in [(1.0, 45.0), (4.0, 25.0), (12.0, 12.0)] {
        let cells =
            |side: i32| ((f64::from(side) / (scale_px * 12.0) * octave).ceil() as i32).max(2);
        let layer = smooth_noise(width, height, cells(width), cells(height), 3, rng)?;
        let mut sum = Mat::default();
        core::scale_add(&layer, amplitude, &image, &mut sum).map_err(cv("add a noise octave"))?;
        image = sum;
    }
    Ok(image)
}

fn stripes(width: i32, height: i32, rng: &mut impl Rng) -> Result<Mat, RenderError> {
    let a = colour(rng, 40.0..240.0);
    let b = colour(rng, 40.0..240.0);
    let period = rng.random_range(6.0..60.0);
    // Where the sine crosses this level sets the share of each colour.
    let level: f64 = rng.random_range(-0.6..0.6);
    let (sin, cos) = rng.random_range(0.0..TAU).sin_cos();
    // Edges about a pixel wide: the sine's slope where it crosses the level.
    let sharpness = period / (TAU * (1.0 - level * level).sqrt());
    per_pixel(width, height, |x, y| {
        let wave = (TAU * (x * cos + y * sin) / period).sin();
        mix(a, b, (0.5 + (wave - level) * sharpness).clamp(0.0, 1.0))
    })
}

fn checker(width: i32, height: i32, rng: &mut impl Rng) -> Result<Mat, RenderError> {
    let a = colour(rng, 40.0..240.0);
    let b = colour(rng, 40.0..240.0);
    let square = rng.random_range(8.0..70.0);
    let (sin, cos) = rng.random_range(0.0..TAU).sin_cos();
    per_pixel(width, height, |x, y| {
        let u = ((x * cos + y * sin) / square).floor() as i64;
        let v = ((y * cos - x * sin) / square).floor() as i64;
        mix(a, b, ((u + v).rem_euclid(2)) as f64)
    })
}

/// Growth rings (bands across the grain, bent by smooth noise) and fine
/// streaks along the grain over a brown or pale wood colour.
fn wood(width: i32, height: i32, rng: &mut impl Rng) -> Result<Mat, RenderError> {
    let light = [
        rng.random_range(90.0..170.0),
        rng.random_range(140.0..200.0),
        rng.random_range(180.0..235.0),
    ];
    let dark_by = rng.random_range(0.45..0.75);
    let dark = light.map(|c| c * dark_by);
    let ring_px = rng.random_range(12.0..45.0);
    let warp_px = rng.random_range(10.0..60.0);
    let (sin, cos) = rng.random_range(0.0..TAU).sin_cos();
    let warp = smooth_noise(width, height, 4, 4, 1, rng)?;
    let warp = warp.data_typed::<f32>().map_err(cv("read the warp"))?;
    // Streaks: a random profile across the grain, one value per pixel.
    let across = (f64::from(width).hypot(f64::from(height)) * 2.0).ceil() as usize + 2;
    let streaks: Vec<f64> = (0..across).map(|_| rng.random_range(-1.0..=1.0)).collect();
    let mut i = 0;
    per_pixel(width, height, |x, y| {
        let u = x * cos + y * sin;
        let bent = u + warp_px * f64::from(warp[i]);
        i += 1;
        let ring = 0.5 + 0.5 * (TAU * bent / ring_px).sin();
        let ring = ring * ring;
        let streak = streaks[(u + across as f64 / 2.0).clamp(0.0, (across - 1) as f64) as usize];
        mix(light, dark, (0.8 * ring + 0.15 * streak).clamp(0.0, 1.0))
    })
}

/// Letters that make text-like blobs.
const LETTERS: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";

/// Paper with printed rectangles, discs, lines, curves and text.
fn printed(width: i32, height: i32, rng: &mut impl Rng) -> Result<Mat, RenderError> {
    let level = rng.random_range(200.0..250.0);
    let paper = near(rng, [level; 3], 12.0);
    let mut image = Mat::new_rows_cols_with_default(
        height,
        width,
        core::CV_8UC3,
        Scalar::new(paper[0], paper[1], paper[2], 0.0),
    )
    .map_err(cv("allocate the paper"))?;
    let area = f64::from(width) * f64::from(height);
    let items = ((area / 8000.0) * rng.random_range(0.5..1.5)).ceil() as usize;
    let side = width.max(height);
    for _ in 0..items {
        let ink = colour(rng, 0.0..230.0);
        let ink = Scalar::new(ink[0], ink[1], ink[2], 0.0);
        let at = Point::new(rng.random_range(0..width), rng.random_range(0..height));
        let thickness = rng.random_range(1..5);
        match rng.random_range(0..5) {
            0 => {
                let size = Size::new(
                    rng.random_range(4..side / 4 + 5),
                    rng.random_range(4..side / 4 + 5),
                );
                let filled = if rng.random_bool(0.6) {
                    imgproc::FILLED
                } else {
                    thickness
                };
                imgproc::rectangle(
                    &mut image,
                    Rect::from_point_size(at, size),
                    ink,
                    filled,
                    imgproc::LINE_8,
                    0,
                )
                .map_err(cv("print a rectangle"))?;
            }
            1 => {
                let filled = if rng.random_bool(0.6) {
                    imgproc::FILLED
                } else {
                    thickness
                };
                imgproc::circle(
                    &mut image,
                    at,
                    rng.random_range(3..side / 10 + 4),
                    ink,
                    filled,
                    imgproc::LINE_AA,
                    0,
                )
                .map_err(cv("print a disc"))?;
            }
            2 => {
                let to = Point::new(rng.random_range(0..width), rng.random_range(0..height));
                imgproc::line(&mut image, at, to, ink, thickness, imgproc::LINE_AA, 0)
                    .map_err(cv("print a line"))?;
            }
            3 => {
                let axes = Size::new(
                    rng.random_range(5..side / 5 + 6),
                    rng.random_range(5..side / 5 + 6),
                );
                let start = rng.random_range(0.0..360.0);
                imgproc::ellipse(
                    &mut image,
                    at,
                    axes,
                    rng.random_range(0.0..180.0),
                    start,
                    start + rng.random_range(60.0..300.0),
                    ink,
                    thickness,
                    imgproc::LINE_AA,
                    0,
                )
                .map_err(cv("print an arc"))?;
            }
            _ => {
                let length = rng.random_range(2..12);
                let text: String = (0..length)
                    .map(|_| char::from(LETTERS[rng.random_range(0..LETTERS.len())]))
                    .collect();
                imgproc::put_text(
                    &mut image,
                    &text,
                    at,
                    rng.random_range(0..8),
                    rng.random_range(0.4..2.5),
                    ink,
                    thickness.min(3),
                    imgproc::LINE_AA,
                    false,
                )
                .map_err(cv("print text"))?;
            }
        }
    }
    // Printing leaves no perfectly sharp edge.
    let mut soft = Mat::default();
    imgproc::gaussian_blur(
        &image,
        &mut soft,
        Size::new(0, 0),
        0.7,
        0.7,
        core::BORDER_REFLECT,
    )
    .map_err(cv("soften the print"))?;
    to_float(&soft, "convert the paper")
}

/// An 8-bit drawing as the CV_32FC3 image the renderer works in.
fn to_float(image: &Mat, step: &'static str) -> Result<Mat, RenderError> {
    let mut out = Mat::default();
    image
        .convert_to(&mut out, core::CV_32FC3, 1.0, 0.0)
        .map_err(cv(step))?;
    Ok(out)
}

/// `image` (CV_32FC3) under a faint mottle of `cells_x` × `cells_y` noise
/// cells, of an amplitude drawn from `amplitude`: paper, cloth and canvas
/// are not flat.
fn mottled(
    image: &Mat,
    cells_x: i32,
    cells_y: i32,
    amplitude: std::ops::Range<f64>,
    rng: &mut impl Rng,
    step: &'static str,
) -> Result<Mat, RenderError> {
    let (width, height) = (image.cols(), image.rows());
    let mottle = smooth_noise(width, height, cells_x, cells_y, 3, rng)?;
    let mut sum = Mat::default();
    core::scale_add(&mottle, rng.random_range(amplitude), image, &mut sum).map_err(cv(step))?;
    Ok(sum)
}

/// A fully saturated-to-grey colour of hue `hue_deg`, saturation and value
/// in [0, 1], as BGR gray levels.
fn from_hsv(hue_deg: f64, saturation: f64, value: f64) -> [f64; 3] {
    let sector = (hue_deg.rem_euclid(360.0)) / 60.0;
    let chroma = value * saturation;
    let second = chroma * (1.0 - (sector % 2.0 - 1.0).abs());
    let (r, g, b) = match sector as u32 {
        0 => (chroma, second, 0.0),
        1 => (second, chroma, 0.0),
        2 => (0.0, chroma, second),
        3 => (0.0, second, chroma),
        4 => (second, 0.0, chroma),
        _ => (chroma, 0.0, second),
    };
    let low = value - chroma;
    [b, g, r].map(|c| 255.0 * (c + low))
}

/// A sheet's colour: pale paper half the time, else a strong colour like
/// coloured paper, card or cloth.
fn sheet_colour(rng: &mut impl Rng) -> [f64; 3] {
    if rng.random_bool(0.5) {
        let level = rng.random_range(200.0..250.0);
        near(rng, [level; 3], 10.0)
    } else {
        from_hsv(
            rng.random_range(0.0..360.0),
            rng.random_range(0.25..0.8),
            rng.random_range(0.45..0.95),
        )
    }
}

/// One to three sheets, each a slightly rotated rectangle reaching past at
/// least one side of the image, on a mottled table; a sheet may have a row
/// of punched holes along an edge that shows the table through them.
fn sheets(width: i32, height: i32, rng: &mut impl Rng) -> Result<Mat, RenderError> {
    let table = colour(rng, 60.0..230.0);
    let mut image = Mat::new_rows_cols_with_default(
        height,
        width,
        core::CV_8UC3,
        Scalar::new(table[0], table[1], table[2], 0.0),
    )
    .map_err(cv("allocate the table"))?;
    let (w, h) = (f64::from(width), f64::from(height));
    for _ in 0..rng.random_range(1..=3) {
        let paper = sheet_colour(rng);
        let angle =
            rng.random_range(-0.25..0.25_f64) + f64::from(rng.random_range(0..4)) * PI / 2.0;
        let (sin, cos) = angle.sin_cos();
        // The sheet's near corner inside the image; it runs off the far side.
        let corner = [
            rng.random_range(0.0..0.5 * w),
            rng.random_range(0.0..0.5 * h),
        ];
        let size = [
            rng.random_range(0.5..2.0) * w,
            rng.random_range(0.5..2.0) * h,
        ];
        let at = |u: f64, v: f64| [corner[0] + u * cos - v * sin, corner[1] + u * sin + v * cos];
        let outline: Vec<Point> = [
            [0.0, 0.0],
            [size[0], 0.0],
            [size[0], size[1]],
            [0.0, size[1]],
        ]
        .iter()
        .map(|&[u, v]| {
            let [x, y] = at(u, v);
            Point::new(x.round() as i32, y.round() as i32)
        })
        .collect();
        let outline = core::Vector::<core::Vector<Point>>::from_iter([outline.into()]);
        let ink = Scalar::new(paper[0], paper[1], paper[2], 0.0);
        imgproc::fill_poly(
            &mut image,
            &outline,
            ink,
            imgproc::LINE_AA,
            0,
            Point::default(),
        )
        .map_err(cv("lay a sheet"))?;
        if rng.random_bool(0.5) {
            // Holes along the sheet's edge v = 0, like a binder's punch.
            let inset = rng.random_range(6.0..20.0);
            let pitch = rng.random_range(12.0..30.0);
            let (long, short) = (rng.random_range(3.0..10.0), rng.random_range(2.0..5.0));
            let hole = Scalar::new(table[0], table[1], table[2], 0.0);
            let mut u = pitch / 2.0;
            while u < size[0] {
                let [x, y] = at(u, inset);
                let hole_box = core::RotatedRect::new(
                    core::Point2f::new(x as f32, y as f32),
                    core::Size2f::new(short as f32, long as f32),
                    angle.to_degrees() as f32,
                )
                .map_err(cv("place a hole"))?;
                imgproc::ellipse_rotated_rect(
                    &mut image,
                    hole_box,
                    hole,
                    imgproc::FILLED,
                    imgproc::LINE_AA,
                )
                .map_err(cv("punch a hole"))?;
                u += pitch;
            }
        }
    }
    let out = to_float(&image, "convert the sheets")?;
    mottled(&out, 12, 9, 3.0..15.0, rng, "mottle the sheets")
}

/// A paint's colour: black or white a third of the time (drip paintings
/// use them most), else any hue at any strength.
fn paint(rng: &mut impl Rng) -> [f64; 3] {
    match rng.random_range(0..6) {
        0 => near(rng, [25.0; 3], 15.0),
        1 => near(rng, [235.0; 3], 15.0),
        _ => from_hsv(
            rng.random_range(0.0..360.0),
            rng.random_range(0.2..1.0),
            rng.random_range(0.25..1.0),
        ),
    }
}

/// A wandering path a few pixels a step, curling more than a cable does
/// (poured paint follows the wrist, not a stiff wire), from anywhere in
/// the image, `length_px` long.
fn wandering_path(rng: &mut impl Rng, width: i32, height: i32, length_px: f64) -> Vec<Point> {
    const STEP_PX: f64 = 3.0;
    let (mut x, mut y) = (
        rng.random_range(0.0..f64::from(width)),
        rng.random_range(0.0..f64::from(height)),
    );
    let mut heading = rng.random_range(0.0..TAU);
    let curl = rng.random_range(0.02..0.25);
    let mut turn = 0.0_f64;
    let mut points = vec![Point::new(x as i32, y as i32)];
    for _ in 0..(length_px / STEP_PX) as usize {
        turn = 0.8 * turn + rng.random_range(-curl..=curl);
        heading += turn;
        x += STEP_PX * heading.cos();
        y += STEP_PX * heading.sin();
        points.push(Point::new(x.round() as i32, y.round() as i32));
    }
    points
}

/// A drip painting: a canvas, then layers of poured lines (thin, long),
/// brushed strokes (as wide as cables, their width swelling and thinning)
/// and splatters (clusters of drops), each in one of a few paints.
fn pollock(width: i32, height: i32, rng: &mut impl Rng) -> Result<Mat, RenderError> {
    let canvas = if rng.random_bool(0.3) {
        colour(rng, 15.0..80.0)
    } else {
        colour(rng, 160.0..240.0)
    };
    let mut image = Mat::new_rows_cols_with_default(
        height,
        width,
        core::CV_8UC3,
        Scalar::new(canvas[0], canvas[1], canvas[2], 0.0),
    )
    .map_err(cv("allocate the canvas"))?;
    let palette: Vec<[f64; 3]> = (0..rng.random_range(3..9)).map(|_| paint(rng)).collect();
    let area = f64::from(width) * f64::from(height) / (640.0 * 480.0);
    let marks = (f64::from(rng.random_range(20..90)) * area).ceil() as usize;
    let diagonal = f64::from(width).hypot(f64::from(height));
    for _ in 0..marks {
        let ink = palette[rng.random_range(0..palette.len())];
        let ink = Scalar::new(ink[0], ink[1], ink[2], 0.0);
        match rng.random_range(0..5) {
            0..=1 => {
                let length_px = rng.random_range(0.2..1.5) * diagonal;
                let path = wandering_path(rng, width, height, length_px);
                let thickness = rng.random_range(1..5);
                let path = core::Vector::<core::Vector<Point>>::from_iter([path.into()]);
                imgproc::polylines(
                    &mut image,
                    &path,
                    false,
                    ink,
                    thickness,
                    imgproc::LINE_AA,
                    0,
                )
                .map_err(cv("pour a line"))?;
            }
            2..=3 => {
                let length_px = rng.random_range(0.05..0.6) * diagonal;
                let path = wandering_path(rng, width, height, length_px);
                let widest = rng.random_range(4.0..20.0);
                let (phase, period) = (rng.random_range(0.0..TAU), rng.random_range(5.0..40.0));
                for (k, pair) in path.windows(2).enumerate() {
                    let swell = 0.5 + 0.5 * (phase + k as f64 / period).sin().abs();
                    let thickness = (widest * swell).round().max(1.0) as i32;
                    imgproc::line(
                        &mut image,
                        pair[0],
                        pair[1],
                        ink,
                        thickness,
                        imgproc::LINE_AA,
                        0,
                    )
                    .map_err(cv("brush a stroke"))?;
                }
            }
            _ => {
                let centre = [
                    rng.random_range(0.0..f64::from(width)),
                    rng.random_range(0.0..f64::from(height)),
                ];
                let spread = rng.random_range(5.0..60.0);
                for _ in 0..rng.random_range(5..40) {
                    let (sin, cos) = rng.random_range(0.0..TAU).sin_cos();
                    let r = spread * rng.random_range(0.0..1.0_f64).sqrt();
                    let at = Point::new(
                        (centre[0] + r * cos).round() as i32,
                        (centre[1] + r * sin).round() as i32,
                    );
                    let radius = rng.random_range(1.0..7.0_f64);
                    let axes = Size::new(
                        (radius * rng.random_range(1.0..3.0)).round() as i32,
                        radius.round() as i32,
                    );
                    let angle = sin.atan2(cos).to_degrees();
                    imgproc::ellipse(
                        &mut image,
                        at,
                        axes,
                        angle,
                        0.0,
                        360.0,
                        ink,
                        imgproc::FILLED,
                        imgproc::LINE_AA,
                        0,
                    )
                    .map_err(cv("splatter a drop"))?;
                }
            }
        }
    }
    let out = to_float(&image, "convert the canvas")?;
    // The canvas's weave and the paint's thickness, finer than paper's.
    mottled(&out, 40, 30, 3.0..12.0, rng, "mottle the canvas")
}

/// A printed mosaic: the Voronoi cells of random points (OpenCV's
/// `Subdiv2D`), each a strong colour, with grout lines between them.
fn mosaic(width: i32, height: i32, rng: &mut impl Rng) -> Result<Mat, RenderError> {
    let mut image =
        Mat::new_rows_cols_with_default(height, width, core::CV_8UC3, Scalar::all(128.0))
            .map_err(cv("allocate the mosaic"))?;
    let area = f64::from(width) * f64::from(height);
    let tile_px = rng.random_range(12.0..70.0_f64);
    let count = ((area / (tile_px * tile_px)).ceil() as usize).max(2);
    let seeds: core::Vector<core::Point2f> = (0..count)
        .map(|_| {
            core::Point2f::new(
                rng.random_range(0.0..width as f32),
                rng.random_range(0.0..height as f32),
            )
        })
        .collect();
    let mut subdivision =
        imgproc::Subdiv2D::new(Rect::new(0, 0, width, height)).map_err(cv("start the tiling"))?;
    subdivision
        .insert_multiple(&seeds)
        .map_err(cv("place the tiles"))?;
    let mut facets = core::Vector::<core::Vector<core::Point2f>>::new();
    let mut centres = core::Vector::<core::Point2f>::new();
    subdivision
        .get_voronoi_facet_list(&core::Vector::new(), &mut facets, &mut centres)
        .map_err(cv("cut the tiles"))?;
    let grout = colour(rng, 30.0..230.0);
    let grout = Scalar::new(grout[0], grout[1], grout[2], 0.0);
    let grout_px = rng.random_range(0..4);
    for facet in &facets {
        let outline: core::Vector<Point> = facet
            .iter()
            .map(|p| Point::new(p.x.round() as i32, p.y.round() as i32))
            .collect();
        let tile = paint(rng);
        let tile = Scalar::new(tile[0], tile[1], tile[2], 0.0);
        imgproc::fill_convex_poly(&mut image, &outline, tile, imgproc::LINE_AA, 0)
            .map_err(cv("lay a tile"))?;
        if grout_px > 0 {
            let outline = core::Vector::<core::Vector<Point>>::from_iter([outline]);
            imgproc::polylines(
                &mut image,
                &outline,
                true,
                grout,
                grout_px,
                imgproc::LINE_AA,
                0,
            )
            .map_err(cv("grout a tile"))?;
        }
    }
    to_float(&image, "convert the mosaic")
}
