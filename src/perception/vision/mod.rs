//! From a camera image to grasp frames (the paper's Section II): a mask of
//! the cables (a classical threshold on a plain background, else the
//! segmentation network), one instance per cable, a B-spline along each,
//! and the grasp frame at its middle.

pub mod background;
pub mod calibration;
pub mod curves;
pub mod error;
pub mod eval;
pub mod grasp_frame;
pub mod mask;
pub mod network;
pub mod paths;
pub mod pipeline;
mod runs;
pub mod skeleton;
pub mod spline;
pub mod superpixels;

pub use background::BackgroundStats;
pub use error::VisionError;
pub use eval::{GroundTruth, ImageScore, ScoreSummary, score, score_cables, summarize};
pub use pipeline::{
    CableInstance, DEFAULT_MIN_CONFIDENCE, InstanceMethod, MaskInstances, MaskMethod, MaskNetwork,
    PAINTED_MIN_CONFIDENCE_FACTOR, Pipeline, VisionConfig, VisionOutput, VisionSkip, union_mask,
};
pub use spline::BSpline;
