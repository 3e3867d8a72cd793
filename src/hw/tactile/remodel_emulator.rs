//! An emulated tactile microcontroller: answers `b`, `c` and `a` as the
//! REMODEL firmware does, its samples taken from a source (the simulated
//! pad, in the emulated cell), and can misbehave.

use std::io::{Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};

use serde::Deserialize;

use crate::hw::emulator::FaultSwitch;
use crate::hw::nothing_arrived;
use crate::perception::tactile::{RawFrame, TAXEL_COUNT};

/// Ways the emulated microcontroller can misbehave.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Misbehaviour {
    /// Answers only part of a sample.
    Truncated,
    /// Stops answering.
    Silent,
    /// Sends a stray byte before each answer.
    StrayByte,
    /// Sends bytes that cannot be 12-bit samples instead of each answer.
    Garbage,
    /// The sensor goes away: the emulator closes its end of the port.
    Vanish,
}

/// `source` gives each sample, or `None` when it has none (a silent
/// sensor).
pub struct TactileEmulator<S: FnMut() -> Option<RawFrame>> {
    id: [u8; 4],
    /// Taxel k is sent on ADC channel `layout[k]`.
    layout: [usize; TAXEL_COUNT],
    source: S,
    requests_served: usize,
    pub fault: FaultSwitch<Misbehaviour>,
}

impl<S: FnMut() -> Option<RawFrame>> TactileEmulator<S> {
    pub fn new(layout: [usize; TAXEL_COUNT], source: S) -> Self {
        Self {
            id: *b"F001",
            layout,
            source,
            requests_served: 0,
            fault: FaultSwitch::default(),
        }
    }

    /// The bytes answering one request byte, as the sensor misbehaves.
    pub fn respond(&mut self, request: u8, misbehaviour: Option<Misbehaviour>) -> Vec<u8> {
        if misbehaviour == Some(Misbehaviour::Silent) {
            return Vec::new();
        }
        let mut answer = match request {
            b'b' => self.id.to_vec(),
            b'c' => vec![TAXEL_COUNT as u8],
            b'a' => {
                let Some(frame) = (self.source)() else {
                    return Vec::new();
                };
                let mut channels = [0u16; TAXEL_COUNT];
                for (taxel, &channel) in self.layout.iter().enumerate() {
                    channels[channel] = frame[taxel];
                }
                channels
                    .iter()
                    .flat_map(|c| [(c & 0xFF) as u8, (c >> 8) as u8 & 0x0F])
                    .collect()
            }
            _ => Vec::new(),
        };
        match misbehaviour {
            Some(Misbehaviour::Truncated) => answer.truncate(answer.len() / 2),
            Some(Misbehaviour::StrayByte) if !answer.is_empty() => answer.insert(0, 0xA5),
            Some(Misbehaviour::Garbage) => answer.fill(0xF7),
            _ => {}
        }
        answer
    }

    /// Serves `port` until it fails or closes, `stop` is set, or the
    /// sensor vanishes.
    pub fn serve(&mut self, mut port: impl Read + Write, stop: &AtomicBool) {
        let mut buffer = [0u8; 16];
        while !stop.load(Ordering::Relaxed) {
            let n = match port.read(&mut buffer) {
                Ok(0) => return,
                Ok(n) => n,
                Err(e) if nothing_arrived(&e) => {
                    continue;
                }
                Err(_) => return,
            };
            for &request in &buffer[..n] {
                let misbehaviour = self.fault.active(self.requests_served);
                self.requests_served += 1;
                if misbehaviour == Some(Misbehaviour::Vanish) {
                    return;
                }
                let answer = self.respond(request, misbehaviour);
                if port.write_all(&answer).and_then(|()| port.flush()).is_err() {
                    return;
                }
            }
        }
    }
}
