//! The synthetic camera: cables drawn as shaded tubes of a given colour and
//! diameter over plain or cluttered backgrounds, with crossings, lighting
//! changes and sensor noise, and the fiducial marker on the finger, with
//! exact masks and centre lines as ground truth. It is the simulated
//! camera's image of the simulated world (`render_world`), the vision
//! network's training data (`write_dataset`, in the layout of the
//! cables-dev data set) and the vision tests' fixtures.
//!
//! Drawing happens in floating point: background, then the cables in
//! order (a later cable over an earlier one, so crossings occlude; each
//! cable's mask is its whole tube, so masks overlap at crossings as in
//! cables-dev), then the marker, then the lighting, optical blur and
//! sensor noise, and finally 8-bit rounding. Every random choice comes from
//! the caller's generator, so a seed fixes the image.

mod background;
pub mod fixtures;
mod random;
mod tube;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Matrix3, Point3, Vector3};
use opencv::aruco::PREDEFINED_DICTIONARY_NAME;
use opencv::core::{self, Mat, Point2f, Scalar, Size, Vec3f, Vector};
use opencv::prelude::*;
use opencv::{aruco, imgcodecs, imgproc};
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub use random::{BackgroundChoice, SceneOptions, random_scene};

use crate::perception::vision::calibration::{CameraModel, MarkerOnFinger};
use crate::perception::vision::paths::polyline_length;
use crate::sim::world::SimWorld;

/// What the cables lie on. Apart from `Plain`, each kind draws its
/// colours, scales and layout from the render's random generator, so one
/// kind gives many different backgrounds.
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Background {
    /// One flat colour.
    Plain { bgr: [u8; 3] },
    /// A smooth ramp between two similar colours: plain, but not flat.
    Gradient,
    /// Mottled colour at several scales, like cloth, carpet or stone.
    Noise,
    /// Parallel bands of two colours at some angle and period.
    Stripes,
    /// A rotated checkerboard of two colours.
    Checker,
    /// Wood: wavy growth rings and fine grain along one direction.
    Wood,
    /// Paper with printed shapes, lines and text in many colours: the
    /// clutter that looks most like cables.
    Printed,
    /// Sheets of paper, card or cloth, pale or strongly coloured, lying
    /// on a table, some punched along one edge: long straight edges and
    /// rows of holes that are not cables.
    Sheets,
}

/// A cable to draw: its centre line in the image (a smooth curve, points
/// a pixel or so apart), its diameter in the image, and its colour.
#[derive(Clone, Debug, PartialEq)]
pub struct CableSpec {
    pub centerline_px: Vec<[f64; 2]>,
    pub diameter_px: f64,
    pub bgr: [u8; 3],
    /// Strength of the specular highlight along the cable (0: matte,
    /// 1: glossy insulation).
    pub gloss: f64,
}

/// The scene's light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Unit vector towards the light in the image's frame: x right, y
    /// down, z out of the image towards the viewer. Its x and y say which
    /// side of each cable is lit.
    pub toward_light: [f64; 3],
    /// Overall brightness factor.
    pub gain: f64,
    /// Brightness changes by ± this fraction from one side of the image to
    /// the other (uneven lighting).
    pub gradient: f64,
    /// The direction in the image along which the brightness rises.
    pub gradient_angle_rad: f64,
    /// How much a cable darkens the surface beneath it (0: no shadow; a
    /// cable lying on a table casts one, a suspended cable does not).
    pub shadow: f64,
}

impl Default for Light {
    /// Light from the upper left, even, no shadows.
    fn default() -> Self {
        Self {
            toward_light: unit([-0.5, -0.5, 0.7]),
            gain: 1.0,
            gradient: 0.0,
            gradient_angle_rad: 0.0,
            shadow: 0.0,
        }
    }
}

/// An ArUco marker to draw, given by where the four corners of its black
/// square fall in the image, in ArUco's order (top left, top right, bottom
/// right, bottom left as printed). It is drawn with a white margin one
/// module wide, as printed markers are, so that it can be detected on any
/// background.
#[derive(Clone, Debug, PartialEq)]
pub struct MarkerSpec {
    pub dictionary: PREDEFINED_DICTIONARY_NAME,
    pub id: i32,
    pub corners_px: [[f64; 2]; 4],
}

/// Everything one image shows.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneSpec {
    pub width_px: i32,
    pub height_px: i32,
    pub background: Background,
    /// Drawn in order: a later cable lies over an earlier one.
    pub cables: Vec<CableSpec>,
    pub light: Light,
    /// Standard deviation of the sensor's noise, in gray levels (0–255).
    pub noise_sigma: f64,
    /// Standard deviation of the optical blur, in pixels (0: sharp).
    pub blur_sigma_px: f64,
    pub marker: Option<MarkerSpec>,
}

/// An image and its ground truth.
#[derive(Debug)]
pub struct RenderedScene {
    /// CV_8UC3, BGR.
    pub bgr: Mat,
    /// One CV_8UC1 mask per cable (0 or 255): the pixels whose centre lies
    /// within the cable's tube, hidden or not.
    pub masks: Vec<Mat>,
    /// The masks' union.
    pub union_mask: Mat,
    /// Each cable's centre line, cut to the image (the longest stretch of
    /// it inside the image; empty for a cable out of view).
    pub centerlines_px: Vec<Vec<[f64; 2]>>,
}

/// How the simulated world looks to the simulated camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Appearance {
    pub background: Background,
    pub cable_bgr: [u8; 3],
    pub cable_gloss: f64,
    pub light: Light,
    pub noise_sigma: f64,
    pub blur_sigma_px: f64,
}

impl Default for Appearance {
    /// A dark red cable in front of a light gray wall, a little sensor
    /// noise and blur, as a lab camera sees it.
    fn default() -> Self {
        Self {
            background: Background::Plain {
                bgr: [200, 200, 200],
            },
            cable_bgr: [40, 40, 170],
            cable_gloss: 0.3,
            light: Light::default(),
            noise_sigma: 2.0,
            blur_sigma_px: 0.5,
        }
    }
}

/// Why an image could not be rendered or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The image size is not positive, or absurdly large. Fix the scene or
    /// the camera model.
    #[error("bad image size {width_px}×{height_px}")]
    BadSize { width_px: i32, height_px: i32 },
    /// A cable cannot be drawn: fewer than two points, points or diameter
    /// not finite, or a diameter not positive.
    #[error("cable {index} cannot be drawn: {reason}")]
    BadCable { index: usize, reason: &'static str },
    /// The marker's corners are not finite.
    #[error("the marker cannot be drawn: {reason}")]
    BadMarker { reason: &'static str },
    /// OpenCV failed while `step` ran.
    #[error("OpenCV failed to {step}")]
    OpenCv {
        step: &'static str,
        #[source]
        source: opencv::Error,
    },
    /// A file or folder of the data set could not be written.
    #[error("cannot write {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// OpenCV could not encode or write an image (an unknown extension or
    /// an unwritable place).
    #[error("OpenCV could not write the image {path}")]
    WriteImage { path: PathBuf },
}

/// Wraps an OpenCV error with the step that failed.
fn cv(step: &'static str) -> impl FnOnce(opencv::Error) -> RenderError {
    move |source| RenderError::OpenCv { step, source }
}

/// Beyond this side an image is a mistake rather than a scene.
const MAX_SIDE_PX: i32 = 16384;

/// How light the marker's white and how dark its black, in gray levels:
/// printed paper and toner, not ideal white and black.
const MARKER_WHITE: f64 = 235.0;
const MARKER_BLACK: f64 = 25.0;

/// The marker is drawn at this many times the image's resolution and
/// averaged down, as a sensor's pixels integrate light: its edges then sit
/// where the geometry puts them to a hundredth of a pixel, which a pose
/// from its corners needs.
const MARKER_SUPERSAMPLING: i32 = 4;

/// Draws `scene`, with its ground truth.
pub fn render(scene: &SceneSpec, rng: &mut impl Rng) -> Result<RenderedScene, RenderError> {
    let (width, height) = (scene.width_px, scene.height_px);
    if !(1..=MAX_SIDE_PX).contains(&width) || !(1..=MAX_SIDE_PX).contains(&height) {
        return Err(RenderError::BadSize {
            width_px: width,
            height_px: height,
        });
    }
    for (index, cable) in scene.cables.iter().enumerate() {
        check_cable(index, cable)?;
    }

    let mut image = background::draw(&scene.background, width, height, rng)?;
    let mut masks = Vec::with_capacity(scene.cables.len());
    let mut centerlines_px = Vec::with_capacity(scene.cables.len());
    {
        let pixels = pixels_mut(&mut image)?;
        for cable in &scene.cables {
            let mut mask = Mat::new_rows_cols_with_default(height, width, core::CV_8UC1, 0.into())
                .map_err(cv("allocate a mask"))?;
            let mask_pixels = mask.data_bytes_mut().map_err(cv("write a mask"))?;
            tube::draw(pixels, mask_pixels, width, height, cable, &scene.light);
            masks.push(mask);
            centerlines_px.push(clip_to_image(&cable.centerline_px, width, height));
        }
    }
    if let Some(marker) = &scene.marker {
        draw_marker(&mut image, marker)?;
    }
    apply_light(&mut image, &scene.light)?;
    if scene.blur_sigma_px > 0.0 {
        let mut blurred = Mat::default();
        imgproc::gaussian_blur(
            &image,
            &mut blurred,
            Size::new(0, 0),
            scene.blur_sigma_px,
            scene.blur_sigma_px,
            core::BORDER_REFLECT,
        )
        .map_err(cv("blur the image"))?;
        image = blurred;
    }
    if scene.noise_sigma > 0.0 {
        add_noise(&mut image, scene.noise_sigma, rng)?;
    }
    let mut bgr = Mat::default();
    image
        .convert_to(&mut bgr, core::CV_8UC3, 1.0, 0.0)
        .map_err(cv("round the image to 8 bits"))?;

    let mut union_mask = Mat::new_rows_cols_with_default(height, width, core::CV_8UC1, 0.into())
        .map_err(cv("allocate the union mask"))?;
    for mask in &masks {
        let mut next = Mat::default();
        core::bitwise_or(&union_mask, mask, &mut next, &core::no_array())
            .map_err(cv("unite the masks"))?;
        union_mask = next;
    }
    Ok(RenderedScene {
        bgr,
        masks,
        union_mask,
        centerlines_px,
    })
}

fn check_cable(index: usize, cable: &CableSpec) -> Result<(), RenderError> {
    let bad = |reason| Err(RenderError::BadCable { index, reason });
    if cable.centerline_px.len() < 2 {
        return bad("its centre line has fewer than two points");
    }
    if !cable.centerline_px.iter().flatten().all(|v| v.is_finite()) {
        return bad("its centre line has a point that is not finite");
    }
    if !(cable.diameter_px.is_finite() && cable.diameter_px > 0.0) {
        return bad("its diameter is not positive and finite");
    }
    if !cable.gloss.is_finite() {
        return bad("its gloss is not finite");
    }
    Ok(())
}

/// The pixels of a continuous CV_32FC3 image.
fn pixels_mut(image: &mut Mat) -> Result<&mut [Vec3f], RenderError> {
    image
        .data_typed_mut::<Vec3f>()
        .map_err(cv("access the image's pixels"))
}

/// `v` scaled to unit length (`v` itself if it is zero).
fn unit(v: [f64; 3]) -> [f64; 3] {
    let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if norm > 0.0 {
        [v[0] / norm, v[1] / norm, v[2] / norm]
    } else {
        v
    }
}

/// Warps the marker's image (with its white margin) onto `image` through
/// the homography its corners fix, its edges blended by the warped
/// coverage.
fn draw_marker(image: &mut Mat, marker: &MarkerSpec) -> Result<(), RenderError> {
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
    for [x, y] in [
        [-0.5, -0.5],
        [plate_side, -0.5],
        [plate_side, plate_side],
        [-0.5, plate_side],
    ] {
        let p = image_from_plate * Vector3::new(x, y, 1.0);
        if p.z.is_nan() || p.z <= 0.0 {
            return Err(RenderError::BadMarker {
                reason: "its corners do not make a marker seen from the front",
            });
        }
        for axis in 0..2 {
            box_min[axis] = box_min[axis].min(p[axis] / p.z);
            box_max[axis] = box_max[axis].max(p[axis] / p.z);
        }
    }
    let (width, height) = (image.cols(), image.rows());
    let x0 = (box_min[0].floor() - 1.0).max(0.0);
    let y0 = (box_min[1].floor() - 1.0).max(0.0);
    let x1 = (box_max[0].ceil() + 1.0).min(f64::from(width - 1));
    let y1 = (box_max[1].ceil() + 1.0).min(f64::from(height - 1));
    if x0 > x1 || y0 > y1 {
        return Ok(());
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
    Ok(())
}

/// Multiplies the image by the light's gain and its gradient across the
/// image.
fn apply_light(image: &mut Mat, light: &Light) -> Result<(), RenderError> {
    let (width, height) = (image.cols(), image.rows());
    let (sin, cos) = light.gradient_angle_rad.sin_cos();
    let half_extent = ((f64::from(width) * cos).abs() + (f64::from(height) * sin).abs()) / 2.0;
    let (cx, cy) = (f64::from(width - 1) / 2.0, f64::from(height - 1) / 2.0);
    let slope = if half_extent > 0.0 {
        light.gradient / half_extent
    } else {
        0.0
    };
    let pixels = pixels_mut(image)?;
    for (y, row) in pixels.chunks_exact_mut(width as usize).enumerate() {
        let along_y = (y as f64 - cy) * sin;
        for (x, pixel) in row.iter_mut().enumerate() {
            let factor = (light.gain * (1.0 + slope * ((x as f64 - cx) * cos + along_y))).max(0.0);
            let factor = factor as f32;
            for c in 0..3 {
                pixel[c] *= factor;
            }
        }
    }
    Ok(())
}

/// Adds Gaussian noise of `sigma` gray levels to every channel, from
/// OpenCV's generator seeded by `rng` (fast, and fixed by the seed).
fn add_noise(image: &mut Mat, sigma: f64, rng: &mut impl Rng) -> Result<(), RenderError> {
    let mut noise =
        Mat::new_rows_cols_with_default(image.rows(), image.cols(), core::CV_32FC3, 0.into())
            .map_err(cv("allocate the noise"))?;
    let mut generator = core::RNG::new(rng.random::<u64>()).map_err(cv("seed the noise"))?;
    generator
        .fill(
            &mut noise,
            core::RNG_NORMAL,
            &Scalar::all(0.0),
            &Scalar::all(sigma),
            false,
        )
        .map_err(cv("draw the noise"))?;
    let mut noisy = Mat::default();
    core::add(image, &noise, &mut noisy, &core::no_array(), -1).map_err(cv("add the noise"))?;
    *image = noisy;
    Ok(())
}

/// The longest stretch of `points` inside the image (pixel centres from 0
/// to size − 1), cut where it crosses the border.
fn clip_to_image(points: &[[f64; 2]], width: i32, height: i32) -> Vec<[f64; 2]> {
    let (max_x, max_y) = (f64::from(width - 1), f64::from(height - 1));
    let mut runs: Vec<Vec<[f64; 2]>> = Vec::new();
    let mut continues = false;
    for pair in points.windows(2) {
        let Some((t0, t1)) = clip_segment(pair[0], pair[1], max_x, max_y) else {
            continues = false;
            continue;
        };
        let at = |t: f64| {
            [
                pair[0][0] + t * (pair[1][0] - pair[0][0]),
                pair[0][1] + t * (pair[1][1] - pair[0][1]),
            ]
        };
        match runs.last_mut() {
            Some(run) if continues && t0 == 0.0 => run.push(at(t1)),
            _ => runs.push(vec![at(t0), at(t1)]),
        }
        continues = t1 == 1.0;
    }
    runs.into_iter()
        .max_by(|a, b| polyline_length(a).total_cmp(&polyline_length(b)))
        .unwrap_or_default()
}

/// The part of the segment from `a` to `b` inside [0, max_x] × [0, max_y],
/// as parameters along it (Liang–Barsky).
fn clip_segment(a: [f64; 2], b: [f64; 2], max_x: f64, max_y: f64) -> Option<(f64, f64)> {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let mut t0: f64 = 0.0;
    let mut t1: f64 = 1.0;
    for (p, q) in [
        (-dx, a[0]),
        (dx, max_x - a[0]),
        (-dy, a[1]),
        (dy, max_y - a[1]),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

/// The simulated camera's view of the simulated world: the cable (its
/// sagging centre line from `sim::cable`, placed by the world, projected
/// through `base_from_camera` and the intrinsics) drawn as a shaded tube of
/// the cable's diameter in pixels at its mean depth over the background,
/// and the finger's marker when it faces the camera. While the jaws hold
/// the cable it is drawn where it lay when they closed.
pub fn render_world(
    world: &SimWorld,
    camera: &CameraModel,
    base_from_camera: &Isometry3<f64>,
    marker: Option<&MarkerOnFinger>,
    appearance: &Appearance,
    rng: &mut impl Rng,
) -> Result<RenderedScene, RenderError> {
    let camera_from_base = base_from_camera.inverse();
    let camera_from_cable = camera_from_base * world.base_from_cable;
    let half_span_mm = world.cable.span_mm / 2.0;
    let point_at = |u_mm: f64| {
        let (height_mm, _) = world.cable.height_and_slope(u_mm);
        camera_from_cable * Point3::new(u_mm, height_mm, 0.0)
    };
    // About one point per pixel along the cable's image.
    let chord_px = match (
        camera.project(&point_at(-half_span_mm)),
        camera.project(&point_at(half_span_mm)),
    ) {
        (Some(a), Some(b)) => (a[0] - b[0]).hypot(a[1] - b[1]),
        _ => 0.0,
    };
    let samples = (chord_px.ceil() as usize).clamp(64, 4096);
    let in_camera: Vec<Point3<f64>> = (0..=samples)
        .map(|i| point_at(-half_span_mm + 2.0 * half_span_mm * i as f64 / samples as f64))
        .filter(|p| p.z > 0.0)
        .collect();
    let centerline_px: Vec<[f64; 2]> = in_camera.iter().filter_map(|p| camera.project(p)).collect();

    let mut cables = Vec::new();
    if centerline_px.len() >= 2 {
        let mean_depth_mm = in_camera.iter().map(|p| p.z).sum::<f64>() / in_camera.len() as f64;
        let focal_px = (camera.fx_px + camera.fy_px) / 2.0;
        cables.push(CableSpec {
            centerline_px,
            diameter_px: focal_px * world.cable_diameter_mm / mean_depth_mm,
            bgr: appearance.cable_bgr,
            gloss: appearance.cable_gloss,
        });
    }

    let marker = marker.and_then(|marker| {
        let camera_from_marker = camera_from_base * world.base_from_tcp * marker.tcp_from_marker;
        let normal = camera_from_marker.rotation * Vector3::z();
        // Seen from behind, or edge on, the marker shows nothing.
        if normal.dot(&-camera_from_marker.translation.vector) <= 0.0 {
            return None;
        }
        let corners = marker.corners_in_marker();
        let mut corners_px = [[0.0; 2]; 4];
        for (corner_px, corner) in corners_px.iter_mut().zip(&corners) {
            *corner_px = camera.project(&(camera_from_marker * corner))?;
        }
        Some(MarkerSpec {
            dictionary: marker.dictionary,
            id: marker.id,
            corners_px,
        })
    });

    render(
        &SceneSpec {
            width_px: camera.width_px,
            height_px: camera.height_px,
            background: appearance.background.clone(),
            cables,
            light: appearance.light,
            noise_sigma: appearance.noise_sigma,
            blur_sigma_px: appearance.blur_sigma_px,
            marker,
        },
        rng,
    )
}

/// JPEG quality of a data set's images: high enough to keep thin cables,
/// low enough to leave the compression's artefacts a real camera's
/// pipeline leaves.
const JPEG_QUALITY: i32 = 92;

/// Spacing of the points written to a data set's polylines, which hold
/// spline control points in cables-dev rather than every pixel.
const POLYLINE_SPACING_PX: f64 = 6.0;

/// Writes `count` random scenes into `dir` in the cables-dev layout: per
/// image `NNNNN.jpg`, `NNNNN_mask_K.png` (0/255, one per cable, K from 0),
/// `NNNNN_mask_all.png` and `NNNNN.txt` (line K: `N x0 y0 x1 y1 ...`, the
/// K-th cable's centre line, integer pixels as in cables-dev). Image i is
/// drawn from stream i of a generator seeded with `seed`, so it does not
/// depend on `count`.
pub fn write_dataset(
    dir: &Path,
    count: usize,
    seed: u64,
    options: &SceneOptions,
) -> Result<(), RenderError> {
    std::fs::create_dir_all(dir).map_err(|source| RenderError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    for index in 0..count {
        let rendered = dataset_scene(seed, index as u64, options)?;
        write_scene_files(dir, &format!("{index:05}"), &rendered)?;
    }
    Ok(())
}

/// Image `index` of the data set [`write_dataset`] writes for `seed` and
/// `options`, as rendered (before it is written as a JPEG).
pub fn dataset_scene(
    seed: u64,
    index: u64,
    options: &SceneOptions,
) -> Result<RenderedScene, RenderError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index);
    let scene = random_scene(&mut rng, options);
    render(&scene, &mut rng)
}

/// Writes `rendered` into the existing folder `dir` as image `stem` of a
/// data set in the cables-dev layout (see [`write_dataset`]).
pub fn write_scene_files(
    dir: &Path,
    stem: &str,
    rendered: &RenderedScene,
) -> Result<(), RenderError> {
    write_image(
        &dir.join(format!("{stem}.jpg")),
        &rendered.bgr,
        &[imgcodecs::IMWRITE_JPEG_QUALITY, JPEG_QUALITY],
    )?;
    for (k, mask) in rendered.masks.iter().enumerate() {
        write_image(&dir.join(format!("{stem}_mask_{k}.png")), mask, &[])?;
    }
    write_image(
        &dir.join(format!("{stem}_mask_all.png")),
        &rendered.union_mask,
        &[],
    )?;
    let mut text = String::new();
    for centerline in &rendered.centerlines_px {
        let points = resample(centerline, POLYLINE_SPACING_PX);
        let _ = write!(text, "{}", points.len());
        for [x, y] in points {
            let _ = write!(text, " {} {}", x.round(), y.round());
        }
        text.push('\n');
    }
    let path = dir.join(format!("{stem}.txt"));
    std::fs::write(&path, text).map_err(|source| RenderError::Io { path, source })
}

fn write_image(path: &Path, image: &Mat, params: &[i32]) -> Result<(), RenderError> {
    let params: Vector<i32> = params.iter().copied().collect();
    let written = imgcodecs::imwrite(path, image, &params).map_err(cv("encode an image"))?;
    if written {
        Ok(())
    } else {
        Err(RenderError::WriteImage {
            path: path.to_path_buf(),
        })
    }
}

/// Points along `points` about `spacing_px` apart, keeping both ends.
fn resample(points: &[[f64; 2]], spacing_px: f64) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    let mut since_kept = 0.0;
    for (i, point) in points.iter().enumerate() {
        if i > 0 {
            since_kept += (point[0] - points[i - 1][0]).hypot(point[1] - points[i - 1][1]);
        }
        if i == 0 || since_kept >= spacing_px {
            out.push(*point);
            since_kept = 0.0;
        }
    }
    match (points.last(), out.last()) {
        (Some(last), Some(kept)) if last != kept => out.push(*last),
        _ => {}
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_keeps_the_longest_stretch_inside_and_cuts_at_the_border() {
        let points = [[-10.0, 5.0], [50.0, 5.0], [120.0, 5.0], [150.0, 5.0]];
        let clipped = clip_to_image(&points, 100, 20);
        assert_eq!(clipped, vec![[0.0, 5.0], [50.0, 5.0], [99.0, 5.0]]);
        // Out and back in: the longer stretch wins.
        let points = [
            [10.0, 5.0],
            [10.0, -5.0],
            [30.0, -5.0],
            [30.0, 5.0],
            [90.0, 5.0],
        ];
        let clipped = clip_to_image(&points, 100, 20);
        assert_eq!(clipped, vec![[30.0, 0.0], [30.0, 5.0], [90.0, 5.0]]);
        assert!(clip_to_image(&[[-5.0, -5.0], [-1.0, -9.0]], 100, 20).is_empty());
    }

    #[test]
    fn resampling_keeps_the_ends_and_spaces_the_rest() {
        let points: Vec<[f64; 2]> = (0..=20).map(|i| [f64::from(i), 0.0]).collect();
        let kept = resample(&points, 6.0);
        assert_eq!(
            kept,
            vec![
                [0.0, 0.0],
                [6.0, 0.0],
                [12.0, 0.0],
                [18.0, 0.0],
                [20.0, 0.0]
            ]
        );
    }

    #[test]
    fn a_bad_size_or_cable_is_refused() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut scene = SceneSpec {
            width_px: 0,
            height_px: 10,
            background: Background::Gradient,
            cables: vec![],
            light: Light::default(),
            noise_sigma: 0.0,
            blur_sigma_px: 0.0,
            marker: None,
        };
        assert!(matches!(
            render(&scene, &mut rng),
            Err(RenderError::BadSize { .. })
        ));
        scene.width_px = 10;
        scene.cables.push(CableSpec {
            centerline_px: vec![[1.0, 1.0]],
            diameter_px: 2.0,
            bgr: [0, 0, 0],
            gloss: 0.0,
        });
        assert!(matches!(
            render(&scene, &mut rng),
            Err(RenderError::BadCable { index: 0, .. })
        ));
    }
}
