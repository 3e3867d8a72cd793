//! An emulated PG70: answers SMP requests as the module does, including
//! refusals before referencing, the spontaneous end-of-move messages, and
//! an object between the jaws that blocks a grip.

use std::io::{Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};

use crate::hw::gripper::smp::{Decoder, Frame, Group, command, state_bits};
use crate::hw::nothing_arrived;

/// Ways the emulated module can misbehave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Misbehaviour {
    None,
    /// Random-looking bytes before every answer.
    GarbageFirst,
    /// No answer at all.
    Silent,
    /// Answers whose CRC is wrong.
    BadCrc,
}

pub struct Pg70Emulator {
    module_id: u8,
    stroke_mm: f32,
    speed_mm_s: f32,
    position_mm: f32,
    referenced: bool,
    /// Width of an object between the jaws: a grip stops on it.
    pub object_mm: Option<f32>,
    pub misbehaviour: Misbehaviour,
}

impl Pg70Emulator {
    pub fn new(module_id: u8) -> Self {
        Self {
            module_id,
            stroke_mm: 68.0,
            speed_mm_s: 80.0,
            position_mm: 0.0,
            referenced: false,
            object_mm: None,
            misbehaviour: Misbehaviour::None,
        }
    }

    /// The frames the module sends in answer to `request`.
    pub fn respond(&mut self, request: &Frame) -> Vec<Frame> {
        let id = self.module_id;
        let ok = || reply(id, request.command, b"OK".to_vec());
        let refuse = |error: u8| vec![reply(id, request.command, vec![error])];
        match request.command {
            command::CMD_REFERENCE => {
                self.referenced = true;
                self.position_mm = 0.0;
                vec![ok(), value(id, command::CMD_POS_REACHED, 0.0)]
            }
            command::MOVE_POS | command::MOVE_GRIP if !self.referenced => refuse(0x06),
            command::MOVE_POS => match request.float(0) {
                Some(target) if target > self.stroke_mm => refuse(0xD6),
                Some(target) if target < 0.0 => refuse(0xD5),
                Some(target) => {
                    let duration_s = (target - self.position_mm).abs() / self.speed_mm_s;
                    self.position_mm = target;
                    vec![
                        value(id, command::MOVE_POS, duration_s),
                        value(id, command::CMD_POS_REACHED, target),
                    ]
                }
                None => refuse(0x1D),
            },
            command::MOVE_GRIP => match self.object_mm.filter(|&w| w < self.position_mm) {
                Some(width) => {
                    self.position_mm = width;
                    vec![ok(), value(id, command::CMD_MOVE_BLOCKED, width)]
                }
                None => {
                    self.position_mm = 0.0;
                    vec![ok(), value(id, command::CMD_POS_REACHED, 0.0)]
                }
            },
            command::GET_STATE => {
                let state = if self.referenced {
                    state_bits::REFERENCED
                } else {
                    0
                };
                let mut data = self.position_mm.to_le_bytes().to_vec();
                data.extend_from_slice(&[state, 0]);
                vec![reply(id, command::GET_STATE, data)]
            }
            command::CMD_STOP | command::CMD_ACK => vec![ok()],
            _ => refuse(0x1D),
        }
    }

    /// Serves `port` until it fails or closes, or `stop` is set. `port`'s
    /// reads must time out now and then so that `stop` is seen.
    pub fn serve(&mut self, mut port: impl Read + Write, stop: &AtomicBool) {
        let mut decoder = Decoder::default();
        let mut buffer = [0u8; 64];
        while !stop.load(Ordering::Relaxed) {
            match port.read(&mut buffer) {
                Ok(0) => return,
                Ok(n) => decoder.push(&buffer[..n]),
                Err(e) if nothing_arrived(&e) => {
                    continue;
                }
                Err(_) => return,
            }
            while let Some(request) = decoder.next_frame() {
                if request.group != Group::Request || request.module_id != self.module_id {
                    continue;
                }
                let answer = self.respond(&request);
                let bytes = self.wire(&answer);
                if port.write_all(&bytes).and_then(|()| port.flush()).is_err() {
                    return;
                }
            }
        }
    }

    /// The answer's bytes as this module misbehaves.
    fn wire(&self, frames: &[Frame]) -> Vec<u8> {
        let mut bytes = Vec::new();
        for frame in frames {
            let mut encoded = frame.encode();
            match self.misbehaviour {
                Misbehaviour::None => {}
                Misbehaviour::GarbageFirst => {
                    bytes.extend_from_slice(&[0x00, 0x42, 0x07, 0x01, 0xFF, 0x3C])
                }
                Misbehaviour::Silent => continue,
                Misbehaviour::BadCrc => {
                    if let Some(last) = encoded.last_mut() {
                        *last ^= 0x5A;
                    }
                }
            }
            bytes.append(&mut encoded);
        }
        bytes
    }
}

fn reply(module_id: u8, command: u8, data: Vec<u8>) -> Frame {
    Frame {
        group: Group::Reply,
        module_id,
        command,
        data,
    }
}

fn value(module_id: u8, command: u8, value: f32) -> Frame {
    reply(module_id, command, value.to_le_bytes().to_vec())
}
