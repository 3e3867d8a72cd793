//! cablecell: a robot task orchestrator for a vision- and tactile-guided
//! cable-grasping cell. See ARCHITECTURE.md for the map of the parts.

pub mod geometry;
pub mod perception;
