//! Synthetic camera images of cables with known centrelines: the vision
//! pipeline's own fixtures (tests, benchmarks, the CLI's demo), drawn with
//! OpenCV so that no photograph needs to ship with the project.

use opencv::core::{Mat, Point, Scalar, Vector};
use opencv::imgproc;
use opencv::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::error::{VisionError, cv};

/// What the cables lie on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Background {
    /// One flat gray level (0–255).
    Plain { gray: f64 },
    /// A flat gray level with Gaussian sensor noise of `sigma` gray levels.
    Noisy { gray: f64, sigma: f64 },
    /// Wood-like: wavy light and dark bands with noise, so the colour-
    /// distance test finds no plain background.
    Textured,
}

/// A cable to draw: its centreline, colour (BGR) and width.
#[derive(Clone, Debug, PartialEq)]
pub struct SyntheticCable {
    pub centreline_px: Vec<[f64; 2]>,
    pub bgr: [f64; 3],
    pub width_px: i32,
}

/// A synthetic image and the cables drawn in it.
#[derive(Debug)]
pub struct SyntheticScene {
    /// CV_8UC3 BGR.
    pub image: Mat,
    pub cables: Vec<SyntheticCable>,
}

/// Points along a circular arc, every pixel or so: centre, radius, start
/// and end angle (radians, image coordinates: y down).
pub fn arc_px(centre: [f64; 2], radius_px: f64, from_rad: f64, to_rad: f64) -> Vec<[f64; 2]> {
    let steps = ((to_rad - from_rad).abs() * radius_px).ceil().max(1.0) as usize;
    (0..=steps)
        .map(|i| {
            let t = from_rad + (to_rad - from_rad) * i as f64 / steps as f64;
            [
                centre[0] + radius_px * t.cos(),
                centre[1] + radius_px * t.sin(),
            ]
        })
        .collect()
}

/// Points along a line segment, every pixel or so.
pub fn segment_px(from: [f64; 2], to: [f64; 2]) -> Vec<[f64; 2]> {
    let steps = (to[0] - from[0]).hypot(to[1] - from[1]).ceil().max(1.0) as usize;
    (0..=steps)
        .map(|i| {
            let t = i as f64 / steps as f64;
            [
                from[0] + t * (to[0] - from[0]),
                from[1] + t * (to[1] - from[1]),
            ]
        })
        .collect()
}

/// The point halfway along a polyline's length.
pub fn midpoint_px(points: &[[f64; 2]]) -> Option<[f64; 2]> {
    let lengths: Vec<f64> = points
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .collect();
    let half = lengths.iter().sum::<f64>() / 2.0;
    let mut acc = 0.0;
    for (w, l) in points.windows(2).zip(&lengths) {
        if acc + l >= half && *l > 0.0 {
            let t = (half - acc) / l;
            return Some([
                w[0][0] + t * (w[1][0] - w[0][0]),
                w[0][1] + t * (w[1][1] - w[0][1]),
            ]);
        }
        acc += l;
    }
    points.first().copied()
}

fn background(
    rows: i32,
    cols: i32,
    kind: Background,
    rng: &mut ChaCha8Rng,
) -> Result<Mat, VisionError> {
    let mut pixels = Vec::with_capacity(usize::try_from(rows * cols * 3).unwrap_or(0));
    let phase: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    for y in 0..rows {
        for x in 0..cols {
            let (xf, yf) = (f64::from(x), f64::from(y));
            let bgr = match kind {
                Background::Plain { gray } => [gray; 3],
                Background::Noisy { gray, sigma } => {
                    let n = sigma * gaussian(rng);
                    [gray + n; 3]
                }
                Background::Textured => {
                    let band = (yf / 9.0 + 3.0 * (xf / 70.0 + phase).sin()).sin();
                    let grain = 10.0 * gaussian(rng);
                    let v = 150.0 + 60.0 * band + grain;
                    [v * 0.55, v * 0.8, v]
                }
            };
            pixels.extend(bgr.map(|v| v.round().clamp(0.0, 255.0) as u8));
        }
    }
    let flat = Mat::new_rows_cols_with_data(rows, cols * 3, &pixels)
        .and_then(|m| m.try_clone())
        .map_err(cv("synthetic background"))?;
    flat.reshape(3, rows)
        .and_then(|m| m.try_clone())
        .map_err(cv("synthetic background channels"))
}

/// A standard normal draw (Box–Muller).
fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let u: f64 = rng.random_range(f64::EPSILON..1.0);
    let v: f64 = rng.random_range(0.0..1.0);
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// Draws `cables` in order (later ones on top) on a `cols`×`rows`
/// background; `seed` fixes the noise.
pub fn draw_scene(
    rows: i32,
    cols: i32,
    kind: Background,
    cables: Vec<SyntheticCable>,
    seed: u64,
) -> Result<SyntheticScene, VisionError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut image = background(rows, cols, kind, &mut rng)?;
    for cable in &cables {
        let pts: Vector<Point> = cable
            .centreline_px
            .iter()
            .map(|p| Point::new(p[0].round() as i32, p[1].round() as i32))
            .collect();
        let mut contours = Vector::<Vector<Point>>::new();
        contours.push(pts);
        let [b, g, r] = cable.bgr;
        imgproc::polylines(
            &mut image,
            &contours,
            false,
            Scalar::new(b, g, r, 0.0),
            cable.width_px,
            imgproc::LINE_AA,
            0,
        )
        .map_err(cv("draw synthetic cable"))?;
    }
    Ok(SyntheticScene { image, cables })
}

/// The benchmark's and demo's scene: 640×480, three cables (two crossing)
/// on a noisy light table.
pub fn demo_scene(seed: u64) -> Result<SyntheticScene, VisionError> {
    let cables = vec![
        SyntheticCable {
            centreline_px: arc_px([320.0, 520.0], 330.0, -2.6, -0.55),
            bgr: [40.0, 40.0, 40.0],
            width_px: 8,
        },
        SyntheticCable {
            centreline_px: segment_px([120.0, 80.0], [540.0, 400.0]),
            bgr: [180.0, 60.0, 30.0],
            width_px: 8,
        },
        SyntheticCable {
            centreline_px: arc_px([330.0, 200.0], 150.0, 2.2, 3.9),
            bgr: [30.0, 30.0, 200.0],
            width_px: 7,
        },
    ];
    draw_scene(
        480,
        640,
        Background::Noisy {
            gray: 215.0,
            sigma: 4.0,
        },
        cables,
        seed,
    )
}
