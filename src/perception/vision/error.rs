//! The vision layer's one error type.

use std::path::PathBuf;

/// Why the vision pipeline could not turn an image (or a data set entry)
/// into cable instances. Each variant says what failed and where, so a CLI
/// can report it without a backtrace.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum VisionError {
    /// A ground-truth file (a mask or the centre lines' `STEM.txt`) could
    /// not be read (`source`: the I/O error). Check that the data set
    /// folder holds it and that it can be read.
    #[error("cannot read {path}: {source}")]
    ReadTruth {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// A ground-truth mask is not an image OpenCV can decode (`source`:
    /// OpenCV's error, when it gave one). Check that it is a whole PNG.
    #[error(
        "cannot read image {path}: not a decodable image{}",
        source.as_ref().map(|e| format!(" ({e})")).unwrap_or_default()
    )]
    DecodeTruth {
        path: PathBuf,
        #[source]
        source: Option<opencv::Error>,
    },

    /// The image has no pixels (a failed capture, an empty file). Give the
    /// pipeline a non-empty image.
    #[error("empty image{}", path.as_ref().map(|p| format!(" {}", p.display())).unwrap_or_default())]
    EmptyImage { path: Option<PathBuf> },

    /// The image's pixel type is not one the pipeline reads: it takes
    /// 8- or 16-bit images with 1, 3 or 4 channels (gray, BGR, BGRA).
    #[error(
        "unsupported image type: {channels} channel(s) of depth code {depth} (expected 8- or 16-bit gray, BGR or BGRA)"
    )]
    UnsupportedImage { channels: i32, depth: i32 },

    /// The configured region of interest does not overlap the image. Fix
    /// `roi_px` in the vision configuration.
    #[error(
        "region of interest x={x} y={y} {width}x{height} px lies outside the {cols}x{rows} px image"
    )]
    RoiOutside {
        x: i32,
        y: i32,
        width: i32,
        height: i32,
        cols: i32,
        rows: i32,
    },

    /// The configuration asks for the segmentation network but none was
    /// given. Load one (`--model PATH.onnx` on the CLI) or choose the
    /// classical mask (`mask = "classical"`, or `auto` on a plain background).
    #[error(
        "the network mask was asked for but no segmentation network was given; pass a model (e.g. `--model cables.onnx`) or use the classical or auto mask"
    )]
    NoNetwork,

    /// The segmentation network could not be loaded or run; `source` says
    /// how (model file, ONNX Runtime library, inference, tensor shape) and
    /// its variant's documentation how to fix it.
    #[error("segmentation network failed: {source}")]
    Network {
        #[source]
        source: super::network::NetworkError,
    },

    /// The network returned a mask the pipeline cannot use: it must have
    /// one channel (8-bit 0/255 or 0/1, or 32-bit float probabilities).
    #[error(
        "the network's mask has {channels} channel(s) of depth code {depth} and size {cols}x{rows} px; expected one channel, 8-bit or 32-bit float"
    )]
    BadNetworkMask {
        channels: i32,
        depth: i32,
        cols: i32,
        rows: i32,
    },

    /// An OpenCV call failed at `stage` (a bug or an out-of-memory image).
    #[error("OpenCV failed during {stage}: {source}")]
    OpenCv {
        stage: &'static str,
        #[source]
        source: opencv::Error,
    },

    /// A ground-truth annotation file is malformed at `line` (1-based).
    #[error("ground truth {path}, line {line}: {reason}")]
    BadAnnotation {
        path: PathBuf,
        line: usize,
        reason: String,
    },

    /// A ground-truth mask's size differs from the entry's other masks or
    /// from its image: masks are compared pixel by pixel, so all must be
    /// the image's size.
    #[error(
        "ground truth mask {path} is {cols}x{rows} px, expected {expected_cols}x{expected_rows} px ({expected_from})"
    )]
    TruthMaskSize {
        path: PathBuf,
        cols: i32,
        rows: i32,
        expected_cols: i32,
        expected_rows: i32,
        expected_from: String,
    },

    /// A mask given to find cables in differs in size from its image.
    #[error(
        "the mask is {mask_cols}x{mask_rows} px and its image {image_cols}x{image_rows} px; they must be the same size"
    )]
    MaskSize {
        mask_cols: i32,
        mask_rows: i32,
        image_cols: i32,
        image_rows: i32,
    },

    /// A ground-truth entry has no per-cable masks (`STEM_mask_0.png`).
    #[error("ground truth for {stem} in {dir}: no per-cable masks ({stem}_mask_0.png)")]
    NoTruthMasks { dir: PathBuf, stem: String },

    /// Scoring needs the cables' masks, which the pipeline was set not to
    /// draw.
    #[error("no cable masks to score: the pipeline ran with cable_masks off")]
    NoCableMasks,
}

impl VisionError {
    /// Whether the error lies in what the pipeline was given to work with
    /// (its network: no model, a file that is no network, no runtime)
    /// rather than in an image: every image would fail alike, so the
    /// command's input is at fault.
    pub fn is_in_setup(&self) -> bool {
        match self {
            VisionError::NoNetwork => true,
            VisionError::Network { source } => source.is_in_setup(),
            _ => false,
        }
    }
}

/// Wraps an OpenCV error with the stage it happened in, for `map_err`.
pub(crate) fn cv(stage: &'static str) -> impl FnOnce(opencv::Error) -> VisionError {
    move |source| VisionError::OpenCv { stage, source }
}
