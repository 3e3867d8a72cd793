//! From a camera image to grasp frames (the paper's Section II): a mask of
//! the cables (a classical threshold on a plain background, else the
//! segmentation network), one instance per cable, a B-spline along each,
//! and the grasp frame at its middle.
