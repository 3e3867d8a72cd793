//! Scenes with known answers for the vision pipeline's tests and
//! benchmarks (`benches/vision.rs` includes this file): cables along given curves (arcs, segments) on a given
//! background, drawn by the renderer in even light without blur.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use cablecell::perception::vision::curves::{arc_px, segment_px};
use cablecell::sim::render::{
    Background, CableSpec, Light, RenderError, RenderedScene, SceneSpec, render,
};

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

/// A matte cable of `diameter_px` along `centerline_px`.
pub fn matte_cable(centerline_px: Vec<[f64; 2]>, diameter_px: f64, bgr: [u8; 3]) -> CableSpec {
    CableSpec {
        centerline_px,
        diameter_px,
        bgr,
        gloss: 0.0,
        metal_end_px: 0.0,
    }
}

/// Draws `cables` in order (later ones on top) on `background`, an image
/// of `height_px` rows and `width_px` columns with sensor noise of
/// `noise_sigma` gray levels; `seed` fixes the background's and the
/// noise's random draws.
pub fn draw_scene(
    height_px: i32,
    width_px: i32,
    background: Background,
    noise_sigma: f64,
    cables: Vec<CableSpec>,
    seed: u64,
) -> Result<RenderedScene, RenderError> {
    let spec = SceneSpec {
        width_px,
        height_px,
        background,
        cables,
        light: Light::default(),
        noise_sigma,
        blur_sigma_px: 0.0,
        occluders: Vec::new(),
        marker: None,
    };
    render(&spec, &mut ChaCha8Rng::seed_from_u64(seed))
}

/// The vision benchmark's scene: 640×480, three cables (two crossing)
/// on a noisy light table.
pub fn demo_scene(seed: u64) -> Result<RenderedScene, RenderError> {
    let cables = vec![
        matte_cable(
            arc_px([320.0, 520.0], 330.0, -2.6, -0.55),
            8.0,
            [40, 40, 40],
        ),
        matte_cable(
            segment_px([120.0, 80.0], [540.0, 400.0]),
            8.0,
            [180, 60, 30],
        ),
        matte_cable(arc_px([330.0, 200.0], 150.0, 2.2, 3.9), 7.0, [30, 30, 200]),
    ];
    draw_scene(
        480,
        640,
        Background::Plain { bgr: [215; 3] },
        4.0,
        cables,
        seed,
    )
}
