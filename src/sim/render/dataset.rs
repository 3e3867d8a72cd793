//! Writing rendered scenes as a data set in the cables-dev layout: the
//! vision network's training data and the vision tests' scenes.

use std::fmt::Write as _;
use std::path::Path;

use opencv::core::{Mat, Vector};
use opencv::imgcodecs;
use opencv::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::pasted::{LabelledPhotograph, Placement, paste_cables};
use super::{RenderError, RenderedScene, SceneOptions, cv, random_scene, render, unite};

/// JPEG quality of a data set's images: high enough to keep thin cables,
/// low enough to leave the compression's artefacts a real camera's
/// pipeline leaves.
const JPEG_QUALITY: i32 = 92;

/// Spacing of the points written to a data set's polylines, which hold
/// spline control points in cables-dev rather than every pixel.
const POLYLINE_SPACING_PX: f64 = 6.0;

/// Where a data set's cables come from.
#[derive(Clone, Copy)]
pub enum Cables<'a> {
    /// Drawn as shaded tubes ([`dataset_scene`]).
    Rendered,
    /// Cut out of labelled photographs, image i holding photograph i's
    /// (modulo their number) over a background ([`pasted_scene`]); with
    /// `cast_shadows`, the cables cast their shadows on it.
    Pasted {
        photos: &'a [LabelledPhotograph<'a>],
        cast_shadows: bool,
    },
}

/// Writes `count` random scenes into `dir` in the cables-dev layout: per
/// image `NNNNN.jpg`, `NNNNN_mask_K.png` (0/255, one per cable, K from 0),
/// `NNNNN_mask_all.png` and `NNNNN.txt` (line K: `N x0 y0 x1 y1 ...`, the
/// K-th cable's centre line, integer pixels as in cables-dev). Image i is
/// drawn from stream i of a generator seeded with `seed`, so it does not
/// depend on `count`. `written` is called after each image (a progress
/// bar's tick).
pub fn write_dataset(
    dir: &Path,
    count: usize,
    seed: u64,
    options: &SceneOptions,
    cables: Cables,
    mut written: impl FnMut(),
) -> Result<(), RenderError> {
    std::fs::create_dir_all(dir).map_err(|source| RenderError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    for index in 0..count {
        let rendered = match cables {
            Cables::Pasted {
                photos,
                cast_shadows,
            } if !photos.is_empty() => pasted_scene(
                seed,
                index as u64,
                options,
                &photos[index % photos.len()],
                cast_shadows,
            )?,
            _ => dataset_scene(seed, index as u64, options)?,
        };
        write_scene_files(dir, &format!("{index:05}"), &rendered)?;
        written();
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
    let mut rng = stream(seed, index);
    let scene = random_scene(&mut rng, options);
    render(&scene, &mut rng)
}

/// Image `index` of a data set of `photo`'s cables over rendered
/// backgrounds: the background [`dataset_scene`] draws for `options` less
/// its cables, the photograph laid over it in a placement drawn from the
/// same stream ([`Placement::random`]). With `cast_shadows`, the cables
/// cast their shadows under the background's light, which draws nothing
/// more from the stream: the same scene, shadows added.
pub fn pasted_scene(
    seed: u64,
    index: u64,
    options: &SceneOptions,
    photo: &LabelledPhotograph,
    cast_shadows: bool,
) -> Result<RenderedScene, RenderError> {
    let mut rng = stream(seed, index);
    let no_cables = SceneOptions {
        min_cables: 0,
        max_cables: 0,
        ..options.clone()
    };
    let spec = random_scene(&mut rng, &no_cables);
    let background = render(&spec, &mut rng)?;
    let placement = Placement::random(&mut rng, options.width_px, options.height_px);
    let shadow_light = cast_shadows.then_some(&spec.light);
    paste_cables(&background.bgr, photo, &placement, shadow_light)
}

/// Stream `index` of a generator seeded with `seed`: image `index`'s draws.
fn stream(seed: u64, index: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index);
    rng
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
    // What the camera sees of each cable: a board over a stretch of one
    // hides it from the labels as from the image.
    for (k, mask) in rendered.visible_masks.iter().enumerate() {
        write_image(&dir.join(format!("{stem}_mask_{k}.png")), mask, &[])?;
    }
    let (width, height) = (rendered.bgr.cols(), rendered.bgr.rows());
    let union_mask = unite(&rendered.visible_masks, width, height)?;
    write_image(&dir.join(format!("{stem}_mask_all.png")), &union_mask, &[])?;
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
pub(super) fn resample(points: &[[f64; 2]], spacing_px: f64) -> Vec<[f64; 2]> {
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
