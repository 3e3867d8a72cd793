//! Scoring the pipeline against ground truth laid out as in the Cables
//! Dataset (De Gregorio et al., arXiv 1810.04461): per image `STEM`, one
//! mask per cable (`STEM_mask_K.png`), their union (`STEM_mask_all.png`)
//! and each cable's polyline (`STEM.txt`, line K: `N x0 y0 x1 y1 ...`).
//!
//! The truth masks were drawn at one width along smoothed curves of the
//! polylines' points (see [`label_curve`]), so their edges are
//! approximate: the scores compare centrelines and counts as well as pixel
//! overlap.
//!
//! - `dataset.rs`: reading an image's ground truth ([`GroundTruth`]);
//! - `labels.rs`: how far the labels agree with themselves;
//! - `score.rs`: what the pipeline found against the truth;
//! - `measure.rs`: mask overlaps and polyline distances both use.

mod dataset;
mod labels;
mod measure;
mod score;

pub use dataset::{GroundTruth, labelled_images};
pub use labels::{LabelConsistency, label_consistency, label_curve};
pub use measure::distance_to_polylines;
pub use score::{
    ALONG_SHARE, CENTRELINE_NEAR_PX, ImageScore, InPieces, MASK_OFFSET_SEARCH_PX, MATCH_MIN_DICE,
    ScoreSummary, Unmatched, best_offset, score, score_cables, summarize,
};
