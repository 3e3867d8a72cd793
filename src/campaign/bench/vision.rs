//! The vision pipeline's settings on labelled images: the network's
//! input size, the mask method and the instance method, each one's error
//! against the labels (union DICE, cables counted right, grasp-point
//! error) against its time, with the Pareto front; and the skips a plain
//! background allows (the network, the work outside a region of interest)
//! with and without them, so that the time they save shows beside the
//! error they keep.
//!
//! The images are rendered in memory from a fixed seed, with exact masks
//! and centre lines (what `render-dataset` writes, before its JPEG), so
//! the bench needs no files; photographs with their labels are scored
//! alike when a folder is given.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use opencv::core::{Mat, Rect};
use opencv::imgproc;
use schemars::JsonSchema;
use serde::Serialize;

use super::{StageLatency, mean, pareto_front};
use crate::campaign::stats::Summary;
use crate::hw::camera::{ImageError, read_image};
use crate::perception::vision::eval::{GroundTruth, labelled_images, score, summarize};
use crate::perception::vision::network::{
    DEFAULT_BUSY_THRESHOLD, DEFAULT_INPUT_SCALE, DEFAULT_THRESHOLD, InputScales, LazyNetwork,
};
use crate::perception::vision::{
    InstanceMethod, MaskMethod, MaskNetwork, Pipeline, VisionConfig, VisionError, VisionSkip,
};
use crate::sim::render::{BackgroundChoice, RenderError, SceneOptions, dataset_scene};

/// Why the vision bench could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum VisionBenchError {
    /// The renderer failed on one of the bench's scenes (`source`: its
    /// error): a bug, since the scenes are fixed.
    #[error("cannot render the bench's image {index}: {source}")]
    Render {
        index: usize,
        #[source]
        source: RenderError,
    },
    /// The photographs' folder cannot be listed. Fix: name the folder of
    /// cables-dev (or any folder in its layout).
    #[error("{dir}: cannot list the folder: {source}")]
    List {
        dir: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The folder holds no labelled image. Fix: name a folder with
    /// `NNNNN.jpg` and `NNNNN_mask_all.png` beside it.
    #[error("{dir}: no NNNNN.jpg images with NNNNN_mask_all.png beside them")]
    NoImages { dir: PathBuf },
    /// A photograph cannot be read (`source` names it and says why).
    #[error(transparent)]
    Image(Box<ImageError>),
    /// A photograph's labels are missing or malformed, or not its size.
    #[error("{dir}: {stem}: {source}")]
    Truth {
        dir: PathBuf,
        stem: String,
        #[source]
        source: Box<VisionError>,
    },
    /// The pipeline failed on an image (`source`: why; a missing network
    /// or ONNX Runtime fails every image alike: run `scripts/setup`).
    #[error("{setting}: {image}: {source}")]
    Pipeline {
        setting: String,
        image: String,
        #[source]
        source: Box<VisionError>,
    },
}

/// An image and its labels.
pub struct LabelledImage {
    pub name: String,
    pub image: Mat,
    pub truth: GroundTruth,
}

/// Images that settings are compared on, by name: each set has its own
/// Pareto front.
pub struct ImageSet {
    pub name: String,
    pub images: Vec<LabelledImage>,
}

/// `count` scenes of the renderer (640 × 480, one to four cables) on
/// `backgrounds`, image i from stream i of `seed` as `render-dataset`
/// draws them, with their exact masks and centre lines as labels.
pub fn rendered_set(
    name: &str,
    count: usize,
    seed: u64,
    backgrounds: BackgroundChoice,
) -> Result<ImageSet, VisionBenchError> {
    let options = SceneOptions {
        backgrounds,
        ..SceneOptions::default()
    };
    let images = (0..count)
        .map(|index| {
            let rendered = dataset_scene(seed, index as u64, &options)
                .map_err(|source| VisionBenchError::Render { index, source })?;
            Ok(LabelledImage {
                name: format!("{index:05}"),
                image: rendered.bgr,
                truth: GroundTruth {
                    masks: rendered.masks,
                    union_mask: rendered.union_mask,
                    polylines_px: rendered.centerlines_px,
                },
            })
        })
        .collect::<Result<_, VisionBenchError>>()?;
    Ok(ImageSet {
        name: name.to_owned(),
        images,
    })
}

/// Every labelled photograph of `dir` (cables-dev's layout), sorted.
pub fn photographs(dir: &Path) -> Result<ImageSet, VisionBenchError> {
    let list = labelled_images(dir).map_err(|source| VisionBenchError::List {
        dir: dir.to_path_buf(),
        source,
    })?;
    if list.is_empty() {
        return Err(VisionBenchError::NoImages {
            dir: dir.to_path_buf(),
        });
    }
    let images = list
        .into_iter()
        .map(|(stem, path)| {
            let image = read_image(&path).map_err(|e| VisionBenchError::Image(Box::new(e)))?;
            let truth = GroundTruth::load(dir, &stem)
                .and_then(|truth| truth.check_fits(&image, &path, dir, &stem).map(|()| truth))
                .map_err(|source| VisionBenchError::Truth {
                    dir: dir.to_path_buf(),
                    stem: stem.clone(),
                    source: Box::new(source),
                })?;
            Ok(LabelledImage {
                name: stem,
                image,
                truth,
            })
        })
        .collect::<Result<_, VisionBenchError>>()?;
    Ok(ImageSet {
        name: format!("photographs ({})", dir.display()),
        images,
    })
}

/// One way of running the pipeline.
#[derive(Clone, Debug)]
pub struct VisionSetting {
    /// What it varies: "mask", "input size", "instances", "skip".
    pub group: &'static str,
    pub name: String,
    pub config: VisionConfig,
    /// The network's input sides over the image's; `None`: no network
    /// given (the classical mask).
    pub input_scales: Option<InputScales>,
    /// Work only on a region around the labelled cables (see
    /// [`roi_around_cables`]).
    pub roi_around_cables: bool,
}

impl VisionSetting {
    fn new(
        group: &'static str,
        name: String,
        mask: MaskMethod,
        input_scales: Option<InputScales>,
    ) -> Self {
        VisionSetting {
            group,
            name,
            config: VisionConfig {
                mask,
                ..VisionConfig::default()
            },
            input_scales,
            roi_around_cables: false,
        }
    }
}

/// How the row of cablecell's default settings begins, for the report
/// to find its stages.
pub const DEFAULT_SETTING: &str = "cablecell's default";

/// The settings compared on every image set: the classical mask, the
/// network at three input sizes (varied and dark backgrounds too), cablecell's
/// default (the network at its default sizes, larger on a varied or
/// dark background), and the paper's superpixels for the instances. Each
/// draws the cables' masks, which scoring needs (their stage is timed
/// but left out of the total: the cell's detector skips it).
pub fn vision_settings() -> Vec<VisionSetting> {
    let network = |scale: f64| format!("network at {scale}×");
    let mut settings = vec![VisionSetting::new(
        "mask",
        "classical, skeleton".to_owned(),
        MaskMethod::Classical,
        None,
    )];
    for scale in [0.25, DEFAULT_INPUT_SCALE, 0.5] {
        settings.push(VisionSetting::new(
            "input size",
            format!("{}, skeleton", network(scale)),
            MaskMethod::Network,
            Some(InputScales::fixed(scale)),
        ));
    }
    let defaults = InputScales::default();
    settings.push(VisionSetting::new(
        "mask",
        format!(
            "{DEFAULT_SETTING}: {}, {}× on a varied or dark background, {}× on paint, skeleton",
            network(defaults.normal),
            defaults.close,
            defaults.busy
        ),
        MaskMethod::Network,
        Some(defaults),
    ));
    let mut superpixels = VisionSetting::new(
        "instances",
        format!(
            "{}, superpixels (the paper's)",
            network(DEFAULT_INPUT_SCALE)
        ),
        MaskMethod::Network,
        Some(InputScales::fixed(DEFAULT_INPUT_SCALE)),
    );
    superpixels.config.instances = InstanceMethod::Superpixels;
    settings.push(superpixels);
    settings
}

/// The skips on a plain background, each with it taken and with it
/// forced off: `auto` (the network skipped where the classical mask is
/// not in doubt) against the default, the network on every image; and
/// the default on a region of interest around the cables (see
/// [`roi_around_cables`]) against the whole image.
pub fn skip_settings() -> Vec<VisionSetting> {
    let scale = Some(InputScales::default());
    let mut roi = VisionSetting::new(
        "skip",
        "the default on a region of interest around the cables: the image outside it skipped"
            .to_owned(),
        MaskMethod::Network,
        scale,
    );
    roi.roi_around_cables = true;
    vec![
        VisionSetting::new(
            "skip",
            "auto: the network skipped on a plain background".to_owned(),
            MaskMethod::Auto,
            scale,
        ),
        VisionSetting::new(
            "skip",
            "the default: the network on every image".to_owned(),
            MaskMethod::Network,
            scale,
        ),
        roi,
    ]
}

/// What one setting reached on one image set, and its time.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct VisionRow {
    /// The image set.
    pub images: String,
    pub group: String,
    pub setting: String,
    pub image_count: usize,
    /// Mean over the images of the found and labelled union masks' DICE.
    pub union_dice_mean: f64,
    /// The share of images with as many cables found as labelled.
    pub count_right_rate: f64,
    /// Mean over the images of the mean distance (px) from each found
    /// grasp point to the nearest labelled centre line.
    pub grasp_error_px_mean: Option<f64>,
    /// The pipeline's time per image (its stages but the cables' masks,
    /// which the cell's detector does not draw), median and 95th
    /// percentile.
    pub ms_median: Option<f64>,
    pub ms_p95: Option<f64>,
    /// Each stage of the pipeline (prepare, mask, instances, spline,
    /// instance_masks).
    pub stages: Vec<StageLatency>,
    /// Images on which each skip was taken, by skip.
    pub skipped: BTreeMap<String, usize>,
    /// Each image's time, error and skips, in the set's order.
    pub per_image: Vec<ImageResult>,
    /// No other row of the same image set is both faster (median) and
    /// closer (union DICE).
    pub front: bool,
}

/// One image's run of a setting.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ImageResult {
    pub image: String,
    /// As [`VisionRow::ms_median`] counts it.
    pub ms: f64,
    pub union_dice: f64,
    pub count_right: bool,
    pub skipped: Vec<String>,
}

/// A skip's time saved at equal error: on the images where a setting
/// took it, the setting against the same setting with the skip forced
/// off, image by image.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct SkipSaving {
    pub skip: String,
    /// The image set.
    pub images: String,
    /// Images on which the skip was taken.
    pub image_count: usize,
    /// Medians over those images of the time with and without the skip,
    /// and of the time saved.
    pub ms_with_median: f64,
    pub ms_without_median: f64,
    pub ms_saved_median: f64,
    /// Mean union DICE with and without it on those images.
    pub union_dice_with_mean: f64,
    pub union_dice_without_mean: f64,
    /// Those images' cables counted right, with and without it.
    pub count_right_with: usize,
    pub count_right_without: usize,
}

/// What `skip` saves: row `with` took it, row `without` is the same
/// pipeline with the skip forced off, on the same images. `None` when no
/// image took it.
pub fn skip_saving(skip: &str, with: &VisionRow, without: &VisionRow) -> Option<SkipSaving> {
    let pairs: Vec<(&ImageResult, &ImageResult)> = with
        .per_image
        .iter()
        .zip(&without.per_image)
        .filter(|(w, _)| w.skipped.iter().any(|s| s == skip))
        .collect();
    let median = |f: &dyn Fn(&(&ImageResult, &ImageResult)) -> f64| {
        Summary::of(&pairs.iter().map(f).collect::<Vec<_>>()).map(|s| s.median)
    };
    let count =
        |f: &dyn Fn(&(&ImageResult, &ImageResult)) -> bool| pairs.iter().filter(|p| f(p)).count();
    Some(SkipSaving {
        skip: skip.to_owned(),
        images: with.images.clone(),
        image_count: pairs.len(),
        ms_with_median: median(&|(w, _)| w.ms)?,
        ms_without_median: median(&|(_, o)| o.ms)?,
        ms_saved_median: median(&|(w, o)| o.ms - w.ms)?,
        union_dice_with_mean: mean(pairs.iter().map(|(w, _)| w.union_dice))?,
        union_dice_without_mean: mean(pairs.iter().map(|(_, o)| o.union_dice))?,
        count_right_with: count(&|(w, _)| w.count_right),
        count_right_without: count(&|(_, o)| o.count_right),
    })
}

/// A region of interest that holds every labelled cable of `truth` with
/// a margin: what a cell that knows where its cables lie (a fixture, a
/// tray) would set.
pub fn roi_around_cables(truth: &GroundTruth) -> Option<Rect> {
    const MARGIN_PX: i32 = 48;
    let r = imgproc::bounding_rect(&truth.union_mask).ok()?;
    (r.width > 0).then(|| {
        Rect::new(
            r.x - MARGIN_PX,
            r.y - MARGIN_PX,
            r.width + 2 * MARGIN_PX,
            r.height + 2 * MARGIN_PX,
        )
    })
}

/// Runs each setting on every image of `set` and scores it against the
/// labels, with `busy_model` for the painted scenes where given. Each
/// setting loads its networks and runs once on the first image untimed,
/// so that loading them and first-use allocations are not counted.
/// `on_image` is called after each image.
pub fn run_vision(
    set: &ImageSet,
    settings: &[VisionSetting],
    model: &Path,
    busy_model: Option<&Path>,
    runtime_library: &Path,
    mut on_image: impl FnMut(),
) -> Result<Vec<VisionRow>, VisionBenchError> {
    let mut rows = Vec::with_capacity(settings.len());
    for setting in settings {
        let mut network = setting.input_scales.map(|scales| {
            LazyNetwork::new(model.to_path_buf(), runtime_library.to_path_buf())
                .tuned(DEFAULT_THRESHOLD, scales)
                .with_busy_model(busy_model.map(Path::to_path_buf), DEFAULT_BUSY_THRESHOLD)
        });
        let mut scores = Vec::with_capacity(set.images.len());
        let mut total_ms = Vec::with_capacity(set.images.len());
        let mut stage_ms: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
        let mut skipped: BTreeMap<String, usize> = BTreeMap::new();
        let mut per_image = Vec::with_capacity(set.images.len());
        for (k, labelled) in set.images.iter().enumerate() {
            let mut pipeline = Pipeline::new(VisionConfig {
                roi_px: if setting.roi_around_cables {
                    roi_around_cables(&labelled.truth)
                } else {
                    None
                },
                ..setting.config.clone()
            });
            let failed = |source| VisionBenchError::Pipeline {
                setting: setting.name.clone(),
                image: labelled.name.clone(),
                source: Box::new(source),
            };
            if k == 0
                && let Some(network) = network.as_mut()
            {
                network.load().map_err(failed)?;
            }
            let mut detect = || {
                let net = network.as_mut().map(|n| n as &mut dyn MaskNetwork);
                pipeline.detect(&labelled.image, net).map_err(failed)
            };
            if k == 0 {
                detect()?;
            }
            let output = detect()?;
            for (stage, ms) in &output.timings_ms {
                stage_ms.entry(stage).or_default().push(*ms);
            }
            let ms = output
                .timings_ms
                .iter()
                .filter(|(stage, _)| *stage != "instance_masks")
                .map(|(_, ms)| ms)
                .sum();
            total_ms.push(ms);
            let names: Vec<String> = output
                .skipped
                .iter()
                .map(|skip| skip_name(skip).to_owned())
                .collect();
            for name in &names {
                *skipped.entry(name.clone()).or_default() += 1;
            }
            let image_score = score(&output, &labelled.truth).map_err(failed)?;
            per_image.push(ImageResult {
                image: labelled.name.clone(),
                ms,
                union_dice: image_score.union_dice,
                count_right: image_score.count_right,
                skipped: names,
            });
            scores.push(image_score);
            on_image();
        }
        let summary = summarize(&scores);
        let total = Summary::of(&total_ms);
        let in_us = |ms: &[f64]| ms.iter().map(|ms| ms * 1e3).collect::<Vec<_>>();
        rows.push(VisionRow {
            images: set.name.clone(),
            group: setting.group.to_owned(),
            setting: setting.name.clone(),
            image_count: summary.images,
            union_dice_mean: summary.union_dice,
            count_right_rate: summary.count_accuracy,
            grasp_error_px_mean: summary.grasp_error_px,
            ms_median: total.as_ref().map(|s| s.median),
            ms_p95: total.as_ref().map(|s| s.p95),
            stages: stage_ms
                .iter()
                .filter_map(|(stage, ms)| StageLatency::of(*stage, &in_us(ms)))
                .chain(StageLatency::of("whole pipeline", &in_us(&total_ms)))
                .collect(),
            skipped,
            per_image,
            front: false,
        });
    }
    let points: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| {
            (
                r.ms_median.unwrap_or(f64::INFINITY),
                1.0 - r.union_dice_mean,
            )
        })
        .collect();
    for (row, front) in rows.iter_mut().zip(pareto_front(&points)) {
        row.front = front;
    }
    Ok(rows)
}

/// A skip's name in a row's counts.
fn skip_name(skip: &VisionSkip) -> &'static str {
    match skip {
        VisionSkip::Network { .. } => "network",
        VisionSkip::CrossingResolution => "crossing_resolution",
        VisionSkip::ImageOutsideRoi { .. } => "image_outside_roi",
        VisionSkip::CableMasks => "cable_masks",
    }
}

#[cfg(test)]
mod tests {
    use opencv::prelude::*;

    use super::*;
    use crate::perception::vision::network::{DEFAULT_MODEL, runtime_library};

    #[test]
    fn rendered_images_are_fixed_by_the_seed_and_labelled_exactly() {
        let a = rendered_set("a", 2, 1, BackgroundChoice::Plain).unwrap();
        let b = rendered_set("b", 2, 1, BackgroundChoice::Plain).unwrap();
        assert_eq!(a.images.len(), 2);
        for (a, b) in a.images.iter().zip(&b.images) {
            let mut diff = Mat::default();
            opencv::core::absdiff(&a.image, &b.image, &mut diff).unwrap();
            assert_eq!(opencv::core::sum_elems(&diff).unwrap()[0], 0.0);
            assert_eq!(a.truth.masks.len(), a.truth.polylines_px.len());
            assert_eq!(a.truth.union_mask.size().unwrap(), a.image.size().unwrap());
        }
    }

    #[test]
    fn the_skips_on_a_plain_background_are_counted_and_compared_image_by_image() {
        let set = rendered_set("plain", 3, 1, BackgroundChoice::Plain).unwrap();
        let model = Path::new(DEFAULT_MODEL);
        let mut images = 0;
        let rows = run_vision(
            &set,
            &skip_settings(),
            model,
            None,
            &runtime_library(None),
            || images += 1,
        )
        .unwrap();
        assert_eq!(images, 9);
        let (skip, default, roi) = (&rows[0], &rows[1], &rows[2]);
        assert_eq!(skip.image_count, 3);
        // Some plain images skipped the network with the skip (where the
        // classical mask is in doubt, `auto` runs it all the same), none
        // without; and the skip costs little accuracy.
        assert!(
            skip.skipped.get("network").is_some_and(|&n| n >= 1),
            "{skip:?}"
        );
        assert_eq!(default.skipped.get("network"), None);
        assert!(
            (skip.union_dice_mean - default.union_dice_mean).abs() < 0.05,
            "{skip:?}\n{default:?}"
        );
        // The region costs no accuracy. It may gain: the region is worked
        // on enlarged to the working width, where a cable cut by the border
        // can reach the length under which it would be dropped.
        assert!(
            roi.union_dice_mean > default.union_dice_mean - 0.05,
            "{roi:?}\n{default:?}"
        );
        // Image by image: the images that skipped the network, with and
        // without the skip; the region against the whole image.
        let network = skip_saving("network", skip, default).unwrap();
        assert_eq!(network.image_count, skip.skipped["network"]);
        assert!(network.count_right_with <= network.image_count);
        let names = |row: &VisionRow| -> Vec<String> {
            row.per_image.iter().map(|r| r.image.clone()).collect()
        };
        assert_eq!(names(skip), names(default));
        let region = skip_saving("image_outside_roi", roi, default);
        assert_eq!(
            region.map_or(0, |r| r.image_count),
            roi.skipped.get("image_outside_roi").copied().unwrap_or(0)
        );
        assert!(skip_saving("cable_masks", skip, default).is_none());
        // The region holds the cables: what is outside it is skipped where
        // it leaves some of the image out.
        let outside = |image: &LabelledImage| {
            let region = roi_around_cables(&image.truth).unwrap();
            usize::from((region & Rect::new(0, 0, 640, 480)) != Rect::new(0, 0, 640, 480))
        };
        assert_eq!(
            roi.skipped.get("image_outside_roi").copied().unwrap_or(0),
            set.images.iter().map(outside).sum::<usize>()
        );
        // Both find the cables on a plain background.
        for row in &rows {
            assert!(row.union_dice_mean > 0.7, "{row:?}");
            assert!(row.stages.iter().any(|s| s.stage == "mask"), "{row:?}");
        }
    }

    #[test]
    fn photographs_are_read_from_a_folder_in_the_cables_dev_layout() {
        let dir = tempfile::tempdir().unwrap();
        let empty = photographs(dir.path()).err().unwrap();
        assert!(
            matches!(empty, VisionBenchError::NoImages { .. }),
            "{empty}"
        );
        let options = SceneOptions::default();
        crate::sim::render::write_dataset(
            dir.path(),
            2,
            1,
            &options,
            crate::sim::render::Cables::Rendered,
            || {},
        )
        .unwrap();
        let set = photographs(dir.path()).unwrap();
        let names: Vec<&str> = set.images.iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names, ["00000", "00001"]);
        for image in &set.images {
            assert_eq!(image.truth.masks.len(), image.truth.polylines_px.len());
        }
        // A label that does not parse is named with its image.
        std::fs::write(dir.path().join("00001.txt"), "3 1 2\n").unwrap();
        let error = photographs(dir.path()).err().unwrap();
        assert!(error.to_string().contains("00001"), "{error}");
    }
}
