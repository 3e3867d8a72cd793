//! The live view: Foxglove's WebSocket protocol (`foxglove.websocket.v1`)
//! served by the `foxglove` crate, on which a recorder publishes the same
//! channels, schemas and bytes it writes to its file. One server outlives
//! the runs that use it (the REPL's runs one after another): a channel is
//! advertised when its first message goes out and stays advertised.

use std::net::SocketAddr;
use std::sync::Arc;

use foxglove::{Context, PartialMetadata, RawChannel, WebSocketServer, WebSocketServerHandle};

use super::RecordingError;
use super::schema::Topic;

/// Where `--live` serves when it is given no address.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8765";

/// A running WebSocket server and the channels published on it.
pub struct LiveServer {
    context: Arc<Context>,
    addr: SocketAddr,
    /// Stopped when the server is dropped.
    handle: Option<WebSocketServerHandle>,
}

impl LiveServer {
    /// Serves on `addr` (port 0: one the system picks) from now on.
    pub fn start(addr: SocketAddr) -> Result<Self, RecordingError> {
        let context = Context::new();
        let handle = WebSocketServer::new()
            .name(concat!("cablecell ", env!("CARGO_PKG_VERSION")))
            .context(&context)
            .bind(addr.ip().to_string(), addr.port())
            .start_blocking()
            .map_err(|source| RecordingError::Live { addr, source })?;
        Ok(Self {
            addr: SocketAddr::new(addr.ip(), handle.port()),
            context,
            handle: Some(handle),
        })
    }

    /// The address it serves on (with the port the system picked).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The channel of `topic` (the same one for every run).
    pub(super) fn channel(&self, topic: Topic) -> Result<LiveChannel, RecordingError> {
        let schema = topic.schema();
        self.context
            .channel_builder(topic.name())
            .message_encoding(schema.message_encoding)
            .schema(foxglove::Schema::new(
                schema.name,
                schema.encoding,
                schema.data,
            ))
            .build_raw()
            .map(LiveChannel)
            .map_err(|source| RecordingError::Live {
                addr: self.addr,
                source,
            })
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        if let Some(handle) = self.handle.take() {
            // Closes the connections; the server's tasks end on their own.
            handle.stop().detach_all();
        }
    }
}

/// One topic on the server.
pub(super) struct LiveChannel(Arc<RawChannel>);

impl LiveChannel {
    /// Sends `data` to the clients subscribed to it (none: nothing is
    /// encoded or sent); a slow client drops messages, never the run.
    pub(super) fn send(&self, data: &[u8], log_time_ns: u64) {
        self.0.log_with_meta(
            data,
            PartialMetadata {
                log_time: Some(log_time_ns),
            },
        );
    }
}
