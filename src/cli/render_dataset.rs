//! `cablecell render-dataset OUT`: synthetic images with exact ground
//! truth, in the layout of cables-dev, for training the segmentation
//! network and for scoring the pipeline with `eval-vision`; with
//! `--cables-from`, a labelled folder's real cables over rendered
//! backgrounds.

use crate::cli::output::outln;
use std::path::{Path, PathBuf};

use cablecell::sim::render::{
    BackgroundChoice, Cables, LabelledPhotograph, SceneOptions, write_dataset,
};
use clap::Args;

use super::labelled_folder::{LabelledImage, load_labelled};
use super::{Status, number_within, progress};

#[derive(Args, Debug, Clone)]
pub struct RenderDatasetArgs {
    /// The folder to write (created; must be empty or absent).
    pub out: PathBuf,
    /// How many images.
    #[arg(long, default_value_t = 100, value_parser = count)]
    pub count: usize,
    /// The seed: image K is drawn from stream K of this seed, so the same
    /// seed and options give the same images, and a larger count only
    /// adds images.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// What the cables lie on.
    #[arg(long, value_enum, default_value = "any")]
    pub backgrounds: BackgroundArg,
    /// Each image's width, pixels.
    #[arg(long, default_value_t = 640, value_parser = side_px)]
    pub width_px: i32,
    /// Each image's height, pixels.
    #[arg(long, default_value_t = 480, value_parser = side_px)]
    pub height_px: i32,
    /// Fewest cables per image.
    #[arg(long, default_value_t = 1, value_parser = cables)]
    pub min_cables: usize,
    /// Most cables per image.
    #[arg(long, default_value_t = 4, value_parser = cables)]
    pub max_cables: usize,
    /// Thinnest cable, in pixels.
    #[arg(long, default_value_t = 6.0, value_parser = diameter_px)]
    pub min_diameter_px: f64,
    /// Thickest cable, in pixels.
    #[arg(long, default_value_t = 16.0, value_parser = diameter_px)]
    pub max_diameter_px: f64,
    /// Keep cables apart (no crossings).
    #[arg(long)]
    pub no_crossings: bool,
    /// Take each image's cables from a labelled folder's photographs (the
    /// cables-dev layout), in turn, instead of rendering them: each
    /// photograph's cables, cut along their masks, mirrored and enlarged
    /// up to twice, over a rendered background without cables, their
    /// labels moved with them.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["min_cables", "max_cables", "min_diameter_px", "max_diameter_px", "no_crossings"])]
    pub cables_from: Option<PathBuf>,
    /// With --cables-from: only photographs whose name sorts at or after
    /// this, e.g. 00030.
    #[arg(long, requires = "cables_from")]
    pub from: Option<String>,
    /// With --cables-from: only photographs whose name sorts at or before
    /// this, e.g. 00044.
    #[arg(long, requires = "cables_from")]
    pub to: Option<String>,
    /// With --cables-from: the pasted cables cast their shadows on the
    /// background, as rendered cables do, under the background's light.
    /// Off by default, so that a set rendered before renders the same.
    #[arg(long, requires = "cables_from")]
    pub cast_shadows: bool,
}

/// 1 to 100 000 images: a training set of a few thousand is plenty.
fn count(text: &str) -> Result<usize, String> {
    number_within(text, 1..=100_000, "images")
}

/// 16 to 4096 px a side: the pipeline works at 640 px wide.
fn side_px(text: &str) -> Result<i32, String> {
    number_within(text, 16..=4096, "px")
}

/// 0 to 16 cables: more do not fit apart on an image.
fn cables(text: &str) -> Result<usize, String> {
    number_within(text, 0..=16, "cables")
}

/// 1 to 100 px: thinner is no cable, thicker fills the image.
fn diameter_px(text: &str) -> Result<f64, String> {
    number_within(text, 1.0..=100.0, "px")
}

#[derive(clap::ValueEnum, Debug, Clone, Copy)]
pub enum BackgroundArg {
    Plain,
    Cluttered,
    Any,
    /// Drip paintings, mosaics and print, cables with metal ends: the
    /// paper's kind of scene.
    Busy,
    /// Wood, a board over a stretch of a cable in half the images: the
    /// simulated cell's kind of scene.
    Workbench,
    /// Black cloth or a dark table under a light's falloff: tubes on a
    /// dark background.
    Dark,
}

pub fn render_dataset(args: &RenderDatasetArgs) -> Status {
    let options = match scene_options(args) {
        Ok(options) => options,
        Err(reason) => {
            eprintln!("error: render-dataset: {reason}");
            return Status::BadInput;
        }
    };
    if let Err(reason) = check_empty(&args.out) {
        eprintln!("error: {}: {reason}", args.out.display());
        return Status::BadInput;
    }
    let labelled: Vec<LabelledImage> = match &args.cables_from {
        Some(dir) => match load_labelled(dir, args.from.as_deref(), args.to.as_deref()) {
            Ok(labelled) => labelled,
            Err(messages) => {
                for message in messages {
                    eprintln!("error: render-dataset: {message}");
                }
                return Status::BadInput;
            }
        },
        None => Vec::new(),
    };
    let photos: Vec<LabelledPhotograph> = labelled
        .iter()
        .map(|l| LabelledPhotograph {
            bgr: &l.image,
            masks: &l.truth.masks,
            centerlines_px: &l.truth.polylines_px,
        })
        .collect();
    let bar = progress::bar(args.count, "images");
    let cables = match &args.cables_from {
        Some(_) => Cables::Pasted {
            photos: &photos,
            cast_shadows: args.cast_shadows,
        },
        None => Cables::Rendered,
    };
    let written = write_dataset(&args.out, args.count, args.seed, &options, cables, || {
        bar.inc(1)
    });
    bar.finish_and_clear();
    match written {
        Ok(()) => {
            let cables = match &args.cables_from {
                Some(dir) => format!(
                    ", cables from {} ({} image{})",
                    dir.display(),
                    photos.len(),
                    if photos.len() == 1 { "" } else { "s" }
                ),
                None => String::new(),
            };
            outln!(
                "{}: {} images, seed {}{cables}",
                args.out.display(),
                args.count,
                args.seed
            );
            Status::Success
        }
        Err(error) => {
            let mut message = format!("error: {}: {error}", args.out.display());
            let mut source = std::error::Error::source(&error);
            while let Some(cause) = source {
                message.push_str(&format!(": {cause}"));
                source = cause.source();
            }
            eprintln!("{message}");
            Status::OutputFailed
        }
    }
}

/// The renderer's options from the command line, or what is wrong with
/// them.
fn scene_options(args: &RenderDatasetArgs) -> Result<SceneOptions, String> {
    if args.min_cables > args.max_cables {
        return Err(format!(
            "--min-cables {} exceeds --max-cables {}",
            args.min_cables, args.max_cables
        ));
    }
    if args.min_diameter_px > args.max_diameter_px {
        return Err(format!(
            "--min-diameter-px {} exceeds --max-diameter-px {}",
            args.min_diameter_px, args.max_diameter_px
        ));
    }
    Ok(SceneOptions {
        width_px: args.width_px,
        height_px: args.height_px,
        min_cables: args.min_cables,
        max_cables: args.max_cables,
        backgrounds: match args.backgrounds {
            BackgroundArg::Plain => BackgroundChoice::Plain,
            BackgroundArg::Cluttered => BackgroundChoice::Cluttered,
            BackgroundArg::Any => BackgroundChoice::Any,
            BackgroundArg::Busy => BackgroundChoice::Busy,
            BackgroundArg::Workbench => BackgroundChoice::Workbench,
            BackgroundArg::Dark => BackgroundChoice::Dark,
        },
        crossings: !args.no_crossings,
        min_diameter_px: args.min_diameter_px,
        max_diameter_px: args.max_diameter_px,
    })
}

/// Refuses a folder that already holds files: images of another seed or
/// count left beside the new ones would silently mix two data sets.
fn check_empty(out: &Path) -> Result<(), String> {
    match std::fs::read_dir(out) {
        Ok(mut entries) => match entries.next() {
            None => Ok(()),
            Some(_) => Err("the folder is not empty; choose a new one or empty it".into()),
        },
        Err(error) if error.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(error) => Err(format!("cannot read the folder: {error}")),
    }
}
