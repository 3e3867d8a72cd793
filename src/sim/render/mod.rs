//! The synthetic camera: cables drawn as shaded tubes of a given colour and
//! diameter over plain or cluttered backgrounds, with crossings, lighting
//! changes and sensor noise, and the fiducial marker on the finger, with
//! exact masks and centre lines as ground truth. It is the simulated
//! camera's image of the simulated world (`render_world`), the vision
//! network's training data (`write_dataset`, in the layout of the
//! cables-dev data set) and the vision tests' scenes (`tests/common/scenes.rs`).
//!
//! Drawing happens in floating point: background, then the cables in
//! order (a later cable over an earlier one, so crossings occlude; each
//! cable's mask is its whole tube, so masks overlap at crossings as in
//! cables-dev), then the marker, then the lighting, optical blur and
//! sensor noise, and finally 8-bit rounding. Every random choice comes from
//! the caller's generator, so a seed fixes the image. What lies in front of
//! the cables (a board over a stretch of the simulated cable, the arm's
//! hand) is drawn over them before the marker, and the ground truth says
//! what of each cable it left visible.

mod background;
mod dataset;
mod hand;
mod marker;
mod occluder;
mod pasted;
mod random;
mod tube;
mod world_view;

use marker::draw_marker;

use std::path::PathBuf;

use opencv::aruco::PREDEFINED_DICTIONARY_NAME;
use opencv::core::{self, Mat, Scalar, Size, Vec3f};
use opencv::imgproc;
use opencv::prelude::*;
use rand::{Rng, RngExt};

pub use dataset::{Cables, dataset_scene, pasted_scene, write_dataset, write_scene_files};
pub use occluder::{Board, OccluderSpec, Occlusion};
pub use pasted::LabelledPhotograph;
pub use random::{BackgroundChoice, SceneOptions, random_scene};
pub use world_view::render_world;

use crate::perception::vision::paths::polyline_length;

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
    /// A drip painting like the Pollock print of the paper's Fig. 1:
    /// layers of poured lines, brushed strokes and splatters in many
    /// colours and widths over a canvas. The strokes are as long and wide
    /// as cables but flat, not shaded like a tube.
    Pollock,
    /// A printed mosaic: tiles of many strong colours (a Voronoi tiling)
    /// with grout lines between them.
    Mosaic,
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
    /// Length of the bare metal (a ferrule or stripped strands) at each
    /// end of the centre line; 0 for none. It is part of the cable's mask.
    pub metal_end_px: f64,
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
    /// Opaque things in front of the cables, drawn over them in order.
    pub occluders: Vec<OccluderSpec>,
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
    /// Each cable's mask less the pixels whose centre an occluder or the
    /// marker covers: what the camera sees of it.
    pub visible_masks: Vec<Mat>,
    /// The stretches of each cable's centre line (as in `centerlines_px`)
    /// that no occluder and not the marker covers, in order along it.
    pub visible_centerlines_px: Vec<Vec<Vec<[f64; 2]>>>,
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
    pub occlusion: Occlusion,
}

impl Default for Appearance {
    /// A dark red cable in front of a light gray wall, a little sensor
    /// noise and blur, nothing in front of it, as a lab camera sees it.
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
            occlusion: Occlusion::default(),
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
    /// An occluder cannot be drawn: fewer than three corners, or a corner
    /// or its texture not finite.
    #[error("occluder {index} cannot be drawn: {reason}")]
    BadOccluder { index: usize, reason: &'static str },
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
    for (index, occluder) in scene.occluders.iter().enumerate() {
        occluder::check(index, occluder)?;
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
    occluder::draw_all(&mut image, &scene.occluders)?;
    let marker_px = scene
        .marker
        .as_ref()
        .map(|marker| draw_marker(&mut image, marker))
        .transpose()?;
    // What covers the cables: the occluders, and the marker's plate.
    let covers: Vec<&[[f64; 2]]> = scene
        .occluders
        .iter()
        .map(|occluder| occluder.outline_px.as_slice())
        .chain(marker_px.as_ref().map(|outline| outline.as_slice()))
        .collect();
    let hidden = occluder::covered_pixels(width, height, &covers)?;
    let visible_masks = masks
        .iter()
        .map(|mask| {
            let mut visible = Mat::default();
            core::subtract(mask, &hidden, &mut visible, &core::no_array(), -1).map(|()| visible)
        })
        .collect::<Result<_, _>>()
        .map_err(cv("take the hidden pixels off the masks"))?;
    let visible_centerlines_px = centerlines_px
        .iter()
        .map(|line| occluder::visible_stretches(line, &covers))
        .collect();
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

    let union_mask = unite(&masks, width, height)?;
    Ok(RenderedScene {
        bgr,
        masks,
        union_mask,
        centerlines_px,
        visible_masks,
        visible_centerlines_px,
    })
}

/// The union of CV_8UC1 `masks` of `width` × `height` (all 0 for none).
fn unite(masks: &[Mat], width: i32, height: i32) -> Result<Mat, RenderError> {
    let mut union_mask = Mat::new_rows_cols_with_default(height, width, core::CV_8UC1, 0.into())
        .map_err(cv("allocate the union mask"))?;
    for mask in masks {
        let mut next = Mat::default();
        core::bitwise_or(&union_mask, mask, &mut next, &core::no_array())
            .map_err(cv("unite the masks"))?;
        union_mask = next;
    }
    Ok(union_mask)
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
    stretches_in_image(points, width, height)
        .into_iter()
        .max_by(|a, b| polyline_length(a).total_cmp(&polyline_length(b)))
        .unwrap_or_default()
}

/// Each stretch of `points` inside the image (pixel centres from 0 to
/// size − 1), in order along them, cut where they cross the border.
fn stretches_in_image(points: &[[f64; 2]], width: i32, height: i32) -> Vec<Vec<[f64; 2]>> {
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
    runs
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

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::dataset::resample;
    use super::*;

    #[test]
    fn clipping_finds_each_stretch_inside_keeps_the_longest_and_cuts_at_the_border() {
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
        assert_eq!(
            stretches_in_image(&points, 100, 20),
            vec![
                vec![[10.0, 5.0], [10.0, 0.0]],
                vec![[30.0, 0.0], [30.0, 5.0], [90.0, 5.0]]
            ]
        );
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
            occluders: Vec::new(),
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
            metal_end_px: 0.0,
        });
        assert!(matches!(
            render(&scene, &mut rng),
            Err(RenderError::BadCable { index: 0, .. })
        ));
    }
}
