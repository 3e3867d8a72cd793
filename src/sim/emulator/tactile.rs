//! An emulated tactile microcontroller: answers `b`, `c` and `a` as the
//! REMODEL firmware does, its samples taken from a source (the simulated
//! pad, in the emulated cell), and can misbehave.

use std::io::{Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};

use crate::hw::nothing_arrived;
use crate::perception::tactile::{RawFrame, TAXEL_COUNT};

/// Ways the emulated microcontroller can misbehave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Misbehaviour {
    None,
    /// Answers only part of a sample.
    Truncated,
    /// Stops answering after this many samples.
    SilentAfter(usize),
    /// Sends a stray byte before each answer.
    StrayByte,
}

pub struct TactileEmulator<S: FnMut() -> RawFrame> {
    id: [u8; 4],
    /// Taxel k is sent on ADC channel `layout[k]`.
    layout: [usize; TAXEL_COUNT],
    source: S,
    samples_sent: usize,
    pub misbehaviour: Misbehaviour,
}

impl<S: FnMut() -> RawFrame> TactileEmulator<S> {
    pub fn new(layout: [usize; TAXEL_COUNT], source: S) -> Self {
        Self {
            id: *b"F001",
            layout,
            source,
            samples_sent: 0,
            misbehaviour: Misbehaviour::None,
        }
    }

    /// The bytes answering one request byte.
    pub fn respond(&mut self, request: u8) -> Vec<u8> {
        let mut answer = match request {
            b'b' => self.id.to_vec(),
            b'c' => vec![TAXEL_COUNT as u8],
            b'a' => {
                if matches!(self.misbehaviour, Misbehaviour::SilentAfter(n) if self.samples_sent >= n)
                {
                    return Vec::new();
                }
                self.samples_sent += 1;
                let frame = (self.source)();
                let mut channels = [0u16; TAXEL_COUNT];
                for (taxel, &channel) in self.layout.iter().enumerate() {
                    channels[channel] = frame[taxel];
                }
                let mut bytes: Vec<u8> = channels
                    .iter()
                    .flat_map(|c| [(c & 0xFF) as u8, (c >> 8) as u8 & 0x0F])
                    .collect();
                if self.misbehaviour == Misbehaviour::Truncated {
                    bytes.truncate(bytes.len() / 2);
                }
                bytes
            }
            _ => Vec::new(),
        };
        if self.misbehaviour == Misbehaviour::StrayByte && !answer.is_empty() {
            answer.insert(0, 0xA5);
        }
        answer
    }

    /// Serves `port` until it fails or closes, or `stop` is set.
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
                let answer = self.respond(request);
                if port.write_all(&answer).and_then(|()| port.flush()).is_err() {
                    return;
                }
            }
        }
    }
}
