//! What the pipeline finds: the cables, each in the image's pixels, and
//! how it found them.

use opencv::core::Mat;
use schemars::JsonSchema;

use super::config::MaskMethod;
use crate::perception::vision::mask::BackgroundStats;
use crate::perception::vision::spline::BSpline;
#[cfg(doc)]
use {super::config::VisionConfig, crate::perception::vision::mask};

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
    /// This cable's pixels: CV_8U 0/255, the image's size (cables overlap
    /// at crossings); `None` unless [`VisionConfig::cable_masks`].
    #[serde(skip)]
    pub mask: Option<Mat>,
}

/// What the pipeline found, and how.
#[derive(Debug)]
pub struct VisionOutput {
    pub cables: Vec<CableInstance>,
    /// The mask method actually run: `Classical` or `Network`.
    pub mask_used: MaskMethod,
    /// Whether the background was judged plain (see
    /// [`mask::PLAIN_MIN_FRACTION`]).
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
    /// Milliseconds for "instances", "spline", and "instance_masks" when
    /// the cables' masks are drawn.
    pub timings_ms: Vec<(&'static str, f64)>,
}
