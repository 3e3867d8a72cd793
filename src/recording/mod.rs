//! Recordings: every run written as an MCAP file that Foxglove opens as it
//! is (state transitions, tactile frames raw and Δv, fits, poses, the
//! cell's frames and a 3D scene, each on its own channel; see `schema` and
//! `scene`), or streamed live to Foxglove over its WebSocket protocol
//! (`live`), and read back for `cablecell replay`, which can fit the
//! recorded frames again with another estimator.

pub mod live;
pub mod read;
pub mod replay;
pub mod scene;
pub mod schema;
pub mod write;

use std::path::{Path, PathBuf};

pub use live::LiveServer;
pub use read::Recording;
pub use scene::CellView;
pub use schema::Topic;
pub use write::{Recorder, RecordingTarget};

/// Errors of writing and reading recordings.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RecordingError {
    /// The file or its folder could not be created, written or read: check
    /// the path, its permissions and the free space.
    #[error("{}: recording I/O failed: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The MCAP writer or reader refused: for reading, the file is not an
    /// MCAP file (or is damaged at its start); for writing, a bug.
    #[error("{}: {source}", path.display())]
    Mcap {
        path: PathBuf,
        #[source]
        source: mcap::McapError,
    },
    /// A message could not be written as JSON (a bug) or a recorded one
    /// does not match its channel's schema (a file from another program or
    /// version).
    #[error("{}: {topic}: {source}", path.display())]
    Encode {
        path: PathBuf,
        topic: &'static str,
        #[source]
        source: serde_json::Error,
    },
    /// One of Foxglove's protobuf messages could not be encoded (a bug).
    #[error("{}: {topic}: {source}", path.display())]
    Protobuf {
        path: PathBuf,
        topic: &'static str,
        #[source]
        source: prost::EncodeError,
    },
    /// The live view's WebSocket server could not start (the address is
    /// taken or not this machine's: pick another with `--live ADDR`) or
    /// refused a channel (a bug).
    #[error("live view on {addr}: {source}")]
    Live {
        addr: std::net::SocketAddr,
        #[source]
        source: foxglove::FoxgloveError,
    },
    /// The recording has no `/run` message, so it is not one of cablecell's
    /// runs (or was cut off before its first message).
    #[error("{}: no /run message: not a cablecell run recording", path.display())]
    NotARun { path: PathBuf },
    /// OpenCV could not encode a camera image as PNG, or decode a recorded
    /// one (a damaged recording).
    #[error("{}: camera image: {source}", path.display())]
    Image {
        path: PathBuf,
        #[source]
        source: opencv::Error,
    },
}

impl RecordingError {
    fn mcap(path: &Path) -> impl Fn(mcap::McapError) -> RecordingError + '_ {
        move |source| RecordingError::Mcap {
            path: path.to_owned(),
            source,
        }
    }
}
