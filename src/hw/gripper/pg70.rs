//! The Schunk PG70 over SMP, on any byte stream: a serial port in the lab,
//! a pseudo-terminal to an emulator in the tests.

use std::io::{Read, Write};
use std::time::{Duration, Instant};

use super::smp::{self, Decoder, Frame, Reply, command};
use super::{GripOutcome, Gripper};
use crate::hw::nothing_arrived;
use crate::hw::{DeviceError, DeviceKind};

pub struct Pg70<T: Read + Write + Send> {
    port: T,
    /// Named in errors: the port's path.
    port_name: String,
    module_id: u8,
    decoder: Decoder,
    /// How long the module may take to answer a request.
    reply_timeout: Duration,
    /// How long a move (reference, position, grip) may take to end.
    move_timeout: Duration,
    /// Jaw speed and acceleration of position moves; `None` leaves the
    /// module's own.
    speed_accel: Option<(f32, f32)>,
}

impl<T: Read + Write + Send> Pg70<T> {
    /// `port` must return from `read` within a short timeout (a serial
    /// port's own), so that the driver can keep its deadlines.
    pub fn new(port: T, port_name: &str, module_id: u8) -> Self {
        Self {
            port,
            port_name: port_name.to_owned(),
            module_id,
            decoder: Decoder::default(),
            reply_timeout: Duration::from_millis(500),
            move_timeout: Duration::from_secs(10),
            speed_accel: None,
        }
    }

    /// How long the module may take to answer a request, and a move to
    /// end.
    pub fn with_timeouts(mut self, reply_timeout: Duration, move_timeout: Duration) -> Self {
        self.reply_timeout = reply_timeout;
        self.move_timeout = move_timeout;
        self
    }

    /// Position moves at this jaw speed and acceleration.
    pub fn with_motion(mut self, speed_mm_s: f32, accel_mm_s2: f32) -> Self {
        self.speed_accel = Some((speed_mm_s, accel_mm_s2));
        self
    }

    /// The module's state once: position, velocity, current, state bits
    /// and error code.
    pub fn state(&mut self) -> Result<Reply, DeviceError> {
        self.request(smp::get_state(self.module_id, 0.0, 0x07), "state")
    }

    /// Acknowledges an error, so that the module moves again.
    pub fn acknowledge(&mut self) -> Result<(), DeviceError> {
        self.request(smp::simple(self.module_id, command::CMD_ACK), "acknowledge")
            .map(|_| ())
    }

    /// Sends `frame` and returns the module's answer to it; spontaneous
    /// error messages end the wait as a refusal.
    fn request(&mut self, frame: Frame, name: &'static str) -> Result<Reply, DeviceError> {
        self.port
            .write_all(&frame.encode())
            .and_then(|()| self.port.flush())
            .map_err(|e| self.io_error(name, &e))?;
        let wanted = frame.command;
        let reply = self.wait(name, self.reply_timeout, |reply| match reply {
            Reply::Ok { command }
            | Reply::Refused { command, .. }
            | Reply::Value { command, .. } => *command == wanted,
            Reply::State { .. } => wanted == command::GET_STATE,
            Reply::Error { .. } => true,
            Reply::Other(_) => false,
        })?;
        match reply {
            Reply::Refused { error, .. } | Reply::Error { error } => Err(self.refused(name, error)),
            reply => Ok(reply),
        }
    }

    /// Waits for the end of a move: position reached or move blocked.
    fn wait_for_move(&mut self, name: &'static str) -> Result<Reply, DeviceError> {
        let reply = self.wait(name, self.move_timeout, |reply| {
            matches!(
                reply,
                Reply::Value {
                    command: command::CMD_POS_REACHED | command::CMD_MOVE_BLOCKED,
                    ..
                } | Reply::Error { .. }
            )
        })?;
        match reply {
            Reply::Error { error } => Err(self.refused(name, error)),
            reply => Ok(reply),
        }
    }

    /// Reads until a reply that `wanted` accepts, or the deadline: a
    /// timeout if nothing came, garbled if only unusable bytes did.
    fn wait(
        &mut self,
        name: &'static str,
        timeout: Duration,
        wanted: impl Fn(&Reply) -> bool,
    ) -> Result<Reply, DeviceError> {
        let deadline = Instant::now() + timeout;
        let (discarded, crc_errors) = (self.decoder.discarded_bytes, self.decoder.crc_errors);
        let mut buffer = [0u8; 64];
        loop {
            while let Some(frame) = self.decoder.next_frame() {
                if frame.module_id != self.module_id {
                    continue;
                }
                let reply = Reply::parse(frame);
                if wanted(&reply) {
                    return Ok(reply);
                }
            }
            if Instant::now() >= deadline {
                let discarded = self.decoder.discarded_bytes - discarded;
                let crc_errors = self.decoder.crc_errors - crc_errors;
                let pending = self.decoder.pending_bytes();
                if discarded + crc_errors + pending == 0 {
                    return Err(DeviceError::NoAnswer {
                        device: DeviceKind::Gripper,
                        port: self.port_name.clone(),
                        command: name,
                        waited_ms: timeout.as_millis() as u64,
                    });
                }
                return Err(DeviceError::Garbled {
                    device: DeviceKind::Gripper,
                    port: self.port_name.clone(),
                    detail: format!(
                        "no whole answer to {name} within {} ms: {discarded} byte(s) \
                         discarded, {crc_errors} wrong CRC(s), {pending} byte(s) of an \
                         unfinished frame",
                        timeout.as_millis()
                    ),
                });
            }
            match self.port.read(&mut buffer) {
                Ok(0) => return Err(self.gone(name, "the port closed")),
                Ok(n) => self.decoder.push(&buffer[..n]),
                Err(e) if nothing_arrived(&e) => {}
                Err(e) => return Err(self.io_error(name, &e)),
            }
        }
    }

    fn refused(&self, command: &'static str, error: u8) -> DeviceError {
        DeviceError::Refused {
            device: DeviceKind::Gripper,
            command,
            reason: format!("error 0x{error:02X}: {}", smp::error_meaning(error)),
        }
    }

    fn io_error(&self, command: &'static str, error: &std::io::Error) -> DeviceError {
        self.gone(command, &error.to_string())
    }

    fn gone(&self, command: &'static str, reason: &str) -> DeviceError {
        DeviceError::Disconnected {
            device: DeviceKind::Gripper,
            port: self.port_name.clone(),
            reason: format!("{command}: {reason}"),
        }
    }
}

impl<T: Read + Write + Send> Gripper for Pg70<T> {
    fn reference(&mut self) -> Result<(), DeviceError> {
        self.request(
            smp::simple(self.module_id, command::CMD_REFERENCE),
            "reference",
        )?;
        self.wait_for_move("reference").map(|_| ())
    }

    fn move_to(&mut self, opening_mm: f64) -> Result<(), DeviceError> {
        self.request(
            smp::move_pos(self.module_id, opening_mm as f32, self.speed_accel),
            "move_to",
        )?;
        match self.wait_for_move("move_to")? {
            Reply::Value {
                command: command::CMD_MOVE_BLOCKED,
                value,
            } => Err(DeviceError::Refused {
                device: DeviceKind::Gripper,
                command: "move_to",
                reason: format!("blocked at {value:.2} mm"),
            }),
            _ => Ok(()),
        }
    }

    fn grip(&mut self, current_a: f64) -> Result<GripOutcome, DeviceError> {
        self.request(smp::move_grip(self.module_id, current_a as f32), "grip")?;
        Ok(match self.wait_for_move("grip")? {
            Reply::Value {
                command: command::CMD_MOVE_BLOCKED,
                value,
            } => GripOutcome::Holding {
                opening_mm: f64::from(value),
            },
            _ => GripOutcome::Empty,
        })
    }

    fn stop(&mut self) -> Result<(), DeviceError> {
        self.request(smp::simple(self.module_id, command::CMD_STOP), "stop")
            .map(|_| ())
    }
}
