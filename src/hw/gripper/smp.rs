//! The Schunk Motion Protocol (SMP), as the PG70 speaks it over RS-232:
//! frames, their CRC, the requests a grasp needs and the replies and
//! spontaneous messages the module sends (docs/protocols.md).
//!
//! Frame: `[group] [module id] [D-Len] [command] [data …] [CRC lo] [CRC hi]`,
//! D-Len counting the command and data bytes, the CRC-16/ARC over every
//! byte before it. Numbers are little-endian IEEE-754 floats: mm, mm/s,
//! mm/s², A.

use crc::{CRC_16_ARC, Crc};

const CRC: Crc<u16> = Crc::<u16>::new(&CRC_16_ARC);

/// Who sends a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Group {
    /// Master to module: a request.
    Request = 0x05,
    /// Module to master: a reply or a spontaneous message.
    Reply = 0x07,
    /// Module to master: an error message.
    Error = 0x03,
}

impl Group {
    fn from_byte(byte: u8) -> Option<Group> {
        match byte {
            0x05 => Some(Group::Request),
            0x07 => Some(Group::Reply),
            0x03 => Some(Group::Error),
            _ => None,
        }
    }
}

/// Command codes used by cablecell.
pub mod command {
    pub const CMD_ERROR: u8 = 0x88;
    pub const CMD_ACK: u8 = 0x8B;
    pub const CMD_STOP: u8 = 0x91;
    pub const CMD_REFERENCE: u8 = 0x92;
    pub const CMD_MOVE_BLOCKED: u8 = 0x93;
    pub const CMD_POS_REACHED: u8 = 0x94;
    pub const GET_STATE: u8 = 0x95;
    pub const MOVE_POS: u8 = 0xB0;
    pub const MOVE_GRIP: u8 = 0xB7;
}

/// A whole frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub group: Group,
    pub module_id: u8,
    pub command: u8,
    pub data: Vec<u8>,
}

impl Frame {
    pub fn request(module_id: u8, command: u8, data: Vec<u8>) -> Frame {
        Frame {
            group: Group::Request,
            module_id,
            command,
            data,
        }
    }

    /// The bytes on the wire. Data longer than 254 bytes does not fit a
    /// D-Len byte; no SMP command has that much.
    pub fn encode(&self) -> Vec<u8> {
        let d_len = u8::try_from(self.data.len() + 1).unwrap_or(u8::MAX);
        let mut bytes = vec![self.group as u8, self.module_id, d_len, self.command];
        bytes.extend_from_slice(&self.data[..usize::from(d_len) - 1]);
        let crc = CRC.checksum(&bytes);
        bytes.extend_from_slice(&crc.to_le_bytes());
        bytes
    }

    /// The `index`-th float of the data, if there.
    pub fn float(&self, index: usize) -> Option<f32> {
        let bytes = self.data.get(4 * index..4 * index + 4)?;
        Some(f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]))
    }
}

/// MOVE_POS: go to `position_mm`, with speed and acceleration when given.
pub fn move_pos(module_id: u8, position_mm: f32, speed_accel: Option<(f32, f32)>) -> Frame {
    let mut data = position_mm.to_le_bytes().to_vec();
    if let Some((speed_mm_s, accel_mm_s2)) = speed_accel {
        data.extend_from_slice(&speed_mm_s.to_le_bytes());
        data.extend_from_slice(&accel_mm_s2.to_le_bytes());
    }
    Frame::request(module_id, command::MOVE_POS, data)
}

/// MOVE_GRIP: close with `current_a` until blocked.
pub fn move_grip(module_id: u8, current_a: f32) -> Frame {
    Frame::request(
        module_id,
        command::MOVE_GRIP,
        current_a.to_le_bytes().to_vec(),
    )
}

/// GET_STATE: once (`period_s` 0) or every `period_s`; `mode` 0x01
/// position, 0x03 and velocity, 0x07 and current.
pub fn get_state(module_id: u8, period_s: f32, mode: u8) -> Frame {
    let mut data = period_s.to_le_bytes().to_vec();
    data.push(mode);
    Frame::request(module_id, command::GET_STATE, data)
}

/// A request with no data (REFERENCE, STOP, ACK).
pub fn simple(module_id: u8, command: u8) -> Frame {
    Frame::request(module_id, command, Vec::new())
}

/// What the module meant by an error code (the manual's, in part).
pub fn error_meaning(code: u8) -> &'static str {
    match code {
        0x06 => "not referenced",
        0x19 => "checksum error",
        0x1D => "wrong message length",
        0x74 => "motor voltage low",
        0xD5 => "soft limit low reached",
        0xD6 => "soft limit high reached",
        0xD9 => "emergency stop",
        0xDA => "tow error (the jaws lag behind the command)",
        0xDE => "current too high",
        _ => "unknown error code",
    }
}

/// Turns a byte stream into frames, resynchronising after garbage: bytes
/// that cannot start a frame, and frames whose CRC does not match, are
/// skipped one byte at a time and counted.
#[derive(Debug, Default)]
pub struct Decoder {
    buffer: Vec<u8>,
    /// Bytes thrown away since the decoder was made.
    pub discarded_bytes: usize,
    /// Candidate frames whose CRC did not match.
    pub crc_errors: usize,
}

impl Decoder {
    pub fn push(&mut self, bytes: &[u8]) {
        self.buffer.extend_from_slice(bytes);
    }

    /// The next whole frame in what was pushed, if any.
    pub fn next_frame(&mut self) -> Option<Frame> {
        loop {
            let start = self
                .buffer
                .iter()
                .position(|&b| Group::from_byte(b).is_some());
            let skipped = start.unwrap_or(self.buffer.len());
            self.discard(skipped);
            if self.buffer.len() < 3 {
                return None;
            }
            let d_len = usize::from(self.buffer[2]);
            if d_len == 0 {
                self.discard(1);
                continue;
            }
            let total = 3 + d_len + 2;
            if self.buffer.len() < total {
                // Either a frame still arriving, or garbage that looks like
                // the start of a long one: a whole valid frame further on
                // shows which.
                match (1..self.buffer.len()).find(|&at| complete_frame_at(&self.buffer[at..])) {
                    Some(at) => {
                        self.discard(at);
                        continue;
                    }
                    None => return None,
                }
            }
            if !complete_frame_at(&self.buffer) {
                self.crc_errors += 1;
                self.discard(1);
                continue;
            }
            let frame = Frame {
                group: Group::from_byte(self.buffer[0])?,
                module_id: self.buffer[1],
                command: self.buffer[3],
                data: self.buffer[4..total - 2].to_vec(),
            };
            self.buffer.drain(..total);
            return Some(frame);
        }
    }

    /// Bytes held back: the start of a frame still arriving.
    pub fn pending_bytes(&self) -> usize {
        self.buffer.len()
    }

    fn discard(&mut self, count: usize) {
        self.buffer.drain(..count);
        self.discarded_bytes += count;
    }
}

/// Whether `bytes` begins with a whole frame whose CRC matches.
fn complete_frame_at(bytes: &[u8]) -> bool {
    if bytes.len() < 3 || Group::from_byte(bytes[0]).is_none() || bytes[2] == 0 {
        return false;
    }
    let total = 3 + usize::from(bytes[2]) + 2;
    bytes.len() >= total
        && CRC.checksum(&bytes[..total - 2])
            == u16::from_le_bytes([bytes[total - 2], bytes[total - 1]])
}

/// A frame from the module, understood.
#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    /// The request was accepted ("OK").
    Ok { command: u8 },
    /// The request was refused with this error code.
    Refused { command: u8, error: u8 },
    /// A move ended; the float is what the module reports with it (the
    /// position, or the expected duration in a MOVE_POS reply).
    Value { command: u8, value: f32 },
    /// GET_STATE: the floats asked for, then the state and error bytes.
    State {
        position_mm: f32,
        velocity_mm_s: Option<f32>,
        current_a: Option<f32>,
        state: u8,
        error: u8,
    },
    /// The module reports an error on its own.
    Error { error: u8 },
    /// Anything else, kept whole.
    Other(Frame),
}

impl Reply {
    pub fn parse(frame: Frame) -> Reply {
        let data = &frame.data;
        match (frame.group, frame.command, data.len()) {
            (Group::Error, command::CMD_ERROR, 1) => Reply::Error { error: data[0] },
            (Group::Reply, command, 2) if data == b"OK" => Reply::Ok { command },
            (Group::Reply, command, 1) => Reply::Refused {
                command,
                error: data[0],
            },
            (Group::Reply, command::GET_STATE, 6 | 10 | 14) => {
                let floats = (data.len() - 2) / 4;
                Reply::State {
                    position_mm: frame.float(0).unwrap_or(f32::NAN),
                    velocity_mm_s: (floats >= 2).then(|| frame.float(1)).flatten(),
                    current_a: (floats >= 3).then(|| frame.float(2)).flatten(),
                    state: data[data.len() - 2],
                    error: data[data.len() - 1],
                }
            }
            (Group::Reply, command, 4) => Reply::Value {
                command,
                value: frame.float(0).unwrap_or(f32::NAN),
            },
            _ => Reply::Other(frame),
        }
    }
}

/// Bits of GET_STATE's state byte.
pub mod state_bits {
    pub const REFERENCED: u8 = 1 << 0;
    pub const MOVING: u8 = 1 << 1;
    pub const ERROR: u8 = 1 << 4;
    pub const MOVE_BLOCKED: u8 = 1 << 6;
    pub const POSITION_REACHED: u8 = 1 << 7;
}

#[cfg(test)]
mod tests {
    //! The manual's example frames (`protocols.md`) are the test vectors.

    use super::*;

    fn hex(text: &str) -> Vec<u8> {
        text.split_whitespace()
            .map(|b| u8::from_str_radix(b, 16).expect("hex byte"))
            .collect()
    }

    #[test]
    fn move_pos_to_10_mm_is_the_manuals_frame() {
        assert_eq!(
            move_pos(1, 10.0, None).encode(),
            hex("05 01 05 B0 00 00 20 41 48 80")
        );
    }

    #[test]
    fn get_state_every_second_is_the_manuals_frame() {
        assert_eq!(
            get_state(1, 1.0, 0x01).encode(),
            hex("05 01 06 95 00 00 80 3F 01 54 41")
        );
    }

    #[test]
    fn the_manuals_replies_decode() {
        let mut decoder = Decoder::default();
        decoder.push(&hex("07 01 05 B0 EE EE 56 40 7B E4"));
        decoder.push(&hex("07 01 07 95 36 89 81 3F 02 00 F9 BC"));
        decoder.push(&hex("03 01 02 88 74 82 1B"));
        match Reply::parse(decoder.next_frame().expect("move reply")) {
            Reply::Value { command, value } => {
                assert_eq!(command, command::MOVE_POS);
                assert!((value - 3.358).abs() < 1e-3, "{value}");
            }
            other => panic!("{other:?}"),
        }
        match Reply::parse(decoder.next_frame().expect("state reply")) {
            Reply::State {
                position_mm,
                velocity_mm_s,
                state,
                error,
                ..
            } => {
                assert!((position_mm - 1.012).abs() < 1e-3);
                assert_eq!(velocity_mm_s, None);
                assert_eq!(state, state_bits::MOVING);
                assert_eq!(error, 0);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(
            Reply::parse(decoder.next_frame().expect("error message")),
            Reply::Error { error: 0x74 }
        );
        assert_eq!(error_meaning(0x74), "motor voltage low");
        assert_eq!(decoder.next_frame(), None);
        assert_eq!((decoder.discarded_bytes, decoder.crc_errors), (0, 0));
    }

    #[test]
    fn garbage_and_a_bad_crc_are_skipped() {
        let mut decoder = Decoder::default();
        let mut corrupt = hex("07 01 07 95 36 89 81 3F 02 00 F9 BC");
        corrupt[5] ^= 0xFF;
        decoder.push(&[0x00, 0xFF, 0x42]);
        decoder.push(&corrupt);
        decoder.push(&hex("03 01 02 88 74 82 1B"));
        assert_eq!(
            Reply::parse(decoder.next_frame().expect("the good frame after the bad")),
            Reply::Error { error: 0x74 }
        );
        assert!(decoder.crc_errors >= 1);
        assert!(decoder.discarded_bytes >= 3 + corrupt.len());
    }

    #[test]
    fn a_frame_split_across_reads_waits_for_its_end() {
        let bytes = hex("07 01 05 B0 EE EE 56 40 7B E4");
        let mut decoder = Decoder::default();
        decoder.push(&bytes[..4]);
        assert_eq!(decoder.next_frame(), None);
        decoder.push(&bytes[4..]);
        assert!(decoder.next_frame().is_some());
    }

    #[test]
    fn ok_and_refusals_parse() {
        let ok = Frame {
            group: Group::Reply,
            module_id: 1,
            command: command::CMD_REFERENCE,
            data: b"OK".to_vec(),
        };
        assert_eq!(
            Reply::parse(ok),
            Reply::Ok {
                command: command::CMD_REFERENCE
            }
        );
        let refused = Frame {
            group: Group::Reply,
            module_id: 1,
            command: command::MOVE_POS,
            data: vec![0x06],
        };
        assert_eq!(
            Reply::parse(refused),
            Reply::Refused {
                command: command::MOVE_POS,
                error: 0x06
            }
        );
    }

    #[test]
    fn every_encoded_request_decodes_to_itself() {
        for frame in [
            move_pos(12, 33.5, Some((50.0, 200.0))),
            move_grip(12, 1.5),
            get_state(12, 0.0, 0x07),
            simple(12, command::CMD_ACK),
        ] {
            let mut decoder = Decoder::default();
            decoder.push(&frame.encode());
            assert_eq!(decoder.next_frame(), Some(frame));
        }
    }
}
