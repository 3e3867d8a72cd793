//! cablecell: a robot task orchestrator for a vision- and tactile-guided
//! cable-grasping cell. ARCHITECTURE.md maps the parts.

pub mod campaign;
pub mod cell;
pub mod detector;
pub mod geometry;
pub mod hw;
pub mod orchestrator;
pub mod perception;
pub mod plot;
pub mod record;
pub mod recording;
pub mod schema;
pub mod sim;
pub mod task;
