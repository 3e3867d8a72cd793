//! The live view: Foxglove's WebSocket protocol (subprotocol `foxglove.sdk.v1`)
//! served by the `foxglove` crate, on which a recorder publishes the same
//! channels, schemas and bytes it writes to its file. One server outlives
//! the runs that use it (the REPL's runs one after another). Every channel
//! is advertised when the server starts: a viewer subscribes to what it
//! has seen advertised, so a channel first advertised with its first
//! message would never show that message (the run's header, the trial
//! grasp's tactile frames).

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use foxglove::{Context, PartialMetadata, RawChannel, WebSocketServer, WebSocketServerHandle};

use super::RecordingError;
use super::schema::Topic;

/// Where `--live` serves when it is given no address.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8765";

/// How long a connected viewer is given to receive the last messages
/// before the server stops: the `foxglove` server drops what it has not
/// yet sent to a client when it stops, and a run's last messages (its
/// final state) go out just before.
const DRAIN: Duration = Duration::from_millis(500);

/// A running WebSocket server and the channels published on it.
pub struct LiveServer {
    /// Holds the channels' context for as long as they publish.
    _context: Arc<Context>,
    channels: BTreeMap<Topic, Arc<RawChannel>>,
    addr: SocketAddr,
    /// Stopped when the server is dropped.
    handle: Option<WebSocketServerHandle>,
}

impl LiveServer {
    /// Serves on `addr` (port 0: one the system picks) from now on.
    pub fn start(addr: SocketAddr) -> Result<Self, RecordingError> {
        let context = Context::new();
        let channels = Topic::ALL
            .into_iter()
            .map(|topic| {
                let schema = topic.schema();
                context
                    .channel_builder(topic.name())
                    .message_encoding(schema.message_encoding)
                    .schema(foxglove::Schema::new(
                        schema.name,
                        schema.encoding,
                        schema.data,
                    ))
                    .build_raw()
                    .map(|channel| (topic, channel))
            })
            .collect::<Result<_, _>>()
            .map_err(|source| RecordingError::Live { addr, source })?;
        let handle = WebSocketServer::new()
            .name(concat!("cablecell ", env!("CARGO_PKG_VERSION")))
            .context(&context)
            .bind(addr.ip().to_string(), addr.port())
            .start_blocking()
            .map_err(|source| RecordingError::Live { addr, source })?;
        Ok(Self {
            addr: SocketAddr::new(addr.ip(), handle.port()),
            _context: context,
            channels,
            handle: Some(handle),
        })
    }

    /// The address it serves on (with the port the system picked).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Sends `data` on `topic` to the clients subscribed to it (none:
    /// nothing is encoded or sent); a slow client drops messages, never
    /// the run.
    pub(super) fn send(&self, topic: Topic, data: &[u8], log_time_ns: u64) {
        self.channels[&topic].log_with_meta(
            data,
            PartialMetadata {
                log_time: Some(log_time_ns),
            },
        );
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        if let Some(handle) = self.handle.take() {
            if handle.client_count() > 0 {
                std::thread::sleep(DRAIN);
            }
            // Closes the connections; the server's tasks end on their own.
            handle.stop().detach_all();
        }
    }
}
