//! Emulators of the cell's serial devices: they speak the devices' real
//! protocols on a byte stream (a pseudo-terminal in the tests), and can
//! misbehave on purpose, so that the real drivers are tested end to end.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::Duration;

use serde::Deserialize;
use serialport::{SerialPort, TTYPort};

/// How an emulator misbehaves, and from which request on: the first
/// `after_requests` requests are answered properly.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fault<M> {
    pub misbehaviour: M,
    #[serde(default)]
    pub after_requests: usize,
}

impl<M> Fault<M> {
    /// Misbehaves from the first request on.
    pub fn now(misbehaviour: M) -> Self {
        Self {
            misbehaviour,
            after_requests: 0,
        }
    }
}

/// An emulator's fault, shared: a test (or the cell that runs the
/// emulator) can switch it on while the emulator serves on its thread.
#[derive(Debug, Clone)]
pub struct FaultSwitch<M>(Arc<Mutex<Option<Fault<M>>>>);

impl<M: Copy> FaultSwitch<M> {
    pub fn new(fault: Option<Fault<M>>) -> Self {
        Self(Arc::new(Mutex::new(fault)))
    }

    /// Misbehave as `fault` says (its `after_requests` counts from the
    /// emulator's first request), or no longer with `None`.
    pub fn set(&self, fault: Option<Fault<M>>) {
        *self.0.lock().unwrap_or_else(PoisonError::into_inner) = fault;
    }

    /// How to answer request number `served` (counted from 0).
    pub fn active(&self, served: usize) -> Option<M> {
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .filter(|fault| served >= fault.after_requests)
            .map(|fault| fault.misbehaviour)
    }
}

impl<M: Copy> Default for FaultSwitch<M> {
    fn default() -> Self {
        Self::new(None)
    }
}

/// An emulator serving the master end of a new pseudo-terminal on a
/// thread of its own until it is unplugged or dropped: what the emulated
/// cell, `cablecell emulate`, the driver tests and the polling benchmark
/// all run a device emulator in.
pub struct PtyEmulator {
    path: String,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

/// How long the emulator's reads wait before it looks at its stop flag.
const MASTER_READ_TIMEOUT: Duration = Duration::from_millis(5);

impl PtyEmulator {
    /// Makes a new pseudo-terminal and hands its master end to `serve` on a
    /// new thread; `serve` returns once the flag it is given is set.
    /// Returns the harness and the slave end, for a driver to talk through
    /// (or to hold open while a driver opens the port by its path: with no
    /// slave open the master's reads fail).
    pub fn start(
        serve: impl FnOnce(TTYPort, &AtomicBool) + Send + 'static,
    ) -> Result<(Self, TTYPort), serialport::Error> {
        let (mut master, slave) = TTYPort::pair()?;
        master.set_timeout(MASTER_READ_TIMEOUT)?;
        let path = slave.name().unwrap_or_else(|| "a pseudo-terminal".into());
        let stop = Arc::new(AtomicBool::new(false));
        let serving = Arc::clone(&stop);
        let thread = std::thread::spawn(move || serve(master, &serving));
        let emulator = Self {
            path,
            stop,
            thread: Some(thread),
        };
        Ok((emulator, slave))
    }

    /// The slave end's path, e.g. `/dev/pts/3`.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Stops the emulator and closes its end, as if the device were
    /// unplugged; an `Err` carries the emulator thread's panic.
    pub fn unplug(&mut self) -> std::thread::Result<()> {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.take().map_or(Ok(()), JoinHandle::join)
    }

    /// Serves until the emulator thread ends (for `cablecell emulate`,
    /// which serves until it is killed).
    pub fn wait(mut self) -> std::thread::Result<()> {
        self.thread.take().map_or(Ok(()), JoinHandle::join)
    }
}

impl Drop for PtyEmulator {
    fn drop(&mut self) {
        // A panicking emulator has already reported itself.
        let _ = self.unplug();
    }
}
