//! What the pipeline finds: the cables, each in the image's pixels, and
//! how it found them.

use std::cmp::Ordering;

use opencv::core::Mat;
use schemars::JsonSchema;

use super::config::MaskMethod;
use crate::perception::vision::background::BackgroundStats;
use crate::perception::vision::spline::BSpline;
#[cfg(doc)]
use {super::config::VisionConfig, crate::perception::vision::background};

/// One cable found in the image, in full-image pixel coordinates (x right,
/// y down), whatever the region of interest.
#[derive(Clone, Debug, serde::Serialize, JsonSchema)]
pub struct CableInstance {
    /// The cable's model, s = 0 at one end (the one with the smaller x) and
    /// s = 1 at the other.
    pub spline: BSpline,
    /// Points at uniform s from 0 to 1.
    pub samples_px: Vec<[f64; 2]>,
    /// The grasp point: the spline at s = 0.5.
    pub grasp_px: [f64; 2],
    /// The cable's direction at the grasp point: atan2(dy, dx) of the chord
    /// from s = 0.45 to s = 0.55, in image coordinates (y down).
    pub direction_rad: f64,
    /// Length of the skeleton path the spline was fitted to.
    pub length_px: f64,
    /// How much it looks like a cable, 0 to 1: long against its width,
    /// equally wide along it, as wide as the image's other cables.
    pub confidence: f64,
    /// This cable's pixels: CV_8U 0/255, the image's size (cables overlap
    /// at crossings); `None` unless [`VisionConfig::cable_masks`].
    #[serde(skip)]
    pub mask: Option<Mat>,
}

/// The order in which the task grasps cables, from each one's confidence
/// and length: the more confident first, the longer of two equally
/// confident. `Less` puts the first cable before the second.
pub fn grasp_order(
    confidence: f64,
    length_px: f64,
    other_confidence: f64,
    other_length_px: f64,
) -> Ordering {
    other_confidence
        .total_cmp(&confidence)
        .then(other_length_px.total_cmp(&length_px))
}

/// The cable the task would grasp first (see [`grasp_order`]); `None`
/// when there is none.
pub fn first_to_grasp(cables: &[CableInstance]) -> Option<&CableInstance> {
    cables
        .iter()
        .min_by(|a, b| grasp_order(a.confidence, a.length_px, b.confidence, b.length_px))
}

/// What the pipeline found, and how.
#[derive(Debug)]
pub struct VisionOutput {
    pub cables: Vec<CableInstance>,
    /// The mask method actually run: `Classical` or `Network`.
    pub mask_used: MaskMethod,
    /// Whether the background was judged plain (see
    /// [`background::PLAIN_MIN_FRACTION`]).
    pub plain_background: bool,
    /// The background statistics behind that judgement.
    pub background: BackgroundStats,
    /// The union of the cables' masks: CV_8U 0/255, the image's size.
    /// Mask pixels no cable took (scraps, stubs at the border) are not in
    /// it. `None` unless [`VisionConfig::cable_masks`].
    pub union_mask: Option<Mat>,
    /// The cables' typical width (mask area over skeleton length).
    pub cable_width_px: f64,
    /// The image's size as worked on over its own (see
    /// [`VisionConfig::work_width_px`]).
    pub work_scale: f64,
    /// Milliseconds per stage, in order: "prepare", "mask", "instances",
    /// "spline", and "instance_masks" when the cables' masks are drawn.
    pub timings_ms: Vec<(&'static str, f64)>,
    /// What a user should know about this run (fallbacks taken,
    /// detections dropped as edges or as cables too little in view).
    pub notes: Vec<String>,
    /// Work this run left out because the image did not need it.
    pub skipped: Vec<VisionSkip>,
}

/// Work a run of the pipeline left out because the scene did not need
/// it: said out loud so that a run's report shows where its time went and
/// where it did not.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, JsonSchema)]
#[serde(tag = "what", rename_all = "snake_case")]
pub enum VisionSkip {
    /// The background is plain and its classical mask not in doubt: the
    /// segmentation network did not run.
    Network {
        /// The share of pixels near the background's colour.
        near_fraction: f64,
    },
    /// The mask's skeleton has no junction: no crossing to resolve, so no
    /// branches were paired.
    CrossingResolution,
    /// Only the region of interest was worked on.
    ImageOutsideRoi {
        /// The share of the image's pixels inside the region.
        worked_fraction: f64,
    },
    /// The cables' masks were not drawn: grasp frames need only their
    /// centre lines.
    CableMasks,
}

impl VisionSkip {
    /// Why the work was not needed, for a report.
    pub fn why(&self) -> String {
        match self {
            VisionSkip::Network { near_fraction } => format!(
                "plain background ({:.0} % of pixels near its colour) and the classical mask not in doubt",
                100.0 * near_fraction
            ),
            VisionSkip::CrossingResolution => {
                "no junction in the mask's skeleton: no cables cross".to_owned()
            }
            VisionSkip::ImageOutsideRoi { worked_fraction } => format!(
                "a region of interest: {:.0} % of the image worked on",
                100.0 * worked_fraction
            ),
            VisionSkip::CableMasks => "grasp frames need only the centre lines".to_owned(),
        }
    }
}

/// The instances found in a given mask (for testing the later stages on
/// ground-truth masks).
#[derive(Debug)]
pub struct MaskInstances {
    pub cables: Vec<CableInstance>,
    pub cable_width_px: f64,
    /// Paths dropped as straight edges (see
    /// [`VisionConfig::straight_edge_radius_px`]).
    pub straight_dropped: usize,
    /// Paths dropped as running out of view too short (see
    /// [`VisionConfig::min_border_cable_length_px`]).
    pub border_dropped: usize,
    /// Paths dropped as probably not cables (see
    /// [`VisionConfig::min_confidence`]).
    pub unconfident_dropped: usize,
    /// Milliseconds for "instances", "spline", and "instance_masks" when
    /// the cables' masks are drawn.
    pub timings_ms: Vec<(&'static str, f64)>,
    /// Junctions whose branches were paired, when the instance method has
    /// such a stage (see [`crate::perception::vision::paths::FoundPaths`]).
    pub junctions: Option<usize>,
}
