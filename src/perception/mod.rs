//! What the cell's sensors tell about the cable: `tactile` turns taxel
//! voltages into the cable's pose on the pad, `vision` camera images into
//! grasp frames.

pub mod tactile;
pub mod vision;
