//! Writes a run's recording as it happens.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use mcap::records::MessageHeader;
use nalgebra::{Isometry3, Point3};
use opencv::core::VectorToVec;
use serde::Serialize;

use super::RecordingError;
use super::schema::{
    CableShapesMessage, CompressedImageMessage, LogMessage, Pose, PoseInFrameMessage, Quaternion,
    RunMessage, TactileDvMessage, TactileFitMessage, TactileRawMessage, Timestamp, Topic,
    TransitionMessage, Vector3, log_time_ns,
};
use crate::hw::camera::CameraImage;
use crate::hw::tactile::TactileFrame;
use crate::perception::shape::ShapePoint;
use crate::perception::tactile::{Bias, BiasEstimator, Estimate, Estimator, TactileMap};
use crate::record::{GraspRecord, GraspShapes, RunOutcome, RunRecord, TransitionRecord};

/// An MCAP file being written. Messages go straight to the file, not into
/// chunks, so that whatever was flushed stays readable if the program is
/// killed; [`Recorder::finish`] adds the summary (channels, counts) that
/// makes the file complete.
pub struct Recorder {
    path: PathBuf,
    writer: mcap::Writer<BufWriter<File>>,
    /// Channel ids by `Topic` order.
    channels: BTreeMap<Topic, u16>,
    sequence: u32,
    /// From the first frames read (`prepare`'s), to record Δv.
    bias: Option<Bias>,
}

impl Recorder {
    /// Creates `path` (and its folders) and writes the run's description.
    pub fn create(path: &Path, run: &RunMessage) -> Result<Self, RecordingError> {
        let io = |source| RecordingError::Io {
            path: path.to_owned(),
            source,
        };
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(io)?;
        }
        let file = File::create(path).map_err(io)?;
        let options = mcap::WriteOptions::new()
            .use_chunks(false)
            .emit_message_indexes(false)
            .library(concat!("cablecell ", env!("CARGO_PKG_VERSION")));
        let mut writer = options
            // A trial's recording (about 40 KB) in one or two writes.
            .create(BufWriter::with_capacity(64 * 1024, file))
            .map_err(RecordingError::mcap(path))?;
        let mut channels = BTreeMap::new();
        for topic in Topic::ALL {
            let (name, schema) = topic.schema();
            let schema_id = writer
                .add_schema(name, "jsonschema", schema.as_bytes())
                .map_err(RecordingError::mcap(path))?;
            let channel_id = writer
                .add_channel(schema_id, topic.name(), "json", &BTreeMap::new())
                .map_err(RecordingError::mcap(path))?;
            channels.insert(topic, channel_id);
        }
        let mut recorder = Self {
            path: path.to_owned(),
            writer,
            channels,
            sequence: 0,
            bias: None,
        };
        recorder.run(run)?;
        Ok(recorder)
    }

    /// The run's description: at the start, and again whenever its plan
    /// changes.
    pub fn run(&mut self, run: &RunMessage) -> Result<(), RecordingError> {
        let t_s = f64::from(run.timestamp.sec) + f64::from(run.timestamp.nsec) * 1e-9;
        self.write(Topic::Run, t_s, run)
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    fn write(
        &mut self,
        topic: Topic,
        t_s: f64,
        message: &impl Serialize,
    ) -> Result<(), RecordingError> {
        let data = serde_json::to_vec(message).map_err(|source| RecordingError::Encode {
            path: self.path.clone(),
            topic: topic.name(),
            source,
        })?;
        let log_time = log_time_ns(t_s);
        self.sequence += 1;
        let header = MessageHeader {
            channel_id: self.channels[&topic],
            sequence: self.sequence,
            log_time,
            publish_time: log_time,
        };
        self.writer
            .write_to_known_channel(&header, &data)
            .map_err(RecordingError::mcap(&self.path))
    }

    /// Tactile frames as read in `state`: raw, and Δv once the bias is
    /// known. The first frames read are the bias frames: their raw counts
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
            let timestamp = Timestamp::of(frame.t_s);
            let raw = TactileRawMessage {
                timestamp,
                state: state.to_owned(),
                counts: frame.raw,
            };
            self.write(Topic::TactileRaw, frame.t_s, &raw)?;
            if let Some(bias) = &bias {
                let dv = TactileDvMessage {
                    timestamp,
                    state: raw.state,
                    dv_v: row_major(&bias.remove(&frame.raw)),
                };
                self.write(Topic::TactileDv, frame.t_s, &dv)?;
            }
        }
        Ok(())
    }

    pub fn transition(&mut self, transition: &TransitionRecord) -> Result<(), RecordingError> {
        let timestamp = Timestamp::of(transition.t_s);
        let message = TransitionMessage {
            timestamp,
            from: transition.from.to_owned(),
            to: transition.to.to_owned(),
            t_s: transition.t_s,
        };
        self.write(Topic::State, transition.t_s, &message)?;
        let text = format!("{} → {}", transition.from, transition.to);
        self.log(transition.t_s, 2, text)
    }

    /// A grasp judged with `estimator` (the REPL's `set` may change it
    /// during a run).
    pub fn grasp(
        &mut self,
        grasp: &GraspRecord,
        estimator: Estimator,
    ) -> Result<(), RecordingError> {
        let line = grasp.fit.as_ref().map(Estimate::line);
        let centroids_mm = match &grasp.fit {
            Some(Estimate::Centroids(fit)) => {
                fit.centroids.iter().map(|c| [c.x_mm, c.y_mm]).collect()
            }
            _ => Vec::new(),
        };
        let message = TactileFitMessage {
            timestamp: Timestamp::of(grasp.t_s),
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
        };
        self.write(Topic::TactileFit, grasp.t_s, &message)?;
        self.pose(Topic::GraspPose, grasp.t_s, &grasp.base_from_tcp)?;
        match &grasp.shapes {
            Some(shapes) => {
                let message = CableShapesMessage {
                    timestamp: Timestamp::of(grasp.t_s),
                    attempt: grasp.attempt,
                    shapes: to_tenth_micrometre(shapes),
                };
                self.write(Topic::CableShapes, grasp.t_s, &message)
            }
            None => Ok(()),
        }
    }

    /// An image the camera took, as PNG (lossless, so that a replay runs
    /// the vision pipeline on exactly what the detector saw).
    pub fn camera_image(&mut self, t_s: f64, image: &CameraImage) -> Result<(), RecordingError> {
        let mut png = opencv::core::Vector::<u8>::new();
        opencv::imgcodecs::imencode(".png", &*image.0, &mut png, &opencv::core::Vector::new())
            .map_err(|source| RecordingError::Image {
                path: self.path.clone(),
                source,
            })?;
        let message = CompressedImageMessage {
            timestamp: Timestamp::of(t_s),
            frame_id: "camera".into(),
            data: png.to_vec(),
            format: "png".into(),
        };
        self.write(Topic::CameraImage, t_s, &message)
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
            timestamp: Timestamp::of(t_s),
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
            timestamp: Timestamp::of(t_s),
            level,
            message,
            name: "cablecell".into(),
            file: String::new(),
            line: 0,
        };
        self.write(Topic::Log, t_s, &message)
    }

    /// Pushes what was written to the file, so a kill loses none of it.
    pub fn flush(&mut self) -> Result<(), RecordingError> {
        self.writer
            .flush()
            .map_err(RecordingError::mcap(&self.path))
    }

    /// Writes the summary and closes the file.
    pub fn finish(mut self) -> Result<PathBuf, RecordingError> {
        self.writer
            .finish()
            .map_err(RecordingError::mcap(&self.path))?;
        self.writer
            .into_inner()
            .flush()
            .map_err(|source| RecordingError::Io {
                path: self.path.clone(),
                source,
            })?;
        Ok(self.path)
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
