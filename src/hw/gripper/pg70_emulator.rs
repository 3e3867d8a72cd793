//! An emulated PG70: answers SMP requests as the module does, including
//! refusals before referencing and beyond the stroke, and the spontaneous
//! end-of-move messages. The jaws it moves are any `Gripper`: free jaws
//! with an optional object between them (`FreeJaws`, for bring-up and the
//! driver's tests), or the simulated cell's (`SimGripper`, in the emulated
//! cell), so the real driver moves the simulated jaws.

use std::io::{Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};

use serde::Deserialize;

use crate::hw::DeviceError;
use crate::hw::emulator::FaultSwitch;
use crate::hw::gripper::smp::{Decoder, Frame, Group, command, state_bits};
use crate::hw::gripper::{GripOutcome, Gripper};
use crate::hw::nothing_arrived;

/// Ways the emulated module can misbehave.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Misbehaviour {
    /// Random-looking bytes before every answer (the driver resynchronises).
    GarbageFirst,
    /// Random-looking bytes instead of every answer.
    Garbage,
    /// No answer at all.
    Silent,
    /// Answers whose CRC is wrong.
    BadCrc,
    /// Only the first half of every answer.
    Truncated,
    /// An error message with this code instead of every answer (0xD9:
    /// emergency stop).
    ErrorFrame(u8),
    /// The module goes away: the emulator closes its end of the port.
    Vanish,
}

/// Jaws with nothing but an optional object between them.
pub struct FreeJaws {
    /// Width of an object between the jaws: a grip from a wider opening
    /// stops on it.
    object_mm: Option<f64>,
    opening_mm: f64,
}

impl FreeJaws {
    pub fn new(object_mm: Option<f64>) -> Self {
        Self {
            object_mm,
            opening_mm: 0.0,
        }
    }
}

impl Gripper for FreeJaws {
    fn reference(&mut self) -> Result<(), DeviceError> {
        self.opening_mm = 0.0;
        Ok(())
    }

    fn move_to(&mut self, opening_mm: f64) -> Result<(), DeviceError> {
        self.opening_mm = opening_mm;
        Ok(())
    }

    fn grip(&mut self, _current_a: f64) -> Result<GripOutcome, DeviceError> {
        let blocked_at = self.object_mm.filter(|&width| width < self.opening_mm);
        self.opening_mm = blocked_at.unwrap_or(0.0);
        Ok(match blocked_at {
            Some(opening_mm) => GripOutcome::Holding { opening_mm },
            None => GripOutcome::Empty,
        })
    }

    fn stop(&mut self) -> Result<(), DeviceError> {
        Ok(())
    }
}

pub struct Pg70Emulator<J: Gripper> {
    module_id: u8,
    stroke_mm: f32,
    speed_mm_s: f32,
    position_mm: f32,
    referenced: bool,
    jaws: J,
    requests_served: usize,
    pub fault: FaultSwitch<Misbehaviour>,
}

impl<J: Gripper> Pg70Emulator<J> {
    pub fn new(module_id: u8, jaws: J) -> Self {
        Self {
            module_id,
            stroke_mm: 68.0,
            speed_mm_s: 80.0,
            position_mm: 0.0,
            referenced: false,
            jaws,
            requests_served: 0,
            fault: FaultSwitch::default(),
        }
    }

    /// The frames the module sends in answer to `request`.
    pub fn respond(&mut self, request: &Frame) -> Vec<Frame> {
        let id = self.module_id;
        let ok = || reply(id, request.command, b"OK".to_vec());
        let refuse = |error: u8| vec![reply(id, request.command, vec![error])];
        match request.command {
            command::CMD_REFERENCE => {
                if self.jaws.reference().is_err() {
                    return refuse(0xDA);
                }
                self.referenced = true;
                self.position_mm = 0.0;
                vec![ok(), value(id, command::CMD_POS_REACHED, 0.0)]
            }
            command::MOVE_POS | command::MOVE_GRIP if !self.referenced => refuse(0x06),
            command::MOVE_POS => match request.float(0) {
                Some(target) if target > self.stroke_mm => refuse(0xD6),
                Some(target) if target < 0.0 => refuse(0xD5),
                Some(target) => {
                    if self.jaws.move_to(f64::from(target)).is_err() {
                        return refuse(0xDA);
                    }
                    let duration_s = (target - self.position_mm).abs() / self.speed_mm_s;
                    self.position_mm = target;
                    vec![
                        value(id, command::MOVE_POS, duration_s),
                        value(id, command::CMD_POS_REACHED, target),
                    ]
                }
                None => refuse(0x1D),
            },
            command::MOVE_GRIP => match request.float(0).map(|a| self.jaws.grip(f64::from(a))) {
                Some(Ok(GripOutcome::Holding { opening_mm })) => {
                    self.position_mm = opening_mm as f32;
                    vec![ok(), value(id, command::CMD_MOVE_BLOCKED, self.position_mm)]
                }
                Some(Ok(GripOutcome::Empty)) => {
                    self.position_mm = 0.0;
                    vec![ok(), value(id, command::CMD_POS_REACHED, 0.0)]
                }
                Some(Err(_)) => refuse(0xDE),
                None => refuse(0x1D),
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
            command::CMD_STOP => {
                // The jaws stop whether or not they were moving.
                let _ = self.jaws.stop();
                vec![ok()]
            }
            command::CMD_ACK => vec![ok()],
            _ => refuse(0x1D),
        }
    }

    /// Serves `port` until it fails or closes, `stop` is set, or the
    /// module vanishes. `port`'s reads must time out now and then so that
    /// `stop` is seen.
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
                let misbehaviour = self.fault.active(self.requests_served);
                self.requests_served += 1;
                if misbehaviour == Some(Misbehaviour::Vanish) {
                    return;
                }
                let answer = self.respond(&request);
                let bytes = wire(&answer, misbehaviour, self.module_id);
                if port.write_all(&bytes).and_then(|()| port.flush()).is_err() {
                    return;
                }
            }
        }
    }
}

/// Bytes that cannot be taken for a frame, with a group byte among them.
const GARBAGE: [u8; 6] = [0x00, 0x42, 0x07, 0x01, 0xFF, 0x3C];

/// The answer's bytes as the module misbehaves.
fn wire(frames: &[Frame], misbehaviour: Option<Misbehaviour>, module_id: u8) -> Vec<u8> {
    if let Some(Misbehaviour::ErrorFrame(error)) = misbehaviour {
        return Frame {
            group: Group::Error,
            module_id,
            command: command::CMD_ERROR,
            data: vec![error],
        }
        .encode();
    }
    let mut bytes = Vec::new();
    for frame in frames {
        let mut encoded = frame.encode();
        match misbehaviour {
            None | Some(Misbehaviour::ErrorFrame(_) | Misbehaviour::Vanish) => {}
            Some(Misbehaviour::GarbageFirst) => bytes.extend_from_slice(&GARBAGE),
            Some(Misbehaviour::Garbage) => encoded = GARBAGE.to_vec(),
            Some(Misbehaviour::Silent) => continue,
            Some(Misbehaviour::BadCrc) => {
                if let Some(last) = encoded.last_mut() {
                    *last ^= 0x5A;
                }
            }
            Some(Misbehaviour::Truncated) => encoded.truncate(encoded.len() / 2),
        }
        bytes.append(&mut encoded);
    }
    bytes
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
