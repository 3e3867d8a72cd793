//! The vision pipeline: image → mask → one path per cable → B-spline →
//! grasp point and direction, each stage timed.
//!
//! - `config.rs`: what the pipeline is asked to do ([`VisionConfig`]);
//! - `detect.rs`: a run, stage by stage ([`Pipeline::detect`]);
//! - `mask_choice.rs`: which mask a run takes, classical or network;
//! - `work_area.rs`: the region of interest and the working size, what
//!   the network sees around the region, and the map back to the image's
//!   pixels;
//! - `straight_edge.rs`: straight detections dropped as edges;
//! - `confidence.rs`: how much a detection looks like a cable;
//! - `draw.rs`: paths and cables drawn as masks;
//! - `freed_memory.rs`: the memory a run frees kept for the next;
//! - `output.rs`: what a run found ([`VisionOutput`]).

mod confidence;
mod config;
mod detect;
mod draw;
mod freed_memory;
mod mask_choice;
mod output;
mod straight_edge;
mod work_area;

use std::time::Instant;

pub use config::{
    DEFAULT_MIN_CONFIDENCE, InstanceMethod, MaskMethod, PAINTED_MIN_CONFIDENCE_FACTOR, VisionConfig,
};
pub(crate) use draw::draw_paths;
pub use draw::union_mask;
pub use mask_choice::MaskNetwork;
pub use output::{
    CableInstance, MaskInstances, VisionOutput, VisionSkip, first_to_grasp, grasp_order,
};
pub use work_area::MAX_ENLARGEMENT;

/// The vision pipeline, configured once and run per image.
pub struct Pipeline {
    config: VisionConfig,
}

fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

impl Pipeline {
    pub fn new(config: VisionConfig) -> Self {
        freed_memory::keep_freed_memory();
        Pipeline { config }
    }

    pub fn config(&self) -> &VisionConfig {
        &self.config
    }
}
