//! From taxel readings to the cable's pose on the pad (paper, Section III).
//!
//! The pipeline of the paper's `read_sensor_node` and `wire_params_node`:
//! raw 12-bit counts ([`RawFrame`]) lose their per-taxel offsets
//! ([`BiasEstimator`], [`Bias`]) to become a [`TactileMap`] of Δv, and
//! [`fit_wire`] finds the cable's direction, one centroid per column or
//! row, and a linear and a quadratic model of the cable through them.
//!
//! When the camera cannot place the cable, [`search`] says where to grasp
//! until the pad feels it.
//!
//! Frame and taxel numbering are the paper's (see [`crate::geometry`]):
//! origin at the centre of c33, x towards c35, y towards c13.

pub mod bias;
pub mod estimator;
pub mod fit;
pub mod map;
pub mod ridge_fit;
pub mod search;

pub use bias::{Bias, BiasEstimator, PAPER_BIAS_SAMPLES, RawFrame};
pub use estimator::{Estimate, Estimator};
pub use fit::{
    CONTACT_THRESHOLD_V, Centroid, Direction, FitCondition, FitConfig, FitError, PAPER_PITCH_MM,
    Quadratic, WireFit, fit_wire,
};
pub use map::{
    ADC_MAX, MapError, PAD_HALF_SIDE_PITCH, TAXEL_COLS, TAXEL_COUNT, TAXEL_ROWS, TactileMap,
    raw_to_volts,
};
