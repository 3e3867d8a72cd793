//! What the pipeline is asked to do: how the mask is made, how it is
//! split into cables, and the sizes and lengths that judge what is found.

use opencv::core::Rect;
use schemars::JsonSchema;

use crate::perception::vision::superpixels;
#[cfg(doc)]
use {
    super::MAX_ENLARGEMENT, super::straight_edge::EDGE_SIDES_RATIO,
    crate::perception::vision::background, crate::perception::vision::mask,
};

/// How the cables' mask is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum MaskMethod {
    /// The classical threshold when the background is plain and its mask
    /// not in doubt (see [`mask::classical_doubt`]), else the
    /// network (or, with no network, the classical threshold with a note).
    Auto,
    /// Colour distance from the background, Otsu, morphology.
    Classical,
    /// The segmentation network.
    Network,
}

/// How the mask is split into cables.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum InstanceMethod {
    /// Skeleton graph, its branches paired at junctions by least bending
    /// and by colour (fast).
    Skeleton,
    /// The paper's: SLIC superpixels on the mask and walks on their
    /// adjacency graph.
    Superpixels,
}

/// What the pipeline does and where. Lengths and areas in px are those
/// of the image as worked on, [`Self::work_width_px`] wide.
#[derive(Clone, Debug)]
pub struct VisionConfig {
    /// `Auto` by default, which runs without a network too; the commands
    /// and the shipped cell files take `Network`, the more accurate on
    /// plain backgrounds as well (docs/vision.md, "The pipeline").
    pub mask: MaskMethod,
    pub instances: InstanceMethod,
    /// Images are worked on at this width, a wider one shrunk and a
    /// narrower one enlarged (by at most [`MAX_ENLARGEMENT`]), and what is
    /// found is mapped back to the image's pixels: the network and the
    /// lengths here were tuned on 640 px wide images, where a wire is
    /// about 6 px across; at a finer camera's resolution they would take
    /// edges and scraps for cables and several times as long, at a coarser
    /// one they would lose the wires. 0 works at the image's own size.
    pub work_width_px: u32,
    /// Bound all work to this region when known (the table, the fixture):
    /// it saves time and keeps clutter outside it from becoming cables.
    pub roi_px: Option<Rect>,
    /// Paths shorter than this are dropped: scraps of mask, not cables. On
    /// a busy background (see [`background::BackgroundStats::busy`]) the limit
    /// is [`BUSY_MIN_LENGTH_FACTOR`] times this: scraps and splashes of
    /// paint that the network marks come longer.
    pub min_cable_length_px: f64,
    /// Paths that run out of the region worked on and are shorter than
    /// this are dropped too: too little of such a cable is in view to
    /// grasp it, and the middle of what is seen is not the cable's middle.
    /// The network marks a cable's bare metal end as cable, so the length
    /// takes in a ferrule of up to 10 px beside 80 px of insulation.
    /// Where the mask holds nothing but cables (no busy background, and no
    /// network mask on a background with paint), the skeleton's length
    /// plus the image's cable width is measured: the cable's length in
    /// view.
    pub min_border_cable_length_px: f64,
    /// Paths straighter than an arc of this radius (px), and within 3 px
    /// of straight, are dropped, as are paths within 1.5 px of straight
    /// however short: the network takes edges of paper, folders and tables
    /// for cables, and a cable lying loose is never that straight (the
    /// straightest in cables-dev's training photographs bends like a 730 px
    /// arc). On a background plain around each pixel off the cables (see
    /// [`mask::plain_locally`]), such a path is kept when the background is
    /// alike on its two sides (see [`EDGE_SIDES_RATIO`]): an edge has two
    /// different sides. On a busy background (paint, prints, mosaics; see
    /// [`background::BackgroundStats::busy`]) every path is kept: the edges this
    /// is for lie on tables, and it dropped the straight cables on paint.
    /// 0 keeps every path: for a cell whose cable is held taut.
    pub straight_edge_radius_px: f64,
    /// Mask blobs smaller than this are dropped as noise before the
    /// instances are looked for.
    pub min_blob_area_px: f64,
    /// Points sampled along each spline at uniform s (for display and
    /// scoring).
    pub samples_per_cable: usize,
    /// Superpixel side in cable widths for [`InstanceMethod::Superpixels`]
    /// (smaller: more superpixels, slower).
    pub superpixel_widths: f64,
    /// Draw each cable's mask and their union, in the image's size, for
    /// writing and scoring them. Grasp frames need neither, and at
    /// 1920 × 1440 the masks take about as long as the network, so the
    /// cell's detector leaves them out.
    pub cable_masks: bool,
    /// Detections less confident than this (see `confidence.rs`) are
    /// dropped as probably not cables: splashes of paint, brushed strokes, flat paint.
    /// On a painted background (see [`background::BackgroundStats::painted`])
    /// the floor is [`PAINTED_MIN_CONFIDENCE_FACTOR`] times this.
    pub min_confidence: f64,
}

/// The confidence below which a detection is dropped, unless a cell or
/// the command line says otherwise (docs/vision.md, "Confidence").
pub const DEFAULT_MIN_CONFIDENCE: f64 = 0.45;

/// How many times [`VisionConfig::min_confidence`] a detection must be on
/// a painted background (paint, prints, mosaics of many colours), where
/// more of what the network marks is paint (docs/vision-record.md, "A
/// higher floor on paint", "The floor on paint with four looks", "Paint
/// seen closer").
pub const PAINTED_MIN_CONFIDENCE_FACTOR: f64 = 1.35;

/// How many times [`VisionConfig::min_cable_length_px`] a path must be on
/// a busy background, where the network marks scraps and splashes of
/// paint longer than scraps of mask (docs/vision-record.md, "Scraps of
/// paint").
pub const BUSY_MIN_LENGTH_FACTOR: f64 = 2.0;

impl Default for VisionConfig {
    fn default() -> Self {
        VisionConfig {
            mask: MaskMethod::Auto,
            instances: InstanceMethod::Skeleton,
            work_width_px: 640,
            roi_px: None,
            min_cable_length_px: 40.0,
            min_border_cable_length_px: 90.0,
            straight_edge_radius_px: 1500.0,
            min_blob_area_px: 80.0,
            samples_per_cable: 50,
            superpixel_widths: superpixels::DEFAULT_REGION_WIDTHS,
            cable_masks: true,
            min_confidence: DEFAULT_MIN_CONFIDENCE,
        }
    }
}
