//! What the cell's sensors tell about the cable: `tactile` turns taxel
//! voltages into the cable's pose on the pad, `vision` camera images into
//! grasp frames; `shape` holds a cable's centre line in the base frame
//! from either, and `fusion` fits one curve to both (the paper's Fig. 12).

pub mod fusion;
pub mod shape;
pub mod tactile;
pub mod vision;
