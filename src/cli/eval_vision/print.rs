//! What `eval-vision` prints: the scores, the length shares, the offsets
//! and the cables left unmatched, or the JSON report.

use crate::cli::output::outln;
use std::path::Path;

use cablecell::campaign::stats::{Rate, Summary};
use cablecell::perception::vision::eval::{
    ALONG_SHARE, CENTRELINE_NEAR_PX, ImageScore, MASK_OFFSET_SEARCH_PX, Unmatched,
};

use super::score::{found_length_labelled, labelled_length_found};
use super::{LengthShare, Report};

/// Images whose share is lower than this are named, lowest first.
const LOW_LENGTH_SHARE: f64 = 0.9;

/// A [`LengthShare`] and the images where it was lowest.
fn print_length_share(
    name: &str,
    what: &str,
    share: &Option<LengthShare>,
    per_image: &[(String, ImageScore)],
    side: fn(&ImageScore) -> (f64, f64),
) {
    let Some(share) = share else {
        return;
    };
    let mut low: Vec<(&str, f64)> = per_image
        .iter()
        .filter_map(|(stem, s)| {
            let (length_px, near_px) = side(s);
            (length_px > 0.0)
                .then(|| near_px / length_px)
                .filter(|&image_share| image_share < LOW_LENGTH_SHARE)
                .map(|image_share| (stem.as_str(), image_share))
        })
        .collect();
    low.sort_by(|a, b| a.1.total_cmp(&b.1));
    let low: Vec<String> = low
        .iter()
        .map(|(stem, image_share)| format!("{stem} {:.0} %", 100.0 * image_share))
        .collect();
    let lowest = if low.is_empty() {
        String::new()
    } else {
        format!(
            "; under {:.0} % in {}",
            100.0 * LOW_LENGTH_SHARE,
            low.join(", ")
        )
    };
    outln!(
        "  {name:<22} {:.1} % of {:.0} px {what} (within {CENTRELINE_NEAR_PX} px){lowest}",
        100.0 * share.share,
        share.length_px
    );
}

/// A summary as printed: mean, median, 95th percentile and maximum.
fn summary(s: &Summary) -> String {
    format!(
        "mean {:.3}  median {:.3}  p95 {:.3}  max {:.3}",
        s.mean, s.median, s.p95, s.max
    )
}

pub(super) fn print_evaluation(dir: &Path, report: &Report) {
    let e = &report.evaluation;
    outln!("{}: {} images", dir.display(), e.images);
    let line = |name: &str, s: &Option<Summary>| {
        if let Some(s) = s {
            outln!("  {name:<22} {}", summary(s));
        }
    };
    line("union IoU", &e.union_iou);
    line("union DICE", &e.union_dice);
    print_offsets(&e.union_dice_at_offset, &e.per_image);
    if let Some(labels) = &report.labels_own_union_dice {
        outln!(
            "  {:<22} {}  (the labelled centre lines, smoothed as the masks were drawn, {:.1} px wide against the labelled masks)",
            "labels' own union DICE",
            summary(&labels.union_dice),
            labels.width_px
        );
    }
    line("instance DICE", &e.instance_dice);
    if let Some(rate) = &e.count_right {
        outln!(
            "  {:<22} {}/{} = {:.0} % [{:.0}, {:.0}] (95 % CI)",
            "instance count right",
            rate.successes,
            rate.trials,
            100.0 * rate.rate,
            100.0 * rate.ci95_low,
            100.0 * rate.ci95_high
        );
    }
    let miscounted: Vec<String> = e
        .per_image
        .iter()
        .filter(|(_, score)| !score.count_right)
        .map(|(stem, score)| {
            format!(
                "{stem} ({} found, {} labelled)",
                score.predicted_count, score.truth_count
            )
        })
        .collect();
    if !miscounted.is_empty() {
        outln!("  {:<22} {}", "count wrong in", miscounted.join(", "));
    }
    print_unmatched(
        "labelled, not found",
        e.per_image
            .iter()
            .map(|(stem, s)| (stem, s.truth_count, &s.missed)),
    );
    print_unmatched(
        "found, not labelled",
        e.per_image
            .iter()
            .map(|(stem, s)| (stem, s.predicted_count, &s.unlabelled)),
    );
    print_in_pieces(e.labels_in_pieces.as_ref(), &e.per_image);
    print_length_share(
        "labelled length found",
        "of the labelled centre lines, near a found one",
        &e.labelled_length_found,
        &e.per_image,
        labelled_length_found,
    );
    print_length_share(
        "found length labelled",
        "of the found centre lines, near a labelled one",
        &e.found_length_labelled,
        &e.per_image,
        found_length_labelled,
    );
    line("centerline px", &e.centerline_px);
    line("grasp error px", &e.grasp_error_px);
    if let Some(rate) = &e.grasps_near_label {
        outln!(
            "  {:<22} {}/{} = {:.1} % [{:.1}, {:.1}] (95 % CI) of the reported cables, grasp point within {CENTRELINE_NEAR_PX} px of a labelled centre line",
            "grasp near a label",
            rate.successes,
            rate.trials,
            100.0 * rate.rate,
            100.0 * rate.ci95_low,
            100.0 * rate.ci95_high
        );
    }
    if let Some(rate) = &e.first_grasps_near_label {
        outln!(
            "  {:<22} {}/{} = {:.1} % [{:.1}, {:.1}] (95 % CI) of the images with a cable found, the most confident one's grasp point within {CENTRELINE_NEAR_PX} px of a labelled centre line (the task grasps it first)",
            "first grasp near label",
            rate.successes,
            rate.trials,
            100.0 * rate.rate,
            100.0 * rate.ci95_low,
            100.0 * rate.ci95_high
        );
    }
    if e.mask_used.labelled > 0 {
        outln!(
            "  {:<22} the labelled one in {} of the images (--labelled-mask)",
            "mask used",
            e.mask_used.labelled
        );
    } else {
        outln!(
            "  {:<22} classical in {}, network in {} of the images",
            "mask used",
            e.mask_used.classical,
            e.mask_used.network
        );
    }
    for (stage, s) in &e.stage_ms {
        outln!(
            "  {:<22} median {:.2} ms  p95 {:.2} ms",
            format!("{stage} time"),
            s.median,
            s.p95
        );
    }
    for (stem, note) in &e.notes {
        outln!("  note: {stem}: {note}");
    }
}

/// The labelled cables found in pieces, with the images and pieces.
fn print_in_pieces(rate: Option<&Rate>, per_image: &[(String, ImageScore)]) {
    let Some(rate) = rate else {
        return;
    };
    let listed: Vec<String> = per_image
        .iter()
        .flat_map(|(stem, s)| {
            s.in_pieces
                .iter()
                .map(move |p| format!("{stem} #{} ({} pieces)", p.index, p.pieces))
        })
        .collect();
    let list = if listed.is_empty() {
        String::new()
    } else {
        format!(": {}", listed.join(", "))
    };
    outln!(
        "  {:<22} {} of {} labelled cables, two or more found cables lying along one ({:.0} % of each within {CENTRELINE_NEAR_PX} px of it){list}",
        "found in pieces",
        rate.successes,
        rate.trials,
        100.0 * ALONG_SHARE
    );
}

/// Images whose found mask moves this far (px, along either axis) to
/// match its labels best are named.
const LARGE_OFFSET_PX: i32 = 2;

/// The union DICE with the found masks moved onto the labels, the median
/// move, and the images moved [`LARGE_OFFSET_PX`] or more.
fn print_offsets(dice: &Option<Summary>, per_image: &[(String, ImageScore)]) {
    let Some(dice) = dice else {
        return;
    };
    let median_px = |axis: usize| {
        let moves: Vec<f64> = per_image
            .iter()
            .map(|(_, s)| f64::from(s.mask_offset_px[axis]))
            .collect();
        Summary::of(&moves).map_or(0.0, |s| s.median)
    };
    let large: Vec<String> = per_image
        .iter()
        .filter(|(_, s)| s.mask_offset_px.iter().any(|d| d.abs() >= LARGE_OFFSET_PX))
        .map(|(stem, s)| format!("{stem} ({}, {})", s.mask_offset_px[0], s.mask_offset_px[1]))
        .collect();
    let large = if large.is_empty() {
        String::new()
    } else {
        format!("; {LARGE_OFFSET_PX} px or more in {}", large.join(", "))
    };
    outln!(
        "  {:<22} {}  (each image's found mask moved by the whole pixels, up to {MASK_OFFSET_SEARCH_PX}, that match its labels best; median move (dx, dy) ({}, {}) px{large})",
        "union DICE, moved",
        summary(dice),
        median_px(0),
        median_px(1),
    );
}

/// One line listing the cables of one side that none of the other side
/// matches, from (image, cables on that side, unmatched ones) per image:
/// "3 of 83: 00034 #7 (52 px, at the border), ...".
fn print_unmatched<'a>(
    what: &str,
    per_image: impl Iterator<Item = (&'a String, usize, &'a Vec<Unmatched>)>,
) {
    let (mut total, mut listed) = (0, Vec::new());
    for (stem, count, unmatched) in per_image {
        total += count;
        listed.extend(unmatched.iter().map(|u| {
            let length = u
                .length_px
                .map_or("no line".to_string(), |l| format!("{l:.0} px"));
            let border = if u.at_border { ", at the border" } else { "" };
            format!("{stem} #{} ({length}{border})", u.index)
        }));
    }
    if total > 0 {
        let of = format!("{} of {total}", listed.len());
        let list = if listed.is_empty() {
            String::new()
        } else {
            format!(": {}", listed.join(", "))
        };
        outln!("  {what:<22} {of}{list}");
    }
}
