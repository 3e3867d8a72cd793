//! Writes a run's recording as it happens: to an MCAP file, to the live
//! view's WebSocket server, or both, the same bytes to each.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use foxglove::Encode;
use mcap::records::{MessageHeader, Metadata};
use nalgebra::{Isometry3, Point3};
use opencv::core::VectorToVec;
use serde::Serialize;

use super::RecordingError;
use super::live::LiveServer;
use super::scene::{self, CellView};
use super::schema::{
    CableShapesMessage, CompressedImageMessage, LogMessage, Pose, PoseInFrameMessage, Quaternion,
    RunMessage, TactileDvMessage, TactileFitMessage, TactileRawMessage, Timestamp, Topic,
    TransitionMessage, Vector3, WallClock, WireParamsMessage,
};
use crate::detector::Detections;
use crate::hw::camera::CameraImage;
use crate::hw::tactile::TactileFrame;
use crate::perception::shape::ShapePoint;
use crate::perception::tactile::{
    Bias, BiasEstimator, Estimate, Estimator, FitConfig, TactileMap, fit_wire,
};
use crate::record::{GraspRecord, GraspShapes, RunOutcome, RunRecord, TransitionRecord};

/// Where a recorder writes, and what the file's metadata record says of
/// the run.
pub struct RecordingTarget<'a> {
    /// The MCAP file to create, if any.
    pub file: Option<&'a Path>,
    /// The live view to publish on, if any.
    pub live: Option<Arc<LiveServer>>,
    /// The `cablecell` metadata record beside the version: task, cell,
    /// seed, and for a campaign trial its policy, index and perturbation.
    pub metadata: BTreeMap<String, String>,
}

/// Uncompressed bytes after which a chunk is closed (a step's flush closes
/// it sooner): small enough that a reader seeks to any time by reading
/// little, large enough for zstd to find the repetition of JSON.
const CHUNK_BYTES: u64 = 256 * 1024;

/// A run's recording. The file is chunked (zstd) and indexed, so a long
/// recording seeks fast; each [`Recorder::flush`] closes the chunk and
/// pushes it to the file, so that whatever was flushed stays readable if
/// the program is killed; [`Recorder::finish`] adds the summary (channels,
/// counts, chunk indexes) that makes the file complete.
///
/// Times are the wall clock: the cell's clock from the moment recording
/// began, in UTC ([`WallClock`]).
pub struct Recorder {
    /// The file's path or, with no file, the live server's address: what
    /// errors name.
    name: PathBuf,
    file: Option<FileSink>,
    live: Option<Arc<LiveServer>>,
    clock: WallClock,
    view: CellView,
    /// From the first frames read (`prepare`'s), to record Δv.
    bias: Option<Bias>,
    /// The grasp frame the detector found, for `/tf`.
    base_from_cable: Option<Isometry3<f64>>,
}

struct FileSink {
    writer: mcap::Writer<BufWriter<File>>,
    /// Channel ids, added with their first message: a file holds only the
    /// channels it has messages on.
    channels: BTreeMap<Topic, u16>,
    sequence: u32,
}

impl Recorder {
    /// Creates the target's file (and its folders), writes its metadata
    /// record, and starts the clock: `cell_now_s` is the cell's clock now.
    pub fn create(
        target: RecordingTarget<'_>,
        view: CellView,
        cell_now_s: f64,
    ) -> Result<Self, RecordingError> {
        let name = match (target.file, &target.live) {
            (Some(path), _) => path.to_owned(),
            (None, Some(live)) => PathBuf::from(format!("ws://{}", live.addr())),
            (None, None) => PathBuf::new(),
        };
        let file = target
            .file
            .map(|path| FileSink::create(path, target.metadata))
            .transpose()?;
        Ok(Self {
            name,
            file,
            live: target.live,
            clock: WallClock::now(cell_now_s),
            view,
            bias: None,
            base_from_cable: None,
        })
    }

    /// The file's path, when there is a file.
    pub fn path(&self) -> Option<&Path> {
        self.file.as_ref().map(|_| self.name.as_path())
    }

    /// The Foxglove time of the cell's `t_s`.
    pub fn timestamp(&self, t_s: f64) -> Timestamp {
        self.clock.timestamp(t_s)
    }

    /// The run's description: at the start, and again whenever its plan
    /// changes.
    pub fn run(&mut self, t_s: f64, run: &RunMessage) -> Result<(), RecordingError> {
        self.write(Topic::Run, t_s, run)
    }

    /// `message` as JSON on `topic`.
    fn write(
        &mut self,
        topic: Topic,
        t_s: f64,
        message: &impl Serialize,
    ) -> Result<(), RecordingError> {
        let data = serde_json::to_vec(message).map_err(|source| RecordingError::Encode {
            path: self.name.clone(),
            topic: topic.name(),
            source,
        })?;
        self.write_bytes(topic, t_s, &data)
    }

    /// `message`, one of Foxglove's protobuf messages, on `topic`.
    fn write_protobuf<M>(
        &mut self,
        topic: Topic,
        t_s: f64,
        message: &M,
    ) -> Result<(), RecordingError>
    where
        M: Encode<Error = prost::EncodeError>,
    {
        let mut data = Vec::with_capacity(message.encoded_len().unwrap_or(256));
        message
            .encode(&mut data)
            .map_err(|source| RecordingError::Protobuf {
                path: self.name.clone(),
                topic: topic.name(),
                source,
            })?;
        self.write_bytes(topic, t_s, &data)
    }

    fn write_bytes(&mut self, topic: Topic, t_s: f64, data: &[u8]) -> Result<(), RecordingError> {
        let log_time_ns = self.clock.log_time_ns(t_s);
        if let Some(live) = &self.live {
            live.send(topic, data, log_time_ns);
        }
        match &mut self.file {
            Some(file) => file
                .write(topic, log_time_ns, data)
                .map_err(RecordingError::mcap(&self.name)),
            None => Ok(()),
        }
    }

    /// Tactile frames as read in `state`: raw, and Δv once the bias is
    /// known, with the pad drawn for Foxglove (an image, and its taxels in
    /// 3D). The first frames read are the bias frames: their raw counts
    /// are the bias's input (a replay measures it again from them), and
    /// their Δv, noise around zero, is not written, which halves what a
    /// campaign writes.
    pub fn tactile_frames(
        &mut self,
        state: &str,
        frames: &[TactileFrame],
    ) -> Result<(), RecordingError> {
        let bias = self.bias.clone();
        if bias.is_none() {
            let mut estimator = BiasEstimator::new(frames.len());
            self.bias = frames.iter().find_map(|frame| estimator.push(&frame.raw));
        }
        for frame in frames {
            let timestamp = self.timestamp(frame.t_s);
            let raw = TactileRawMessage {
                timestamp,
                state: state.to_owned(),
                counts: frame.raw,
            };
            self.write(Topic::TactileRaw, frame.t_s, &raw)?;
            if let Some(bias) = &bias {
                let map = bias.remove(&frame.raw);
                let dv = TactileDvMessage {
                    timestamp,
                    state: raw.state,
                    dv_v: row_major(&map),
                };
                self.write(Topic::TactileDv, frame.t_s, &dv)?;
                let image = scene::tactile_image(timestamp, &map);
                self.write_protobuf(Topic::TactileImage, frame.t_s, &image)?;
                let pad = scene::pad_scene(&self.view, timestamp, &map);
                self.write_protobuf(Topic::Scene, frame.t_s, &pad)?;
            }
        }
        Ok(())
    }

    pub fn transition(&mut self, transition: &TransitionRecord) -> Result<(), RecordingError> {
        let message = TransitionMessage {
            timestamp: self.timestamp(transition.t_s),
            from: transition.from.to_owned(),
            to: transition.to.to_owned(),
            t_s: transition.t_s,
        };
        self.write(Topic::State, transition.t_s, &message)?;
        let text = format!("{} → {}", transition.from, transition.to);
        self.log(transition.t_s, 2, text)
    }

    /// A grasp judged with `estimator` and `fit` (the REPL's `set` may
    /// change them during a run).
    pub fn grasp(
        &mut self,
        grasp: &GraspRecord,
        estimator: Estimator,
        fit: &FitConfig,
    ) -> Result<(), RecordingError> {
        let timestamp = self.timestamp(grasp.t_s);
        let line = grasp.fit.as_ref().map(Estimate::line);
        let centroids_mm = match &grasp.fit {
            Some(Estimate::Centroids(fit)) => {
                fit.centroids.iter().map(|c| [c.x_mm, c.y_mm]).collect()
            }
            _ => Vec::new(),
        };
        let message = TactileFitMessage {
            timestamp,
            attempt: grasp.attempt,
            estimator,
            map_dv_v: row_major(&grasp.map),
            peak_dv_v: grasp.map.peak_dv_v(),
            n_mm: line.map(|l| l.n_mm),
            alpha_rad: line.map(|l| l.alpha_rad),
            error_n_mm: grasp.estimated_error.map(|e| e.n_mm),
            error_alpha_rad: grasp.estimated_error.map(|e| e.alpha_rad),
            true_n_mm: grasp.truth.as_ref().map(|t| t.line.n_mm),
            true_alpha_rad: grasp.truth.as_ref().map(|t| t.line.alpha_rad),
            centroids_mm,
            condition: grasp.fit.as_ref().and_then(Estimate::condition),
        };
        self.write(Topic::TactileFit, grasp.t_s, &message)?;
        let wire = wire_params(timestamp, grasp, fit);
        self.write(Topic::WireParams, grasp.t_s, &wire)?;
        self.pose(Topic::GraspPose, grasp.t_s, &grasp.base_from_tcp)?;
        match &grasp.shapes {
            Some(shapes) => {
                let message = CableShapesMessage {
                    timestamp,
                    attempt: grasp.attempt,
                    shapes: to_tenth_micrometre(shapes),
                };
                self.write(Topic::CableShapes, grasp.t_s, &message)?;
                let scene = scene::shapes_scene(timestamp, &message.shapes);
                self.write_protobuf(Topic::Scene, grasp.t_s, &scene)
            }
            None => Ok(()),
        }
    }

    /// What the detector found: the camera image it looked at (as PNG,
    /// lossless, so that a replay runs the vision pipeline on exactly what
    /// the detector saw) with the camera's calibration and the detections
    /// drawn over it, and the first cable (the one aimed at) in 3D and as
    /// the `cable` frame.
    pub fn detections(&mut self, t_s: f64, detections: &Detections) -> Result<(), RecordingError> {
        let timestamp = self.timestamp(t_s);
        if let Some(image) = &detections.image {
            self.camera_image(t_s, image)?;
            if let Some(camera) = self.view.camera.clone() {
                let calibration = scene::camera_calibration(&camera, timestamp);
                self.write_protobuf(Topic::CameraCalibration, t_s, &calibration)?;
                let drawn = scene::annotations(&camera, timestamp, &detections.cables);
                self.write_protobuf(Topic::CameraAnnotations, t_s, &drawn)?;
            }
        }
        if let Some(cable) = detections.cables.first() {
            self.base_from_cable = Some(cable.base_from_cable);
            if !cable.centre_line.is_empty() {
                let seen = scene::vision_scene(timestamp, &cable.centre_line);
                self.write_protobuf(Topic::Scene, t_s, &seen)?;
            }
        }
        Ok(())
    }

    fn camera_image(&mut self, t_s: f64, image: &CameraImage) -> Result<(), RecordingError> {
        let mut png = opencv::core::Vector::<u8>::new();
        opencv::imgcodecs::imencode(".png", &*image.0, &mut png, &opencv::core::Vector::new())
            .map_err(|source| RecordingError::Image {
                path: self.name.clone(),
                source,
            })?;
        let message = CompressedImageMessage {
            timestamp: self.timestamp(t_s),
            frame_id: "camera".into(),
            data: png.to_vec(),
            format: "png".into(),
        };
        self.write(Topic::CameraImage, t_s, &message)
    }

    /// The cell's frames at `t_s`, the TCP where the arm measured it
    /// (`None`: unknown, left out).
    pub fn frames(
        &mut self,
        t_s: f64,
        base_from_tcp: Option<&Isometry3<f64>>,
    ) -> Result<(), RecordingError> {
        let transforms = scene::frame_transforms(
            &self.view,
            self.timestamp(t_s),
            base_from_tcp,
            self.base_from_cable.as_ref(),
        );
        self.write_protobuf(Topic::Tf, t_s, &transforms)
    }

    /// A pose of the TCP in the arm's base frame (mm) on `topic`.
    pub fn pose(
        &mut self,
        topic: Topic,
        t_s: f64,
        base_from_tcp: &Isometry3<f64>,
    ) -> Result<(), RecordingError> {
        let t = base_from_tcp.translation.vector / 1000.0;
        let q = base_from_tcp.rotation;
        let message = PoseInFrameMessage {
            timestamp: self.timestamp(t_s),
            frame_id: "base".into(),
            pose: Pose {
                position: Vector3 {
                    x: t.x,
                    y: t.y,
                    z: t.z,
                },
                orientation: Quaternion {
                    x: q.i,
                    y: q.j,
                    z: q.k,
                    w: q.w,
                },
            },
        };
        self.write(topic, t_s, &message)
    }

    /// The run's outcome as a log line.
    pub fn outcome(&mut self, record: &RunRecord, t_s: f64) -> Result<(), RecordingError> {
        let (level, text) = match &record.outcome {
            Some(RunOutcome::Success { regrasps }) => {
                (2, format!("success after {regrasps} regrasp(s)"))
            }
            Some(RunOutcome::Failed { reason }) => (3, format!("task failed: {reason}")),
            Some(RunOutcome::Fault { state, error, .. }) => {
                (4, format!("fault in {state}: {error}"))
            }
            None => return Ok(()),
        };
        self.log(t_s, level, text)
    }

    fn log(&mut self, t_s: f64, level: u8, message: String) -> Result<(), RecordingError> {
        let message = LogMessage {
            timestamp: self.timestamp(t_s),
            level,
            message,
            name: "cablecell".into(),
            file: String::new(),
            line: 0,
        };
        self.write(Topic::Log, t_s, &message)
    }

    /// Closes the chunk and pushes it to the file, so a kill loses none of
    /// what was written.
    pub fn flush(&mut self) -> Result<(), RecordingError> {
        match &mut self.file {
            Some(file) => file
                .writer
                .flush()
                .map_err(RecordingError::mcap(&self.name)),
            None => Ok(()),
        }
    }

    /// Writes the summary and closes the file; returns its path (`None`
    /// for a live view alone).
    pub fn finish(self) -> Result<Option<PathBuf>, RecordingError> {
        let Some(mut file) = self.file else {
            return Ok(None);
        };
        file.writer
            .finish()
            .map_err(RecordingError::mcap(&self.name))?;
        file.writer
            .into_inner()
            .flush()
            .map_err(|source| RecordingError::Io {
                path: self.name.clone(),
                source,
            })?;
        Ok(Some(self.name))
    }
}

impl FileSink {
    fn create(path: &Path, metadata: BTreeMap<String, String>) -> Result<Self, RecordingError> {
        let io = |source| RecordingError::Io {
            path: path.to_owned(),
            source,
        };
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(io)?;
        }
        let file = File::create(path).map_err(io)?;
        let options = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            // A campaign records on every core already.
            .compression_threads(0)
            .chunk_size(Some(CHUNK_BYTES))
            .library(concat!("cablecell ", env!("CARGO_PKG_VERSION")));
        let mut writer = options
            // A trial's recording in one or two writes.
            .create(BufWriter::with_capacity(64 * 1024, file))
            .map_err(RecordingError::mcap(path))?;
        let mut fields =
            BTreeMap::from([("version".to_owned(), env!("CARGO_PKG_VERSION").to_owned())]);
        fields.extend(metadata);
        writer
            .write_metadata(&Metadata {
                name: "cablecell".into(),
                metadata: fields,
            })
            .map_err(RecordingError::mcap(path))?;
        Ok(Self {
            writer,
            channels: BTreeMap::new(),
            sequence: 0,
        })
    }

    fn write(
        &mut self,
        topic: Topic,
        log_time_ns: u64,
        data: &[u8],
    ) -> Result<(), mcap::McapError> {
        let channel_id = match self.channels.get(&topic) {
            Some(id) => *id,
            None => {
                let schema = topic.schema();
                let schema_id =
                    self.writer
                        .add_schema(&schema.name, schema.encoding, &schema.data)?;
                let id = self.writer.add_channel(
                    schema_id,
                    topic.name(),
                    schema.message_encoding,
                    &BTreeMap::new(),
                )?;
                self.channels.insert(topic, id);
                id
            }
        };
        self.sequence += 1;
        let header = MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time: log_time_ns,
            publish_time: log_time_ns,
        };
        self.writer.write_to_known_channel(&header, data)
    }
}

/// The paper's wire parameters of a grasp's map: the centroid estimator's
/// own fit, or the same fit made now for a grasp another estimator judged.
fn wire_params(timestamp: Timestamp, grasp: &GraspRecord, config: &FitConfig) -> WireParamsMessage {
    let fitted = match &grasp.fit {
        Some(Estimate::Centroids(fit)) => Ok(std::borrow::Cow::Borrowed(fit)),
        _ => fit_wire(&grasp.map, config).map(std::borrow::Cow::Owned),
    };
    let fit = fitted.as_ref().ok();
    let quadratic = fit.and_then(|f| f.quadratic);
    WireParamsMessage {
        timestamp,
        attempt: grasp.attempt,
        direction: fit.map(|f| f.direction.to_string()),
        m: fit.and_then(|f| f.slope_m),
        n_mm: fit.and_then(|f| f.intercept_n_mm),
        a_per_mm: quadratic.map(|q| q.a),
        b: quadratic.map(|q| q.b),
        c_mm: quadratic.map(|q| q.c),
        h_v: fit.map(|f| f.h_v),
        v_v: fit.map(|f| f.v_v),
        error: fitted.as_ref().err().map(ToString::to_string),
    }
}

/// The shapes with their points and σ rounded to 0.1 µm: far below any
/// of their errors, and half the text of full-precision floats.
fn to_tenth_micrometre(shapes: &GraspShapes) -> GraspShapes {
    let round = |v: f64| (v * 1e4).round() / 1e4;
    let point = |p: &Point3<f64>| p.map(round);
    let shape = |points: &Option<Vec<ShapePoint>>| {
        points.as_ref().map(|points| {
            points
                .iter()
                .map(|p| ShapePoint {
                    in_base_mm: point(&p.in_base_mm),
                    sigma_mm: round(p.sigma_mm),
                })
                .collect()
        })
    };
    GraspShapes {
        vision: shape(&shapes.vision),
        tactile_linear: shape(&shapes.tactile_linear),
        tactile_quadratic: shape(&shapes.tactile_quadratic),
        tactile_ridge: shape(&shapes.tactile_ridge),
        fused: shape(&shapes.fused),
        truth: shapes
            .truth
            .as_ref()
            .map(|truth| truth.iter().map(point).collect()),
        ..shapes.clone()
    }
}

/// The map's Δv, row-major, rounded to the µV: far below the ADC's step
/// (0.8 mV), and a third of the text of a full-precision float.
fn row_major(map: &TactileMap) -> [f64; 25] {
    let mut values = [0.0; 25];
    for (value, dv) in values.iter_mut().zip(map.dv_v.iter().flatten()) {
        *value = (dv * 1e6).round() / 1e6;
    }
    values
}
