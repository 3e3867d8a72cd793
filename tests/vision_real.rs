//! The vision pipeline on real photographs: the cables-dev images (45
//! photographs of wires on wood, cloth and prints from the Cables Dataset
//! of De Gregorio, Palli and Di Stefano, arXiv 1810.04461), read from
//! `../shared/data/cables-dev` beside the project. They are not part of the
//! repository: these tests are ignored unless asked for (`--ignored`),
//! which `scripts/test` does when the folder is there.

mod common;

use cablecell::perception::vision::eval::{self, ImageScore};
use cablecell::perception::vision::{
    GroundTruth, InstanceMethod, MaskMethod, Pipeline, VisionConfig,
};
use opencv::imgcodecs;
use opencv::prelude::*;

fn stems(dir: &std::path::Path) -> Vec<String> {
    let mut stems: Vec<String> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok())
                .filter_map(|e| e.file_name().into_string().ok())
                .filter_map(|name| name.strip_suffix(".jpg").map(str::to_string))
                .collect()
        })
        .unwrap_or_default();
    stems.sort();
    stems
}

fn print_scores(what: &str, scores: &[(String, ImageScore)]) {
    for (stem, s) in scores {
        eprintln!(
            "{what} {stem}: count {}/{} iou {:.3} dice {:.3} inst-dice {:.3} centreline {:?} grasp {:?}",
            s.predicted_count,
            s.truth_count,
            s.union_iou,
            s.union_dice,
            s.instance_dice,
            s.centerline_px,
            s.grasp_error_px
        );
    }
    let only: Vec<ImageScore> = scores.iter().map(|(_, s)| s.clone()).collect();
    eprintln!("{what} summary: {:?}", eval::summarize(&only));
}

/// Instances and splines on the true union masks (the instance stages in
/// isolation from the mask). Every labelled piece is a cable here, so
/// short pieces at the border are kept like any other, and so are
/// straight ones (the labels draw short pieces as near-straight polylines).
fn instances_on_truth(method: InstanceMethod) -> Vec<(String, ImageScore)> {
    let dir = common::cables_dev();
    let mut pipeline = Pipeline::new(VisionConfig {
        instances: method,
        min_border_cable_length_px: 0.0,
        straight_edge_radius_px: 0.0,
        ..VisionConfig::default()
    });
    let mut scores = Vec::new();
    for stem in stems(&dir) {
        let truth = GroundTruth::load(&dir, &stem).expect("ground truth loads");
        let found = pipeline
            .instances_from_mask(&truth.union_mask, None)
            .expect("instances from the true mask");
        scores.push((
            stem,
            eval::score_cables(&found.cables, &truth.union_mask, &truth)
                .expect("the masks are drawn"),
        ));
    }
    scores
}

/// Scores `method` on the true masks and checks the summary: counts right
/// in at least `min_count_accuracy` of the images, instance DICE at least
/// `min_instance_dice`, centre lines and grasp points within 1.2 and 1.3 px.
fn assert_instances_on_truth(
    method: InstanceMethod,
    min_count_accuracy: f64,
    min_instance_dice: f64,
) {
    let scores = instances_on_truth(method);
    print_scores(&format!("{method:?}/truth-mask"), &scores);
    let only: Vec<ImageScore> = scores.iter().map(|(_, s)| s.clone()).collect();
    let summary = eval::summarize(&only);
    assert_eq!(summary.images, 45);
    assert!(summary.count_accuracy >= min_count_accuracy, "{summary:?}");
    assert!(summary.instance_dice >= min_instance_dice, "{summary:?}");
    assert!(
        summary.centerline_px.is_some_and(|d| d <= 1.2),
        "{summary:?}"
    );
    assert!(
        summary.grasp_error_px.is_some_and(|d| d <= 1.3),
        "{summary:?}"
    );
}

#[test]
#[ignore = "needs the cables-dev photographs in ../shared/data; scripts/test runs it when they are there"]
fn skeleton_instances_on_true_masks() {
    // Measured: 43 of 45 counts right (the misses join a cable end to a
    // touching cable, or drop a stub under 40 px), instance DICE 0.987,
    // centreline 0.89 px, grasp point 0.88 px from the true centreline.
    assert_instances_on_truth(InstanceMethod::Skeleton, 0.9, 0.95);
}

#[test]
#[ignore = "needs the cables-dev photographs in ../shared/data; scripts/test runs it when they are there"]
fn superpixel_instances_on_true_masks() {
    // Measured: 40 of 45 counts right, instance DICE 0.955, centreline
    // 0.89 px, grasp point 0.92 px.
    assert_instances_on_truth(InstanceMethod::Superpixels, 0.8, 0.93);
}

/// The classical mask on the training photographs' white paper and wood
/// (every third of 00000..00029 keeps the unoptimised test quick). None of
/// them is plain enough for `auto` to choose it (90 % of the pixels near
/// the background's colour), yet forced, it still finds the wires:
/// measured union DICE 0.724 and grasp points 2.9 px from the labelled
/// centre lines on average. The bounds fail on a broken threshold or
/// morphology. (On the held-out cloth and prints it does worse, 0.58;
/// the README's sweep table has the figures.)
const CLASSICAL_PAPER_MIN_DICE: f64 = 0.69;
const CLASSICAL_PAPER_MAX_GRASP_PX: f64 = 4.0;

#[test]
#[ignore = "needs the cables-dev photographs in ../shared/data; scripts/test runs it when they are there"]
fn classical_mask_finds_wires_on_white_paper() {
    let dir = common::cables_dev();
    let mut pipeline = Pipeline::new(VisionConfig {
        mask: MaskMethod::Classical,
        ..VisionConfig::default()
    });
    let mut scores = Vec::new();
    for stem in stems(&dir)
        .into_iter()
        .filter(|stem| stem.as_str() < "00030")
        .step_by(3)
    {
        let path = dir.join(format!("{stem}.jpg"));
        let image = imgcodecs::imread(path.to_str().expect("UTF-8 path"), imgcodecs::IMREAD_COLOR)
            .expect("jpg reads");
        assert!(!image.empty());
        let truth = GroundTruth::load(&dir, &stem).expect("ground truth loads");
        let out = pipeline
            .detect(&image, None)
            .expect("classical pipeline runs");
        assert!(
            !out.plain_background,
            "{stem}: judged plain: {:?}",
            out.background
        );
        scores.push((
            stem,
            eval::score(&out, &truth).expect("the masks are drawn"),
        ));
    }
    print_scores("classical", &scores);
    assert_eq!(scores.len(), 10);
    let only: Vec<ImageScore> = scores.into_iter().map(|(_, s)| s).collect();
    let summary = eval::summarize(&only);
    assert!(
        summary.union_dice >= CLASSICAL_PAPER_MIN_DICE,
        "{summary:?}"
    );
    assert!(
        summary
            .grasp_error_px
            .is_some_and(|d| d <= CLASSICAL_PAPER_MAX_GRASP_PX),
        "{summary:?}"
    );
}
