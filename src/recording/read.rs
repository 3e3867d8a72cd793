//! Reads a recording back, whole or cut short.

use std::collections::HashMap;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use mcap::records::{Record, op};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use serde::de::DeserializeOwned;

use super::RecordingError;
use super::schema::Topic;

/// The longest record that a chunk may hold, whatever the file's length.
const MAX_MESSAGE_BYTES: usize = 64 << 20;

/// A recording's messages, in file order.
#[derive(Debug, Clone)]
pub struct Recording {
    pub path: PathBuf,
    pub messages: Vec<RecordedMessage>,
    /// Why the file ends early (a run killed before it finished writing):
    /// `None` for a complete file. The messages before the cut are kept.
    pub truncated: Option<String>,
}

#[derive(Debug, Clone)]
pub struct RecordedMessage {
    pub topic: String,
    pub log_time_ns: u64,
    pub data: Vec<u8>,
}

/// Takes one record of a recording's data section: a channel into
/// `topics`, a message into `messages`. Breaks at the data's end (the
/// summary after it repeats the channels), or with why the file reads as
/// cut from here.
fn take_record(
    opcode: u8,
    data: &[u8],
    topics: &mut HashMap<u16, String>,
    messages: &mut Vec<RecordedMessage>,
) -> ControlFlow<Option<String>> {
    match opcode {
        op::DATA_END => return ControlFlow::Break(None),
        // mcap 0.26 cuts an attachment's body before it checks the body's
        // length (a panic on a corrupt one, found by fuzzing); a recording
        // holds none.
        op::ATTACHMENT => return ControlFlow::Continue(()),
        _ => {}
    }
    match mcap::parse_record(opcode, data) {
        Ok(Record::Channel(channel)) => {
            topics.insert(channel.id, channel.topic);
        }
        Ok(Record::Message { header, data }) => {
            let Some(topic) = topics.get(&header.channel_id) else {
                return ControlFlow::Break(Some(format!(
                    "message {} is on channel {}, which no channel record names",
                    header.sequence, header.channel_id
                )));
            };
            messages.push(RecordedMessage {
                topic: topic.clone(),
                log_time_ns: header.log_time,
                data: data.into_owned(),
            });
        }
        Ok(_) => {}
        Err(error) => return ControlFlow::Break(Some(error.to_string())),
    }
    ControlFlow::Continue(())
}

impl Recording {
    pub fn read(path: &Path) -> Result<Self, RecordingError> {
        let bytes = std::fs::read(path).map_err(|source| RecordingError::Io {
            path: path.to_owned(),
            source,
        })?;
        let complete = mcap::read::footer(&bytes).is_ok();
        // mcap's readers set no limit on a record's length by default, and a
        // corrupt length near 2^64 overflows inside the mcap crate (a
        // panic, found by fuzzing): no record is longer than the file, or
        // than a message in a chunk decompressed from it can be (a camera
        // image is under 4 MB).
        let mut reader = LinearReader::new_with_options(
            LinearReaderOptions::default()
                .with_skip_end_magic(true)
                .with_record_length_limit(bytes.len().max(MAX_MESSAGE_BYTES)),
        );
        let mut unread = &bytes[..];
        let mut topics: HashMap<u16, String> = HashMap::new();
        let mut messages = Vec::new();
        let mut truncated = None;
        while let Some(event) = reader.next_event() {
            let flow = match event {
                Ok(LinearReadEvent::ReadRequest(wanted)) => {
                    let n = wanted.min(unread.len());
                    reader.insert(n).copy_from_slice(&unread[..n]);
                    reader.notify_read(n);
                    unread = &unread[n..];
                    continue;
                }
                Ok(LinearReadEvent::Record { opcode, data }) => {
                    take_record(opcode, data, &mut topics, &mut messages)
                }
                Err(error) => ControlFlow::Break(Some(error.to_string())),
            };
            if let ControlFlow::Break(why) = flow {
                truncated = why;
                break;
            }
        }
        if truncated.is_none() && !complete {
            truncated = Some("the file ends without its summary and footer".into());
        }
        Ok(Self {
            path: path.to_owned(),
            messages,
            truncated,
        })
    }

    /// Messages on `topic`.
    pub fn count(&self, topic: Topic) -> usize {
        self.on(topic).count()
    }

    fn on(&self, topic: Topic) -> impl Iterator<Item = &RecordedMessage> {
        self.messages
            .iter()
            .filter(move |m| m.topic == topic.name())
    }

    /// Every message on `topic`, decoded.
    pub fn decode<T: DeserializeOwned>(&self, topic: Topic) -> Result<Vec<T>, RecordingError> {
        self.on(topic)
            .map(|m| {
                serde_json::from_slice(&m.data).map_err(|source| RecordingError::Encode {
                    path: self.path.clone(),
                    topic: topic.name(),
                    source,
                })
            })
            .collect()
    }
}
