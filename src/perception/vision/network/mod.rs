//! The cable segmentation network: an ONNX model (`models/
//! cable_segmentation.onnx`, made by `models/train_segmentation.py`, its
//! model card in `models/README.md`) run with ONNX Runtime through `ort`.
//!
//! The pipeline for a BGR image of W × H (640 × 480 from the camera):
//! 1. resize to the network's size, half the image's rounded to multiples
//!    of 16 (320 × 240; [`SegmentationNet::input_scale`] sets the
//!    fraction), with area averaging (OpenCV's `INTER_AREA`, computed
//!    faster where its factor is not whole: `area_shrink.rs`);
//! 2. feed it as `[1, h, w, 3]`, NHWC, the B, G, R values unscaled: the
//!    bytes themselves to the 8-bit model, float32 0..255 to the float one
//!    (see [`InputKind`]); the model normalises inside;
//! 3. read the probability map `[1, 1, h, w]`, resize it bilinearly to
//!    W × H and keep the pixels above [`SegmentationNet::threshold`] as 255.
//!
//! ONNX Runtime is loaded at run time (`ort`'s `load-dynamic`) from the
//! library the caller names, once per process: `ort` allows one environment
//! per process, so every [`SegmentationNet`] shares it, and a later `load`
//! that names another library is an error.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use opencv::core::{CV_8UC3, Mat, Scalar, Size};
use opencv::prelude::*;
use opencv::{core, imgproc};
use ort::environment::Environment;
use ort::session::Session;
use ort::session::builder::GraphOptimizationLevel;
use ort::value::{DynValueRef, PrimitiveTensorElementType, TensorElementType, TensorRef};

use super::{BackgroundStats, MaskNetwork, VisionError};

mod area_shrink;
mod lazy;
use area_shrink::shrink_by_area;
pub use lazy::LazyNetwork;

/// Intra-op threads of a session: the cell's computer has two cores.
const INTRA_THREADS: usize = 2;

/// Probability above which a pixel is cable, unless set otherwise.
pub const DEFAULT_THRESHOLD: f32 = 0.5;

/// The same in a painted scene, for the shipped busy network
/// ([`BUSY_MODEL`]): the mean of its four looks is a smoother map than one
/// look's, and on real cables over paint it counts most right when cut at
/// 0.4 (`models/history.md`, "The busy network seen four ways"). Looking
/// once, the shipped busy network counts a few more at 0.4 than at
/// [`DEFAULT_THRESHOLD`] (docs/vision-record.md, "The network for busy
/// scenes averaged with two runs from its 8-bit weights").
pub const DEFAULT_BUSY_THRESHOLD: f32 = 0.4;

/// The network's input side over the image's, unless set otherwise. The
/// model was trained at half size; 0.375 (240 × 176 for 640 × 480) is as
/// accurate on the training photographs, finds fewer false cables on the
/// held-out ones, and takes about three quarters of half size's time
/// (README, the sweep table).
pub const DEFAULT_INPUT_SCALE: f64 = 0.375;

/// The network's input side over the image's on a varied or dark background
/// (see [`InputScales`]), unless set otherwise.
pub const DEFAULT_CLOSE_INPUT_SCALE: f64 = 0.5;

/// The network for busy scenes' input side over the image's on a painted
/// background (see [`InputScales`]), unless set otherwise.
pub const DEFAULT_BUSY_INPUT_SCALE: f64 = 0.625;

/// The network's input scales: `normal`; `close` for an image whose
/// background is far from one colour (paint, prints) or dark
/// ([`crate::perception::vision::background::BackgroundStats::closer_look`]);
/// and `busy`, the network for busy scenes' on a painted background
/// ([`crate::perception::vision::background::BackgroundStats::painted`]).
/// There the network tells a cable from paint strokes of its colour, and a
/// tube from dark cloth, better when it looks closer, and the busy network
/// finds more real cables over paint closer still; on the photographs'
/// bright cloth, wood and paper the smaller scale is faster and counts as
/// many right (docs/vision-record.md, "Busy scenes: the paper's kind",
/// "Closer on dark backgrounds too" and "Paint seen closer").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InputScales {
    pub normal: f64,
    pub close: f64,
    pub busy: f64,
}

impl InputScales {
    /// `normal`; `close` when given, else [`DEFAULT_CLOSE_INPUT_SCALE`] or
    /// `normal` where that is larger; `busy` when given, else
    /// [`DEFAULT_BUSY_INPUT_SCALE`] or `close` where that is larger: such a
    /// scene is never looked at less closely than another.
    pub fn new(normal: f64, close: Option<f64>, busy: Option<f64>) -> Self {
        let close = close.unwrap_or(DEFAULT_CLOSE_INPUT_SCALE.max(normal));
        Self {
            normal,
            close,
            busy: busy.unwrap_or(DEFAULT_BUSY_INPUT_SCALE.max(close)),
        }
    }

    /// One scale for every image.
    pub fn fixed(scale: f64) -> Self {
        Self {
            normal: scale,
            close: scale,
            busy: scale,
        }
    }
}

impl Default for InputScales {
    fn default() -> Self {
        Self::new(DEFAULT_INPUT_SCALE, None, None)
    }
}

/// The largest input scale the network is run at: twice the image's size
/// is already far past what the model was trained on.
pub const MAX_INPUT_SCALE: f64 = 2.0;

/// Whether `scale` is an input scale the network can run at: (0, 2].
pub fn input_scale_is_valid(scale: f64) -> bool {
    scale > 0.0 && scale <= MAX_INPUT_SCALE
}

/// The model's input and output names.
const INPUT: &str = "bgr";

/// Errors of the segmentation network. Each keeps what caused it (the
/// I/O, ONNX Runtime or OpenCV error) as its source, and says it in its
/// message too.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum NetworkError {
    /// The model file is missing or unreadable (`source`: the I/O error).
    /// Fix: pass the path of `models/cable_segmentation.onnx` (or retrain
    /// it with `models/train_segmentation.py`).
    #[error("segmentation model {path} is missing or unreadable: {source}")]
    ModelMissing {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The ONNX Runtime library file is missing or cannot be opened
    /// (`source`: the I/O error). Fix: run `scripts/setup`, which puts it
    /// in `.setup/onnxruntime/`, or point `ORT_DYLIB_PATH` at a
    /// `libonnxruntime.so` of version 1.31 or later.
    #[error(
        "ONNX Runtime library {library} could not be used: cannot open the library file: {source} \
         (run scripts/setup, or set ORT_DYLIB_PATH to libonnxruntime.so ≥ 1.31)"
    )]
    RuntimeMissing {
        library: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The path given for the ONNX Runtime library is a folder or another
    /// file that is not a regular file. Fix: as for
    /// [`Self::RuntimeMissing`].
    #[error(
        "ONNX Runtime library {library} could not be used: not a file \
         (run scripts/setup, or set ORT_DYLIB_PATH to libonnxruntime.so ≥ 1.31)"
    )]
    RuntimeNotAFile { library: PathBuf },
    /// Another ONNX Runtime library, `loaded`, is already loaded in this
    /// process, and only one can be. Fix: name the same library
    /// everywhere in one process (`--onnxruntime`, `ORT_DYLIB_PATH`).
    #[error(
        "ONNX Runtime library {library} could not be used: ONNX Runtime is already loaded in this \
         process from {loaded}, and only one library can be loaded per process \
         (run scripts/setup, or set ORT_DYLIB_PATH to libonnxruntime.so ≥ 1.31)"
    )]
    RuntimeConflict { library: PathBuf, loaded: PathBuf },
    /// ONNX Runtime could not be loaded from the library (`source`: `ort`'s
    /// error): a file that is no shared library, or one of too old a
    /// version. Fix: as for [`Self::RuntimeMissing`].
    #[error(
        "ONNX Runtime library {library} could not be used: {source} \
         (run scripts/setup, or set ORT_DYLIB_PATH to libonnxruntime.so ≥ 1.31)"
    )]
    RuntimeLoad {
        library: PathBuf,
        #[source]
        source: ort::LoadDynamicError,
    },
    /// ONNX Runtime, once loaded, could not set up its environment
    /// (`source`: its error). Fix: as for [`Self::RuntimeMissing`].
    #[error(
        "ONNX Runtime library {library} could not be used: {source} \
         (run scripts/setup, or set ORT_DYLIB_PATH to libonnxruntime.so ≥ 1.31)"
    )]
    Runtime {
        library: PathBuf,
        #[source]
        source: ort::Error,
    },
    /// ONNX Runtime could not make a session of the model (`source`: its
    /// error): the file is corrupt or no ONNX model, or one this runtime
    /// cannot run. Fix: use the shipped `models/cable_segmentation.onnx`
    /// or export the model again.
    #[error("segmentation network inference failed: model {path}: {source}")]
    ModelInvalid {
        path: PathBuf,
        #[source]
        source: ort::Error,
    },
    /// The model's input is neither bytes nor float32 (see [`InputKind`]).
    /// Fix: use a model made by `models/train_segmentation.py`.
    #[error(
        "segmentation network inference failed: model {path} takes {found}, expected uint8 or float32"
    )]
    ModelInput { path: PathBuf, found: String },
    /// The model does not have the one input and one output the pipeline
    /// feeds and reads. Fix: use a model made by
    /// `models/train_segmentation.py`.
    #[error(
        "segmentation network inference failed: model {path} has {inputs} inputs and {outputs} \
         outputs, expected one of each"
    )]
    ModelShape {
        path: PathBuf,
        inputs: usize,
        outputs: usize,
    },
    /// ONNX Runtime failed to run the model on an image (`source`: its
    /// error), e.g. out of memory, or a model whose input is not the
    /// image's layout. Fix: check the model and the memory free.
    #[error("segmentation network inference failed: {source}")]
    Inference {
        #[source]
        source: ort::Error,
    },
    /// The image could not be laid out as the network's input tensor
    /// (`source`: ndarray's error): a bug, since the tensor is made from
    /// the resized image. Report it with the image's size.
    #[error("segmentation network inference failed: input tensor: {source}")]
    InputTensor {
        #[source]
        source: ndarray::ShapeError,
    },
    /// The model's output is not one probability per pixel of its input.
    /// Fix: use a model made by `models/train_segmentation.py`.
    #[error(
        "segmentation network inference failed: output of shape {shape:?}, expected [1, 1, {height}, {width}]"
    )]
    OutputShape {
        shape: Vec<i64>,
        width: i32,
        height: i32,
    },
    /// The input image is not what the network takes: it must be a
    /// non-empty 8-bit, 3-channel BGR image. Fix: convert it first (the
    /// pipeline does).
    #[error(
        "segmentation network input image: expected a non-empty 8-bit 3-channel BGR image, \
         got {cols}x{rows} of type {typ}"
    )]
    Image { cols: i32, rows: i32, typ: String },
    /// The network's input scale is outside (0, [`MAX_INPUT_SCALE`]]. Fix:
    /// set `input_scale` (`--net-scale`) within it.
    #[error(
        "segmentation network input image: input scale {scale} is outside (0, {MAX_INPUT_SCALE}]"
    )]
    InputScale { scale: f64 },
    /// An OpenCV operation on the image or the network's output failed at
    /// `stage` (`source`: OpenCV's error): a bug or an out-of-memory image.
    #[error("segmentation network input image: {stage}: {source}")]
    OpenCv {
        stage: &'static str,
        #[source]
        source: opencv::Error,
    },
}

impl NetworkError {
    /// Whether the model or the runtime library is at fault (missing, no
    /// network, the wrong shape, the wrong library) rather than one image.
    pub fn is_in_setup(&self) -> bool {
        matches!(
            self,
            NetworkError::ModelMissing { .. }
                | NetworkError::RuntimeMissing { .. }
                | NetworkError::RuntimeNotAFile { .. }
                | NetworkError::RuntimeConflict { .. }
                | NetworkError::RuntimeLoad { .. }
                | NetworkError::Runtime { .. }
                | NetworkError::ModelInvalid { .. }
                | NetworkError::ModelShape { .. }
                | NetworkError::ModelInput { .. }
                | NetworkError::OutputShape { .. }
        )
    }
}

/// Wraps an OpenCV error with the stage it happened in, for `map_err`.
fn cv(stage: &'static str) -> impl FnOnce(opencv::Error) -> NetworkError {
    move |source| NetworkError::OpenCv { stage, source }
}

/// The ONNX Runtime environment of this process and the library it came
/// from. Behind a mutex rather than a `OnceLock` so that a failed load
/// (a wrong path) leaves it empty for a later, correct one.
static RUNTIME: Mutex<Option<(PathBuf, Environment)>> = Mutex::new(None);

/// The process's ONNX Runtime environment, loading `library` the first time.
fn environment(library: &Path) -> Result<Environment, NetworkError> {
    let library_path = || library.to_path_buf();
    let wanted = library
        .canonicalize()
        .map_err(|source| NetworkError::RuntimeMissing {
            library: library_path(),
            source,
        })?;
    if !wanted.is_file() {
        return Err(NetworkError::RuntimeNotAFile {
            library: library_path(),
        });
    }
    // A panic elsewhere while holding the lock leaves the value consistent.
    let mut runtime = RUNTIME.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((loaded, env)) = runtime.as_ref() {
        if *loaded == wanted {
            return Ok(env.clone());
        }
        return Err(NetworkError::RuntimeConflict {
            library: library_path(),
            loaded: loaded.clone(),
        });
    }
    let env = ort::init_from(&wanted)
        .map_err(|source| NetworkError::RuntimeLoad {
            library: library_path(),
            source,
        })?
        .with_name("cablecell")
        .with_telemetry(false)
        .build()
        .map_err(|source| NetworkError::Runtime {
            library: library_path(),
            source,
        })?;
    *runtime = Some((wanted, env.clone()));
    Ok(env)
}

/// What a model takes as its input tensor, read from the model.
#[derive(Clone, Copy, Debug, PartialEq)]
enum InputKind {
    /// The image's bytes: the 8-bit model, whose first layer reads them as
    /// they are (`models/quantize_segmentation.py`).
    Bytes,
    /// float32 values 0..255: the float model as training exports it.
    Floats,
}

/// The segmentation network, ready to run.
pub struct SegmentationNet {
    session: Session,
    input_kind: InputKind,
    /// Probability above which a pixel is cable in [`Self::mask`];
    /// [`DEFAULT_THRESHOLD`] after [`Self::load`].
    pub threshold: f32,
    /// The network's input side over the image's (see [`network_size`]);
    /// [`DEFAULT_INPUT_SCALE`] after [`Self::load`]. Smaller is faster and
    /// misses thin cables; the model was trained at the default.
    pub input_scale: f64,
    /// Scratch buffers, reused between images (`input` for a float
    /// model only).
    small: Vec<u8>,
    input: Vec<f32>,
}

impl std::fmt::Debug for SegmentationNet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SegmentationNet")
            .field("threshold", &self.threshold)
            .field("input_scale", &self.input_scale)
            .field("input_kind", &self.input_kind)
            .finish_non_exhaustive()
    }
}

/// The network's input size for an image of `width` × `height`: `scale`
/// of it, rounded to multiples of 16 (the model halves its input four
/// times), at least 16.
pub fn network_size(width: i32, height: i32, scale: f64) -> (i32, i32) {
    let round16 = |v: i32| ((f64::from(v) * scale / 16.0).round() as i32).max(1) * 16;
    (round16(width), round16(height))
}

impl SegmentationNet {
    /// Loads `model` into a session on the ONNX Runtime library
    /// `runtime_library` (ort's load-dynamic; see [`runtime_library`]).
    /// The library is loaded once per process: a second `load` naming
    /// another library gives [`NetworkError::Runtime`].
    pub fn load(model: &Path, runtime_library: &Path) -> Result<Self, NetworkError> {
        let model_bytes = std::fs::read(model).map_err(|source| NetworkError::ModelMissing {
            path: model.to_path_buf(),
            source,
        })?;
        let env = environment(runtime_library)?;
        let invalid = |source: ort::Error| NetworkError::ModelInvalid {
            path: model.to_path_buf(),
            source,
        };
        let recover = |e: ort::Error<ort::session::builder::SessionBuilder>| invalid(e.into());
        let session = Session::builder(&env)
            .map_err(invalid)?
            .with_intra_threads(INTRA_THREADS)
            .map_err(recover)?
            .with_inter_threads(1)
            .map_err(recover)?
            .with_optimization_level(GraphOptimizationLevel::All)
            .map_err(recover)?
            .commit_from_memory(&model_bytes)
            .map_err(invalid)?;
        if session.inputs().len() != 1 || session.outputs().len() != 1 {
            return Err(NetworkError::ModelShape {
                path: model.to_path_buf(),
                inputs: session.inputs().len(),
                outputs: session.outputs().len(),
            });
        }
        let input_kind = match session.inputs()[0].dtype().tensor_type() {
            Some(TensorElementType::Uint8) => InputKind::Bytes,
            Some(TensorElementType::Float32) => InputKind::Floats,
            _ => {
                return Err(NetworkError::ModelInput {
                    path: model.to_path_buf(),
                    found: session.inputs()[0].dtype().to_string(),
                });
            }
        };
        tracing::debug!(model = %model.display(), ?input_kind, "segmentation network loaded");
        Ok(Self {
            session,
            input_kind,
            threshold: DEFAULT_THRESHOLD,
            input_scale: DEFAULT_INPUT_SCALE,
            small: Vec::new(),
            input: Vec::new(),
        })
    }

    /// The cable probability of every pixel of a BGR image: CV_32F in
    /// [0, 1], the image's size.
    pub fn probability(&mut self, bgr: &Mat) -> Result<Mat, NetworkError> {
        if bgr.empty() || bgr.typ() != CV_8UC3 {
            return Err(NetworkError::Image {
                cols: bgr.cols(),
                rows: bgr.rows(),
                typ: core::type_to_string(bgr.typ()).unwrap_or_default(),
            });
        }
        if !input_scale_is_valid(self.input_scale) {
            return Err(NetworkError::InputScale {
                scale: self.input_scale,
            });
        }
        let (w, h) = network_size(bgr.cols(), bgr.rows(), self.input_scale);
        shrink_by_area(bgr, Size::new(w, h), &mut self.small)
            .map_err(cv("resize to the network's input size"))?;
        let bytes = self.small.as_slice();
        let shape = (1, h as usize, w as usize, 3);
        let input = match self.input_kind {
            InputKind::Bytes => input_tensor(shape, bytes)?,
            InputKind::Floats => {
                self.input.clear();
                self.input.extend(bytes.iter().map(|&b| f32::from(b)));
                input_tensor(shape, &self.input)?
            }
        };
        let inference = |source: ort::Error| NetworkError::Inference { source };
        let outputs = self
            .session
            .run(ort::inputs![INPUT => input])
            .map_err(inference)?;
        let (shape, data) = outputs[0].try_extract_tensor::<f32>().map_err(inference)?;
        let pixels = (w * h) as usize;
        if shape.iter().product::<i64>() != pixels as i64 || data.len() != pixels {
            return Err(NetworkError::OutputShape {
                shape: shape.to_vec(),
                width: w,
                height: h,
            });
        }
        let small_prob =
            Mat::new_rows_cols_with_data(h, w, data).map_err(cv("wrap the network's output"))?;
        let mut prob = Mat::default();
        imgproc::resize(
            &small_prob,
            &mut prob,
            bgr.size().map_err(cv("image size"))?,
            0.0,
            0.0,
            imgproc::INTER_LINEAR,
        )
        .map_err(cv("resize the probabilities to the image's size"))?;
        Ok(prob)
    }

    /// The cable mask of a BGR image: CV_8U, 0 or 255, the image's size; 255
    /// where the probability exceeds [`Self::threshold`].
    pub fn mask(&mut self, bgr: &Mat) -> Result<Mat, NetworkError> {
        let prob = self.probability(bgr)?;
        let mut mask = Mat::default();
        core::compare(
            &prob,
            &Scalar::all(f64::from(self.threshold)),
            &mut mask,
            core::CMP_GT,
        )
        .map_err(cv("threshold the probabilities"))?;
        Ok(mask)
    }
}

/// `data` borrowed as the model's input tensor of `shape` (NHWC), of
/// whichever element type the model takes.
fn input_tensor<T: PrimitiveTensorElementType + std::fmt::Debug + Clone + 'static>(
    shape: (usize, usize, usize, usize),
    data: &[T],
) -> Result<DynValueRef<'_>, NetworkError> {
    let view = ndarray::ArrayView4::from_shape(shape, data)
        .map_err(|source| NetworkError::InputTensor { source })?;
    let tensor =
        TensorRef::from_array_view(view).map_err(|source| NetworkError::Inference { source })?;
    Ok(tensor.into_dyn())
}

/// Where the ONNX Runtime library is when nothing says otherwise: where
/// `scripts/setup` puts it, in the checkout this binary was built from, so
/// that it is found from any working directory.
const DEFAULT_RUNTIME_LIBRARY: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/.setup/onnxruntime/libonnxruntime.so.1.31.1"
);

/// The shipped segmentation network, in the checkout this binary was built
/// from: 8-bit, quantized from [`FLOAT_MODEL`], whose masks it matches,
/// its mask step about 1.4 times as fast.
pub const DEFAULT_MODEL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/models/cable_segmentation.onnx"
);

/// The float network the shipped one was quantized from, kept to compare
/// their speed and accuracy (`eval-vision --sweep`).
pub const FLOAT_MODEL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/models/cable_segmentation_float.onnx"
);

/// The shipped network wrapped to see the image mirrored too
/// (`models/mirror_segmentation.py`): the mean of its probabilities on the
/// image and on its mirror image, in twice the time; it counts more cables
/// right on busy scenes (`models/history.md`, "The mirrored network").
pub const MIRRORED_MODEL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/models/cable_segmentation_mirrored.onnx"
);

/// The network for busy scenes (paint, prints, mosaics): two fine-tunes
/// of the shipped one on more of them, averaged and quantized
/// (`models/history.md`, "The network for busy scenes"). It counts more
/// real cables over paint right but fewer on the photographs' tables and
/// grasps worse on a workbench, so it sees the painted scenes alone
/// ([`LazyNetwork::with_busy_model`]). It sees the image and its three
/// mirror images (left for right, top for bottom, both), averaged
/// (`models/mirror_segmentation.py --looks 4`): in four times the
/// network's time on those scenes it counts more cables right and grasps
/// nearer their centre lines (`models/history.md`, "The busy network seen
/// four ways").
pub const BUSY_MODEL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/models/cable_segmentation_busy_mirrored.onnx"
);

/// The ONNX Runtime library to load: `given`, else `$ORT_DYLIB_PATH`, else
/// where the set-up puts it.
pub fn runtime_library(given: Option<&Path>) -> PathBuf {
    given
        .map(Path::to_path_buf)
        .or_else(|| std::env::var_os("ORT_DYLIB_PATH").map(PathBuf::from))
        .unwrap_or_else(|| PathBuf::from(DEFAULT_RUNTIME_LIBRARY))
}

/// The pipeline's view of the network: its probabilities, which the
/// pipeline cuts at [`SegmentationNet::threshold`] and which weigh each
/// detection's confidence.
impl MaskNetwork for SegmentationNet {
    /// At its one [`SegmentationNet::input_scale`], whatever the
    /// background.
    fn mask(&mut self, bgr: &Mat, _background: &BackgroundStats) -> Result<Mat, VisionError> {
        self.probability(bgr)
            .map_err(|source| VisionError::Network { source })
    }

    fn threshold(&self, _background: &BackgroundStats) -> f64 {
        f64::from(self.threshold)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_closer_scene_is_never_seen_at_a_smaller_scale_unless_told() {
        let scales = |normal, close, busy| {
            let s = InputScales::new(normal, close, busy);
            (s.normal, s.close, s.busy)
        };
        assert_eq!(scales(0.375, None, None), (0.375, 0.5, 0.625));
        assert_eq!(scales(0.75, None, None), (0.75, 0.75, 0.75));
        assert_eq!(scales(0.375, Some(0.7), None), (0.375, 0.7, 0.7));
        // Given, each is kept as it is: a cell may trade accuracy for time.
        assert_eq!(scales(0.375, Some(0.5), Some(0.4)), (0.375, 0.5, 0.4));
        assert_eq!(InputScales::default(), InputScales::new(0.375, None, None));
    }

    #[test]
    fn network_size_scales_and_rounds_to_16() {
        assert_eq!(network_size(640, 480, 0.5), (320, 240));
        assert_eq!(network_size(1280, 720, 0.5), (640, 368));
        assert_eq!(network_size(10, 10, 0.5), (16, 16));
        assert_eq!(network_size(640, 480, 0.375), (240, 176));
        assert_eq!(network_size(640, 480, 1.0), (640, 480));
    }
}
