//! `cablecell eval-vision DIR [--from STEM] [--to STEM] [--sweep [--rounds N]] [--overlay DIR] [--labelled-mask]`

mod print;
mod score;
pub mod sweep;

use std::collections::BTreeMap;
use std::path::PathBuf;

use cablecell::campaign::stats::{Rate, Summary};
use cablecell::perception::vision::eval::ImageScore;
use clap::Args;
use schemars::JsonSchema;
use serde::Serialize;

use super::labelled_folder::load_labelled;
use super::vision_io::{MaskArg, VisionArgs};
use super::{Status, progress};
use print::print_evaluation;
use score::{Failure, evaluate, labels_own_dice};
use sweep::sweep;

#[derive(Args, Debug, Clone)]
pub struct EvalVisionArgs {
    /// The labelled folder: each image with its masks and centre lines (a
    /// folder `render-dataset` wrote, or the development photographs).
    pub dir: PathBuf,
    #[command(flatten)]
    pub vision: VisionArgs,
    /// Score only images whose name sorts at or after this, e.g. 00030.
    #[arg(long)]
    pub from: Option<String>,
    /// Score only images whose name sorts at or before this, e.g. 00044.
    #[arg(long)]
    pub to: Option<String>,
    /// Score the main settings (mask method, network input size, 8-bit or
    /// float network, instance method, superpixel size) one after another
    /// and print a table of run time against error; the other vision
    /// options set what a row does not.
    #[arg(long)]
    pub sweep: bool,
    /// With --sweep: time the settings in this many rounds, taking turns,
    /// and give each one's median and 95th percentile over all rounds. A
    /// machine's speed drifts over minutes; rounds spread the drift over
    /// every setting instead of loading it onto a few.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub rounds: u32,
    /// Write each image, as DIR/NAME.png, with the cables found drawn on
    /// it as `detect --overlay` draws them, the labelled centre lines in
    /// white, and in red the labelled cables not found and the found ones
    /// not labelled.
    #[arg(long, value_name = "DIR", conflicts_with = "sweep")]
    pub overlay: Option<PathBuf>,
    /// Find the cables in each image's labelled mask instead of one the
    /// pipeline finds (colours still from the image; at the image's own
    /// size, with no region of interest): what the instance stages count
    /// with a perfect mask, to tell their errors from the mask's.
    #[arg(long, conflicts_with = "sweep")]
    pub labelled_mask: bool,
    /// Print the scores as JSON (`cablecell json-schema eval-vision`, or
    /// `eval-vision-sweep` with --sweep).
    #[arg(long)]
    pub json: bool,
}

#[derive(Serialize, JsonSchema)]
struct Evaluation {
    images: usize,
    union_iou: Option<Summary>,
    union_dice: Option<Summary>,
    /// The union DICE with each image's found mask moved by its
    /// [`ImageScore::mask_offset_px`].
    union_dice_at_offset: Option<Summary>,
    instance_dice: Option<Summary>,
    count_right: Option<Rate>,
    /// Labelled cables that a detection matches, over all images.
    labels_found: Option<Rate>,
    /// Detections that match a labelled cable, over all images.
    found_labelled: Option<Rate>,
    /// Labelled cables reported in pieces (two or more detections along
    /// one), over all images.
    labels_in_pieces: Option<Rate>,
    /// The labelled centre lines' length near a found one, over all images.
    labelled_length_found: Option<LengthShare>,
    /// The found centre lines' length near a labelled one, over all images.
    found_length_labelled: Option<LengthShare>,
    centerline_px: Option<Summary>,
    grasp_error_px: Option<Summary>,
    /// Reported cables whose grasp point lies within 5 px of a labelled
    /// centre line, over all images: the label-robust score.
    grasps_near_label: Option<Rate>,
    /// Images whose first grasp, on the cable the task would grasp first
    /// (the most confident), lies within 5 px of a labelled centre line,
    /// over the images where something was found: trial grasps that
    /// would hold a cable.
    first_grasps_near_label: Option<Rate>,
    /// Per stage, and "total": median and 95th percentile among the rest.
    stage_ms: BTreeMap<&'static str, Summary>,
    /// Each image's end-to-end time, in order; the sweep adds its later
    /// rounds' times here.
    #[serde(skip)]
    total_ms: Vec<f64>,
    per_image: Vec<(String, ImageScore)>,
    /// How many images each mask ran on: `auto` chooses per image.
    mask_used: MaskUse,
    /// What the pipeline said about an image (fallbacks taken, detections
    /// dropped as edges or as cables too little in view), by image.
    notes: Vec<(String, String)>,
}

/// Images by the mask that ran on them.
#[derive(Serialize, Default, JsonSchema)]
struct MaskUse {
    classical: usize,
    network: usize,
    /// The labels' own (`--labelled-mask`).
    labelled: usize,
}

/// The labels' own union DICE: their centre lines drawn `width_px` wide
/// against their masks, a reference for the pipeline's union DICE.
#[derive(Serialize, JsonSchema)]
struct LabelsOwnDice {
    width_px: f64,
    union_dice: Summary,
}

/// What `eval-vision --json` prints.
#[derive(Serialize, JsonSchema)]
pub struct Report {
    #[serde(flatten)]
    evaluation: Evaluation,
    labels_own_union_dice: Option<LabelsOwnDice>,
}

/// How much of one side's centre-line length lies within
/// [`CENTRELINE_NEAR_PX`] of the other side's.
#[derive(Serialize, JsonSchema)]
struct LengthShare {
    share: f64,
    length_px: f64,
}

pub fn eval_vision(args: &EvalVisionArgs) -> Status {
    let samples = match load_labelled(&args.dir, args.from.as_deref(), args.to.as_deref()) {
        Ok(samples) => samples,
        Err(messages) => {
            for message in messages {
                eprintln!("error: {message}");
            }
            return Status::BadInput;
        }
    };
    // The network is loaded before scoring unless the classical mask alone
    // is asked for, so that a model that is no network (or no runtime) is
    // the command line's fault, found whether or not an image needs it.
    if !matches!(args.vision.mask, MaskArg::Classical)
        && !args.labelled_mask
        && let Err(error) = args.vision.network().load()
    {
        eprintln!("error: {error}");
        return if error.is_in_setup() {
            Status::BadInput
        } else {
            Status::TaskFailed
        };
    }
    if args.sweep {
        return sweep(args, &samples);
    }
    let bar = progress::bar(samples.len(), "images");
    let evaluated = evaluate(
        &args.vision,
        &samples,
        args.labelled_mask,
        args.overlay.as_deref(),
        &bar,
    );
    bar.finish_and_clear();
    let report = evaluated.and_then(|evaluation| {
        Ok(Report {
            evaluation,
            labels_own_union_dice: labels_own_dice(&samples)?,
        })
    });
    let report = match report {
        Ok(report) => report,
        Err(Failure { message, status }) => {
            eprintln!("error: {message}");
            return status;
        }
    };
    if args.json {
        crate::cli::json::print(&report)
    } else {
        print_evaluation(&args.dir, &report);
        Status::Success
    }
}
