//! What `detect` and `eval-vision` share: the pipeline's configuration
//! from the command line, the network loaded only when a scene needs it,
//! and writing images with the cables found drawn on them.

use std::path::{Path, PathBuf};

use cablecell::cell::{CellFile, load_cell_uncalibrated};
use cablecell::detector::config::{DetectorBackend, VisionDetectorConfig};

use cablecell::perception::vision::network::{
    BUSY_MODEL, DEFAULT_BUSY_THRESHOLD, DEFAULT_INPUT_SCALE, DEFAULT_MODEL, DEFAULT_THRESHOLD,
    InputScales, LazyNetwork, MAX_INPUT_SCALE, runtime_library,
};
use cablecell::perception::vision::superpixels::DEFAULT_REGION_WIDTHS;
use cablecell::perception::vision::{
    CableInstance, DEFAULT_MIN_CONFIDENCE, InstanceMethod, MaskMethod, Pipeline, VisionConfig,
};
use clap::Args;
use opencv::core::{Mat, Point, Scalar, Vector};
use opencv::{imgcodecs, imgproc};

#[derive(Args, Debug, Clone)]
pub struct VisionArgs {
    /// How to find the cables' pixels: the network; the classical mask;
    /// or `auto`: the classical mask on a plain background unless that
    /// mask is in doubt (the notes say why), the network otherwise, which
    /// saves the network's time there at some accuracy (docs/vision.md).
    #[arg(long, value_enum, default_value = "network")]
    pub mask: MaskArg,
    /// How to split the mask into cables.
    #[arg(long, value_enum, default_value = "skeleton")]
    pub instances: InstancesArg,
    /// The segmentation network [default: models/cable_segmentation.onnx,
    /// with models/cable_segmentation_busy_mirrored.onnx for painted scenes]; given
    /// alone, it sees every scene.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// A second network for the scenes whose background is painted (busy
    /// and of many colours: paint, prints, mosaics), which counts more
    /// cables right there (docs/vision.md) [default: the shipped one where
    /// --model is not given].
    #[arg(long)]
    pub busy_model: Option<PathBuf>,
    /// The ONNX Runtime library (default: $ORT_DYLIB_PATH, else the
    /// checkout's .setup/onnxruntime/).
    #[arg(long)]
    pub onnxruntime: Option<PathBuf>,
    /// The network's probability above which a pixel is cable.
    #[arg(long, default_value_t = DEFAULT_THRESHOLD, value_parser = probability)]
    pub threshold: f32,
    /// The same in a painted scene, for the network for busy scenes: the
    /// shipped one averages four looks, whose smoother map is cut best
    /// lower.
    #[arg(long, default_value_t = DEFAULT_BUSY_THRESHOLD, value_parser = probability)]
    pub busy_threshold: f32,
    /// The network's input size as a fraction of the image's (0.5: 320×240
    /// for 640×480; smaller is faster).
    #[arg(long, default_value_t = DEFAULT_INPUT_SCALE, value_parser = input_scale)]
    pub net_scale: f64,
    /// The same where less than half of the image is near its median
    /// colour (paint, prints, mosaics), the background is dark, or it is
    /// not plain and dense with edges (paint on a bare canvas), where the
    /// network tells cables from strokes and tubes from dark cloth better
    /// when it looks closer [default: 0.5, or --net-scale where larger]
    #[arg(long, value_parser = input_scale)]
    pub close_net_scale: Option<f64>,
    /// The same in a painted scene, for the network for busy scenes, which
    /// finds more real cables over paint when it looks closer still, in
    /// about 1.5 times the time of 0.5 [default: 0.625, or
    /// --close-net-scale where larger]
    #[arg(long, value_parser = input_scale)]
    pub busy_net_scale: Option<f64>,
    /// Superpixel side in cable widths, for `--instances superpixels`
    /// (smaller: more superpixels).
    #[arg(long, default_value_t = DEFAULT_REGION_WIDTHS, value_parser = region_widths)]
    pub superpixel_widths: f64,
    /// Work on images at this width (px), wider ones shrunk and narrower
    /// ones enlarged (up to 4 times), and map what is found back to the
    /// image: the network and the lengths below were tuned on 640 px wide
    /// images, and the lengths are those of the image as worked on. 0 works
    /// at the image's own size.
    #[arg(long, default_value_t = VisionConfig::default().work_width_px)]
    pub work_width_px: u32,
    /// Drop cables shorter than this (px): scraps of mask; on a busy
    /// background (paint, prints, mosaics) twice this: scraps of paint.
    #[arg(long, default_value_t = VisionConfig::default().min_cable_length_px, value_parser = length_px)]
    pub min_length_px: f64,
    /// Drop cables that run out of the image (or region of interest) and
    /// are shorter than this (px): too little of them is in view to grasp.
    #[arg(long, default_value_t = VisionConfig::default().min_border_cable_length_px, value_parser = length_px)]
    pub min_border_length_px: f64,
    /// Drop detections straighter than an arc of this radius (px), or within
    /// 1.5 px of straight: edges of paper and tables (on a plain background,
    /// a light's falloff aside, only when the two sides differ; never on a
    /// busy one: paint, prints, mosaics); 0 keeps them (for a cable held
    /// taut).
    #[arg(long, default_value_t = VisionConfig::default().straight_edge_radius_px, value_parser = length_px)]
    pub straight_edge_radius_px: f64,
    /// Drop detections less confident than this (0 to 1; see `detect`'s
    /// `confidence`): splashes of paint, brushed strokes and flat paint; 0 keeps all.
    /// 1.35 times this on a painted background (paint, prints, mosaics).
    #[arg(long, default_value_t = DEFAULT_MIN_CONFIDENCE, value_parser = confidence)]
    pub min_confidence: f64,
}

fn number_in(text: &str, low: f64, high: f64) -> Result<f64, String> {
    let value: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if value > low && value <= high {
        Ok(value)
    } else {
        Err(format!("{value} is outside ({low}, {high}]"))
    }
}

fn probability(text: &str) -> Result<f32, String> {
    number_in(text, 0.0, 1.0).map(|v| v as f32)
}

fn input_scale(text: &str) -> Result<f64, String> {
    number_in(text, 0.0, MAX_INPUT_SCALE)
}

fn length_px(text: &str) -> Result<f64, String> {
    let value: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(format!("{value} is not a length of 0 px or more"))
    }
}

fn confidence(text: &str) -> Result<f64, String> {
    let value: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if (0.0..=1.0).contains(&value) {
        Ok(value)
    } else {
        Err(format!("{value} is outside [0, 1]"))
    }
}

fn region_widths(text: &str) -> Result<f64, String> {
    number_in(text, 0.0, 20.0)
}

#[derive(clap::ValueEnum, Debug, Clone, Copy)]
pub enum MaskArg {
    Auto,
    Classical,
    Network,
}

#[derive(clap::ValueEnum, Debug, Clone, Copy)]
pub enum InstancesArg {
    Skeleton,
    Superpixels,
}

impl VisionArgs {
    /// The pipeline these arguments ask for; `cable_masks`: whether the
    /// command needs each cable's mask (see [`VisionConfig::cable_masks`]).
    pub fn pipeline(&self, cable_masks: bool) -> Pipeline {
        let config = VisionConfig {
            mask: match self.mask {
                MaskArg::Auto => MaskMethod::Auto,
                MaskArg::Classical => MaskMethod::Classical,
                MaskArg::Network => MaskMethod::Network,
            },
            instances: match self.instances {
                InstancesArg::Skeleton => InstanceMethod::Skeleton,
                InstancesArg::Superpixels => InstanceMethod::Superpixels,
            },
            superpixel_widths: self.superpixel_widths,
            work_width_px: self.work_width_px,
            min_cable_length_px: self.min_length_px,
            min_border_cable_length_px: self.min_border_length_px,
            straight_edge_radius_px: self.straight_edge_radius_px,
            min_confidence: self.min_confidence,
            cable_masks,
            ..VisionConfig::default()
        };
        Pipeline::new(config)
    }

    /// The network, with the one for painted scenes: the shipped pair
    /// unless `--model` is given, which alone sees every scene unless
    /// `--busy-model` is given too.
    pub fn network(&self) -> LazyNetwork {
        let (model, busy_model) = match &self.model {
            Some(model) => (model.clone(), self.busy_model.clone()),
            None => (
                PathBuf::from(DEFAULT_MODEL),
                Some(self.busy_model.clone().unwrap_or(BUSY_MODEL.into())),
            ),
        };
        LazyNetwork::new(model, runtime_library(self.onnxruntime.as_deref()))
            .tuned(
                self.threshold,
                InputScales::new(self.net_scale, self.close_net_scale, self.busy_net_scale),
            )
            .with_busy_model(busy_model, self.busy_threshold)
    }
}

/// The cell file at `path`, and its vision detector's settings: what a
/// command given `--cell` runs, so that it finds the cables the task's
/// detect state finds.
pub fn cell_vision_detector(path: &Path) -> Result<(CellFile, VisionDetectorConfig), String> {
    let file: CellFile = load_cell_uncalibrated(path).map_err(|e| e.to_string())?;
    match &file.detector.backend {
        DetectorBackend::Vision(vision) => {
            let vision = vision.clone();
            Ok((file, *vision))
        }
        DetectorBackend::Oracle(_) => Err(format!(
            "{}: detector.backend: the cell has no vision detector",
            path.display()
        )),
    }
}

/// Runs `pipeline` once on `image`, untimed, so that the times reported
/// after it are a warmed-up pipeline's (loading the network is no image's
/// time); the line that says what it cost. Where the image needed the
/// network, the busy scenes' network is loaded too, whatever the image's
/// background. An error here recurs in the timed run, which reports it.
pub fn warm_up(pipeline: &mut Pipeline, network: &mut LazyNetwork, image: &Mat) -> String {
    let start = std::time::Instant::now();
    if let Ok(output) = pipeline.detect(image, Some(network))
        && output.mask_used == MaskMethod::Network
    {
        let _ = network.load();
    }
    format!(
        "start-up: {:.1} ms (the first image run once, untimed: one-off set-up such as loading the network)",
        start.elapsed().as_secs_f64() * 1e3
    )
}

pub fn create_dir(dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("{}: cannot create the folder: {e}", dir.display()))
}

pub fn write_png(path: &Path, image: &Mat) -> Result<(), String> {
    let name = path.display().to_string();
    match imgcodecs::imwrite(&name, image, &Vector::new()) {
        Ok(true) => Ok(()),
        Ok(false) => Err(format!("{name}: OpenCV could not write the image")),
        Err(e) => Err(format!("{name}: {e}")),
    }
}

/// The image with each cable's spline, grasp point and grasp frame's x
/// axis drawn on it.
pub fn draw_overlay(image: &Mat, cables: &[CableInstance]) -> opencv::Result<Mat> {
    const COLOURS: [(f64, f64, f64); 6] = [
        (0.0, 255.0, 255.0),
        (255.0, 0.0, 255.0),
        (255.0, 255.0, 0.0),
        (0.0, 128.0, 255.0),
        (255.0, 128.0, 0.0),
        (128.0, 255.0, 0.0),
    ];
    let mut drawn = image.clone();
    for (k, cable) in cables.iter().enumerate() {
        let (b, g, r) = COLOURS[k % COLOURS.len()];
        let colour = Scalar::new(b, g, r, 0.0);
        draw_line(&mut drawn, &cable.samples_px, colour, 2)?;
        let grasp = Point::new(
            cable.grasp_px[0].round() as i32,
            cable.grasp_px[1].round() as i32,
        );
        imgproc::circle(&mut drawn, grasp, 5, colour, -1, imgproc::LINE_AA, 0)?;
        let (dx, dy) = (
            cable.direction_rad.cos() * 40.0,
            cable.direction_rad.sin() * 40.0,
        );
        let tip = Point::new(grasp.x + dx.round() as i32, grasp.y + dy.round() as i32);
        imgproc::arrowed_line(
            &mut drawn,
            grasp,
            tip,
            Scalar::new(0.0, 0.0, 255.0, 0.0),
            2,
            imgproc::LINE_AA,
            0,
            0.25,
        )?;
        // The frame's y axis: normal to the cable in the image plane.
        let normal = Point::new(grasp.x - dy.round() as i32, grasp.y + dx.round() as i32);
        imgproc::arrowed_line(
            &mut drawn,
            grasp,
            normal,
            Scalar::new(0.0, 255.0, 0.0, 0.0),
            2,
            imgproc::LINE_AA,
            0,
            0.25,
        )?;
    }
    Ok(drawn)
}

/// Draws the polyline through `line_px` on `image`, `thickness` px wide.
pub fn draw_line(
    image: &mut Mat,
    line_px: &[[f64; 2]],
    colour: Scalar,
    thickness: i32,
) -> opencv::Result<()> {
    let points: Vector<Point> = line_px
        .iter()
        .map(|p| Point::new(p[0].round() as i32, p[1].round() as i32))
        .collect();
    let curves = Vector::<Vector<Point>>::from_iter([points]);
    imgproc::polylines(
        image,
        &curves,
        false,
        colour,
        thickness,
        imgproc::LINE_AA,
        0,
    )
}
