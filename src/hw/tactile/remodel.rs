//! The REMODEL 5×5 tactile finger's microcontroller over serial
//! (docs/protocols.md): single-byte requests, fixed-length answers with no
//! framing or checksum, 12-bit samples.
//!
//! Because nothing frames an answer, every request starts from an empty
//! input buffer and reads against its own deadline: a late byte of an old
//! answer must never be taken for the start of a new one.

use std::io::{Read, Write};
use std::time::{Duration, Instant};

use serialport::{ClearBuffer, SerialPort};

use super::{TactileFrame, TactileSensor};
use crate::hw::clock::Clock;
use crate::hw::nothing_arrived;
use crate::hw::{DeviceError, DeviceKind};
use crate::perception::tactile::{RawFrame, TAXEL_COUNT};

/// Request bytes.
const ID: u8 = b'b';
const COUNT: u8 = b'c';
const SAMPLE: u8 = b'a';

/// A byte stream whose unread input can be thrown away.
pub trait SerialLink: Read + Write + Send {
    fn discard_input(&mut self) -> std::io::Result<()>;
}

impl<P: SerialPort> SerialLink for P {
    fn discard_input(&mut self) -> std::io::Result<()> {
        self.clear(ClearBuffer::Input).map_err(std::io::Error::from)
    }
}

pub struct RemodelTactile<L: SerialLink> {
    link: L,
    port_name: String,
    /// `layout[k]` is the ADC channel of taxel k (c11..c55, row-major).
    layout: [usize; TAXEL_COUNT],
    deadline: Duration,
    clock: Box<dyn Clock>,
}

impl<L: SerialLink> RemodelTactile<L> {
    pub fn new(
        link: L,
        port_name: &str,
        layout: [usize; TAXEL_COUNT],
        clock: Box<dyn Clock>,
    ) -> Self {
        Self {
            link,
            port_name: port_name.to_owned(),
            layout,
            // A sample is 51 bytes at 1 Mbaud, half a millisecond; 20 ms
            // leaves room for a busy host without hiding a dead sensor.
            deadline: Duration::from_millis(20),
            clock,
        }
    }

    /// How long an answer may take to arrive whole.
    pub fn with_deadline(mut self, deadline: Duration) -> Self {
        self.deadline = deadline;
        self
    }

    /// The sensor's 4-character id: `F…` for a tactile pad.
    pub fn id(&mut self) -> Result<String, DeviceError> {
        let mut answer = [0u8; 4];
        self.exchange(ID, &mut answer, "id")?;
        Ok(String::from_utf8_lossy(&answer).into_owned())
    }

    /// The number of sensing elements (25 for this pad).
    pub fn count(&mut self) -> Result<u8, DeviceError> {
        let mut answer = [0u8; 1];
        self.exchange(COUNT, &mut answer, "count")?;
        Ok(answer[0])
    }

    /// One sample of every taxel, in taxel order.
    pub fn sample(&mut self) -> Result<RawFrame, DeviceError> {
        let mut answer = [0u8; 2 * TAXEL_COUNT];
        self.exchange(SAMPLE, &mut answer, "sample")?;
        // 12-bit samples leave every high byte's upper nibble clear: set
        // bits there mean the answer is shifted by a stray byte.
        if let Some(channel) = (0..TAXEL_COUNT).find(|&c| answer[2 * c + 1] & 0xF0 != 0) {
            return Err(DeviceError::Garbled {
                device: DeviceKind::Tactile,
                port: self.port_name.clone(),
                detail: format!(
                    "channel {channel}'s high byte 0x{:02X} is not 12-bit",
                    answer[2 * channel + 1]
                ),
            });
        }
        // Low byte, then the high byte's low nibble (12 bits: 256, not 255).
        let channel =
            |c: usize| u16::from(answer[2 * c]) | (u16::from(answer[2 * c + 1] & 0x0F) << 8);
        Ok(std::array::from_fn(|taxel| channel(self.layout[taxel])))
    }

    fn exchange(
        &mut self,
        request: u8,
        answer: &mut [u8],
        name: &'static str,
    ) -> Result<(), DeviceError> {
        self.link
            .discard_input()
            .and_then(|()| self.link.write_all(&[request]))
            .and_then(|()| self.link.flush())
            .map_err(|e| self.lost(name, &e.to_string()))?;
        let deadline = Instant::now() + self.deadline;
        let mut filled = 0;
        while filled < answer.len() {
            if Instant::now() >= deadline {
                let waited_ms = self.deadline.as_millis() as u64;
                return Err(if filled == 0 {
                    DeviceError::NoAnswer {
                        device: DeviceKind::Tactile,
                        port: self.port_name.clone(),
                        command: name,
                        waited_ms,
                    }
                } else {
                    DeviceError::Garbled {
                        device: DeviceKind::Tactile,
                        port: self.port_name.clone(),
                        detail: format!(
                            "{name}: answer cut short: {filled} of {} bytes within {waited_ms} ms",
                            answer.len()
                        ),
                    }
                });
            }
            match self.link.read(&mut answer[filled..]) {
                Ok(0) => return Err(self.lost(name, "the port closed")),
                Ok(n) => filled += n,
                Err(e) if nothing_arrived(&e) => {}
                Err(e) => return Err(self.lost(name, &e.to_string())),
            }
        }
        Ok(())
    }

    fn lost(&self, command: &'static str, reason: &str) -> DeviceError {
        DeviceError::Disconnected {
            device: DeviceKind::Tactile,
            port: self.port_name.clone(),
            reason: format!("{command}: {reason}"),
        }
    }
}

impl<L: SerialLink> TactileSensor for RemodelTactile<L> {
    fn read(&mut self) -> Result<TactileFrame, DeviceError> {
        let raw = self.sample()?;
        Ok(TactileFrame {
            t_s: self.clock.now_s(),
            raw,
        })
    }
}
