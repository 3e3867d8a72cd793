//! `cablecell eval-vision DIR`

use std::collections::BTreeMap;
use std::path::Path;

use cablecell::campaign::stats::{Rate, Summary};
use cablecell::perception::vision::MaskNetwork;
use cablecell::perception::vision::eval::{GroundTruth, ImageScore, score};
use serde::Serialize;

use super::Status;
use super::vision_io::{VisionArgs, read_image};

#[derive(Serialize)]
struct Evaluation {
    images: usize,
    union_iou: Option<Summary>,
    union_dice: Option<Summary>,
    instance_dice: Option<Summary>,
    count_right: Option<Rate>,
    centerline_px: Option<Summary>,
    grasp_error_px: Option<Summary>,
    /// Per stage, and "total": median and 95th percentile among the rest.
    stage_ms: BTreeMap<&'static str, Summary>,
    per_image: Vec<(String, ImageScore)>,
}

pub fn eval_vision(dir: &Path, args: &VisionArgs, json: bool) -> Status {
    let stems = match image_stems(dir) {
        Ok(stems) if !stems.is_empty() => stems,
        Ok(_) => {
            eprintln!(
                "error: {}: no NNNNN.jpg images with NNNNN_mask_all.png beside them",
                dir.display()
            );
            return Status::BadInput;
        }
        Err(error) => {
            eprintln!("error: {}: cannot list the folder: {error}", dir.display());
            return Status::BadInput;
        }
    };
    let mut pipeline = args.pipeline();
    let mut network = args.network();
    let mut per_image = Vec::new();
    let mut stage_ms: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
    for (stem, image_path) in &stems {
        let image = match read_image(image_path) {
            Ok(image) => image,
            Err(error) => {
                eprintln!("error: {error}");
                return Status::BadInput;
            }
        };
        let truth = match GroundTruth::load(dir, stem) {
            Ok(truth) => truth,
            Err(error) => {
                eprintln!("error: {}: {stem}: {error}", dir.display());
                return Status::BadInput;
            }
        };
        let output = match pipeline.detect(&image, Some(&mut network as &mut dyn MaskNetwork)) {
            Ok(output) => output,
            Err(error) => {
                eprintln!("error: {}: {error}", image_path.display());
                return Status::TaskFailed;
            }
        };
        for (stage, ms) in &output.timings_ms {
            stage_ms.entry(stage).or_default().push(*ms);
        }
        stage_ms
            .entry("total")
            .or_default()
            .push(output.timings_ms.iter().map(|(_, ms)| ms).sum());
        per_image.push((stem.clone(), score(&output, &truth)));
    }
    let of = |f: &dyn Fn(&ImageScore) -> Option<f64>| {
        Summary::of(
            &per_image
                .iter()
                .filter_map(|(_, s)| f(s))
                .collect::<Vec<_>>(),
        )
    };
    let evaluation = Evaluation {
        images: per_image.len(),
        union_iou: of(&|s| Some(s.union_iou)),
        union_dice: of(&|s| Some(s.union_dice)),
        instance_dice: of(&|s| Some(s.instance_dice)),
        count_right: Rate::wilson(
            per_image.iter().filter(|(_, s)| s.count_right).count(),
            per_image.len(),
        ),
        centerline_px: of(&|s| s.centerline_px),
        grasp_error_px: of(&|s| s.grasp_error_px),
        stage_ms: stage_ms
            .iter()
            .filter_map(|(stage, ms)| Summary::of(ms).map(|s| (*stage, s)))
            .collect(),
        per_image,
    };
    if json {
        match serde_json::to_string_pretty(&evaluation) {
            Ok(text) => println!("{text}"),
            Err(error) => {
                eprintln!("error: cannot write the evaluation as JSON: {error}");
                return Status::OutputFailed;
            }
        }
    } else {
        print_evaluation(dir, &evaluation);
    }
    Status::Success
}

fn print_evaluation(dir: &Path, e: &Evaluation) {
    println!("{}: {} images", dir.display(), e.images);
    let line = |name: &str, s: &Option<Summary>| {
        if let Some(s) = s {
            println!(
                "  {name:<22} mean {:.3}  median {:.3}  p95 {:.3}  max {:.3}",
                s.mean, s.median, s.p95, s.max
            );
        }
    };
    line("union IoU", &e.union_iou);
    line("union DICE", &e.union_dice);
    line("instance DICE", &e.instance_dice);
    if let Some(rate) = &e.count_right {
        println!(
            "  {:<22} {}/{} = {:.0} % [{:.0}, {:.0}] (95 % CI)",
            "instance count right",
            rate.successes,
            rate.trials,
            100.0 * rate.rate,
            100.0 * rate.ci95_low,
            100.0 * rate.ci95_high
        );
    }
    line("centerline px", &e.centerline_px);
    line("grasp error px", &e.grasp_error_px);
    for (stage, s) in &e.stage_ms {
        println!(
            "  {:<22} median {:.2} ms  p95 {:.2} ms",
            format!("{stage} time"),
            s.median,
            s.p95
        );
    }
}

/// (stem, image path) of every image with a union mask beside it, sorted.
fn image_stems(dir: &Path) -> std::io::Result<Vec<(String, std::path::PathBuf)>> {
    let mut stems = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        let is_image = path.extension().is_some_and(|e| e == "jpg" || e == "png");
        let Some(stem) = path.file_stem().map(|s| s.to_string_lossy().into_owned()) else {
            continue;
        };
        if is_image
            && !stem.contains("_mask_")
            && dir.join(format!("{stem}_mask_all.png")).is_file()
        {
            stems.push((stem, path));
        }
    }
    stems.sort();
    Ok(stems)
}
