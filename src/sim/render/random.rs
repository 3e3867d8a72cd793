//! Random scenes for training and tests: cables as smooth random curves
//! (their bend limited so that the tube stays a tube), entering from the
//! image's border or lying loose, in typical wire colours, over a random
//! background under random light.

use std::f64::consts::{PI, TAU};

use rand::{Rng, RngExt};
use rand_distr::{Distribution, StandardNormal};

use super::occluder::{Board, OccluderSpec, board_over};
use super::{Background, CableSpec, Light, SceneSpec, clip_to_image, unit};

/// Which backgrounds a random scene may have.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BackgroundChoice {
    /// Flat colours and smooth gradients: what a classical threshold
    /// segments.
    Plain,
    /// Noise, stripes, checkers, wood, print and sheets: what needs the
    /// network.
    Cluttered,
    /// Either, cluttered more often.
    Any,
    /// The paper's kind of scene: drip paintings, mosaics and print, the
    /// cables with bare metal at their ends.
    Busy,
    /// The simulated cell's kind of scene: cables over a wooden
    /// workbench, a board lying over a stretch of one of them in half the
    /// images.
    Workbench,
    /// Tubes on a dark background: black cloth or a dark table, plain
    /// under a light's falloff.
    Dark,
}

/// What random scenes may hold.
#[derive(Clone, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneOptions {
    pub width_px: i32,
    pub height_px: i32,
    /// The number of cables is drawn from `min_cables..=max_cables`.
    pub min_cables: usize,
    pub max_cables: usize,
    pub backgrounds: BackgroundChoice,
    /// Whether cables may cross. When they may not, a cable that would is
    /// drawn again, and left out after a few tries.
    pub crossings: bool,
    /// Cable diameters are drawn from this range.
    pub min_diameter_px: f64,
    pub max_diameter_px: f64,
}

impl Default for SceneOptions {
    /// cables-dev's image size and cable widths, one to four cables over
    /// any background, crossings allowed.
    fn default() -> Self {
        Self {
            width_px: 640,
            height_px: 480,
            min_cables: 1,
            max_cables: 4,
            backgrounds: BackgroundChoice::Any,
            crossings: true,
            min_diameter_px: 6.0,
            max_diameter_px: 16.0,
        }
    }
}

/// The backgrounds a cluttered scene draws from.
const CLUTTERED: [Background; 6] = [
    Background::Noise,
    Background::Stripes,
    Background::Checker,
    Background::Wood,
    Background::Printed,
    Background::Sheets,
];

/// The backgrounds a busy scene draws from, drip paintings most often.
const BUSY: [Background; 4] = [
    Background::Pollock,
    Background::Pollock,
    Background::Mosaic,
    Background::Printed,
];

/// In a busy scene, the share of cables with bare metal ends, and how
/// long the metal is, in diameters.
const METAL_END_SHARE: f64 = 0.7;
const METAL_END_DIAMETERS: std::ops::Range<f64> = 1.0..3.5;

/// Typical wire insulation colours (BGR): black, white, red, blue, green,
/// yellow, orange, brown, gray, violet, light blue.
const WIRE_COLOURS: [[u8; 3]; 11] = [
    [30, 30, 30],
    [225, 225, 225],
    [40, 40, 200],
    [170, 80, 30],
    [60, 150, 40],
    [40, 200, 220],
    [30, 120, 240],
    [40, 70, 120],
    [130, 130, 130],
    [140, 50, 120],
    [220, 170, 90],
];

/// On a plain background a cable's colour differs from it at least this
/// much (Euclidean, gray levels), as a camera set up for one would ensure.
const MIN_PLAIN_CONTRAST: f64 = 70.0;

/// Tries to place one cable before leaving it out.
const PLACEMENT_TRIES: usize = 20;

/// Steps along a random curve (pixels).
const STEP_PX: f64 = 1.0;

/// A random scene within `options`.
pub fn random_scene(rng: &mut impl Rng, options: &SceneOptions) -> SceneSpec {
    let (width, height) = (options.width_px, options.height_px);
    let background = match options.backgrounds {
        BackgroundChoice::Plain => plain_background(rng),
        BackgroundChoice::Cluttered => cluttered_background(rng),
        BackgroundChoice::Any if rng.random_bool(0.35) => plain_background(rng),
        BackgroundChoice::Any => cluttered_background(rng),
        BackgroundChoice::Busy => BUSY[rng.random_range(0..BUSY.len())].clone(),
        BackgroundChoice::Workbench => Background::Wood,
        BackgroundChoice::Dark => dark_background(rng),
    };
    let busy = options.backgrounds == BackgroundChoice::Busy;

    let low = options.min_cables.min(options.max_cables);
    let high = options.min_cables.max(options.max_cables);
    let count = rng.random_range(low..=high);
    let low_d = options
        .min_diameter_px
        .min(options.max_diameter_px)
        .max(1.0);
    let high_d = options.max_diameter_px.max(low_d);
    let mut cables: Vec<CableSpec> = Vec::with_capacity(count);
    for _ in 0..count {
        for _ in 0..PLACEMENT_TRIES {
            let diameter_px = rng.random_range(low_d..=high_d);
            let Some(centerline_px) = random_curve(rng, width, height, diameter_px / 2.0) else {
                continue;
            };
            let metal_end_px = if busy && rng.random_bool(METAL_END_SHARE) {
                diameter_px * rng.random_range(METAL_END_DIAMETERS)
            } else {
                0.0
            };
            let candidate = CableSpec {
                centerline_px,
                diameter_px,
                bgr: wire_colour(rng, &background),
                gloss: rng.random_range(0.0..0.6),
                metal_end_px,
            };
            if options.crossings || cables.iter().all(|other| apart(&candidate, other)) {
                cables.push(candidate);
                break;
            }
        }
    }

    let occluders = if options.backgrounds == BackgroundChoice::Workbench {
        board_over_a_cable(rng, &cables, width, height)
    } else {
        Vec::new()
    };

    // Light from the camera's side, up to 65° off its axis.
    let off_axis = rng.random_range(0.2..1.13_f64);
    let azimuth = rng.random_range(0.0..TAU);
    let toward_light = unit([
        off_axis.sin() * azimuth.cos(),
        off_axis.sin() * azimuth.sin(),
        off_axis.cos(),
    ]);
    SceneSpec {
        width_px: width,
        height_px: height,
        background,
        cables,
        light: Light {
            toward_light,
            gain: rng.random_range(0.65..1.25),
            gradient: rng.random_range(0.0..0.35),
            gradient_angle_rad: rng.random_range(0.0..TAU),
            shadow: rng.random_range(0.05..0.4),
        },
        noise_sigma: rng.random_range(0.5..6.0),
        blur_sigma_px: rng.random_range(0.0..1.0),
        occluders,
        marker: None,
    }
}

/// In a workbench scene, the share of images with a board over a stretch
/// of a cable, and the share of that cable's length in view it hides.
const BOARD_SHARE: f64 = 0.5;
const BOARD_HIDDEN: std::ops::Range<f64> = 0.1..0.6;

/// A board over a stretch of one of `cables`, in [`BOARD_SHARE`] of the
/// calls: the simulated cell's occluder, so that the network learns that a
/// cable ends at a board's edge and that the edge is none.
fn board_over_a_cable(
    rng: &mut impl Rng,
    cables: &[CableSpec],
    width: i32,
    height: i32,
) -> Vec<OccluderSpec> {
    if cables.is_empty() || !rng.random_bool(BOARD_SHARE) {
        return Vec::new();
    }
    let cable = &cables[rng.random_range(0..cables.len())];
    let board = Board {
        hidden_fraction: rng.random_range(BOARD_HIDDEN),
        position: rng.random_range(0.0..=1.0),
        bgr: near_grey(rng),
        texture_seed: rng.random(),
    };
    let seen_px = clip_to_image(&cable.centerline_px, width, height);
    board_over(&seen_px, cable.diameter_px / 2.0, &board)
        .into_iter()
        .collect()
}

/// A board's colour: cardboard, pressboard or painted wood, pale or dark.
fn near_grey(rng: &mut impl Rng) -> [u8; 3] {
    let level = rng.random_range(60.0..230.0);
    let warmth = rng.random_range(0.0..40.0);
    [level - warmth, level, level + warmth / 2.0].map(|c: f64| c.clamp(0.0, 255.0) as u8)
}

fn plain_background(rng: &mut impl Rng) -> Background {
    if rng.random_bool(0.25) {
        return Background::Gradient;
    }
    tinted_plain(rng, 80.0..245.0, 20.0)
}

/// Black cloth or a dark table: darker than [`plain_background`]'s
/// darkest.
fn dark_background(rng: &mut impl Rng) -> Background {
    tinted_plain(rng, 5.0..55.0, 10.0)
}

/// A flat colour: a gray level drawn from `levels`, each channel off it
/// by up to a tint drawn below `max_tint`.
fn tinted_plain(rng: &mut impl Rng, levels: std::ops::Range<f64>, max_tint: f64) -> Background {
    let level: f64 = rng.random_range(levels);
    let tint: f64 = rng.random_range(0.0..max_tint);
    let bgr = [0; 3].map(|_| (level + rng.random_range(-tint..=tint)).clamp(0.0, 255.0) as u8);
    Background::Plain { bgr }
}

fn cluttered_background(rng: &mut impl Rng) -> Background {
    CLUTTERED[rng.random_range(0..CLUTTERED.len())].clone()
}

/// A wire colour, jittered; on a plain background one that stands out.
fn wire_colour(rng: &mut impl Rng, background: &Background) -> [u8; 3] {
    let mut pick = || {
        let base = WIRE_COLOURS[rng.random_range(0..WIRE_COLOURS.len())];
        base.map(|c| (f64::from(c) + rng.random_range(-20.0..=20.0)).clamp(0.0, 255.0) as u8)
    };
    let Background::Plain { bgr: paper } = background else {
        return pick();
    };
    let contrast = |c: &[u8; 3]| {
        (0..3)
            .map(|i| (f64::from(c[i]) - f64::from(paper[i])).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let mut best = pick();
    for _ in 0..PLACEMENT_TRIES {
        if contrast(&best) >= MIN_PLAIN_CONTRAST {
            break;
        }
        let next = pick();
        if contrast(&next) > contrast(&best) {
            best = next;
        }
    }
    best
}

/// Whether two cables keep clear of each other (centre lines more than
/// their radii and a gap apart), checked every few pixels.
fn apart(a: &CableSpec, b: &CableSpec) -> bool {
    const EVERY: usize = 3;
    let clearance = (a.diameter_px + b.diameter_px) / 2.0 + 3.0 + EVERY as f64;
    a.centerline_px.iter().step_by(EVERY).all(|p| {
        b.centerline_px
            .iter()
            .step_by(EVERY)
            .all(|q| (p[0] - q[0]).hypot(p[1] - q[1]) > clearance)
    })
}

/// How much of a cable is in view, at least, as a share of the image's
/// diagonal: less is a sliver at the border, not a cable to find.
pub(super) const MIN_IN_VIEW_DIAGONALS: f64 = 0.1;

/// A smooth random curve a pixel a step: the heading turns by a curvature
/// that wanders (mean-reverting) within a bound set by the radius, so the
/// curve bends like a wire and never tighter than a few diameters. It
/// starts beyond the border (most often) or inside, and stops at its length
/// or once it has left the image (going on straight until its tube is out
/// too, so that it never comes back in). `None` if too
/// little of it lies inside.
fn random_curve(rng: &mut impl Rng, width: i32, height: i32, radius: f64) -> Option<Vec<[f64; 2]>> {
    let (w, h) = (f64::from(width), f64::from(height));
    let margin = radius + 2.0;
    let (mut x, mut y, mut heading) = if rng.random_bool(0.75) {
        let inward = rng.random_range(-1.0..1.0);
        match rng.random_range(0..4) {
            0 => (-margin, rng.random_range(0.0..h), inward),
            1 => (w - 1.0 + margin, rng.random_range(0.0..h), PI + inward),
            2 => (rng.random_range(0.0..w), -margin, PI / 2.0 + inward),
            _ => (
                rng.random_range(0.0..w),
                h - 1.0 + margin,
                -PI / 2.0 + inward,
            ),
        }
    } else {
        (
            rng.random_range(0.1 * w..0.9 * w),
            rng.random_range(0.1 * h..0.9 * h),
            rng.random_range(0.0..TAU),
        )
    };
    let diagonal = w.hypot(h);
    let length = rng.random_range(0.3..1.5) * diagonal;
    let max_curvature = 1.0 / (6.0 * radius).max(50.0);
    let wander = max_curvature * rng.random_range(0.03..0.12);
    let mut curvature = 0.0_f64;

    let outside_by = |x: f64, y: f64| {
        let dx = (-x).max(x - (w - 1.0)).max(0.0);
        let dy = (-y).max(y - (h - 1.0)).max(0.0);
        dx.max(dy)
    };
    let mut points = vec![[x, y]];
    let mut inside_px = 0.0;
    let mut travelled = 0.0;
    let mut leaving = false;
    while travelled < length {
        let kick: f64 = StandardNormal.sample(rng);
        curvature = (curvature * 0.99 + wander * kick).clamp(-max_curvature, max_curvature);
        if !leaving {
            heading += curvature * STEP_PX;
        }
        x += STEP_PX * heading.cos();
        y += STEP_PX * heading.sin();
        travelled += STEP_PX;
        points.push([x, y]);
        let out = outside_by(x, y);
        if out == 0.0 {
            inside_px += STEP_PX;
        } else if inside_px > 0.0 {
            // Once out, straight on: it never comes back in, and its tube
            // leaves the image whole.
            leaving = true;
            if out > margin {
                break;
            }
        } else if inside_px == 0.0 && out > diagonal / 4.0 {
            // Started off the border, heading away.
            return None;
        }
    }
    (inside_px >= MIN_IN_VIEW_DIAGONALS * diagonal).then_some(points)
}
