//! Emulators of the cell's serial devices: they speak the devices' real
//! protocols on a byte stream (a pseudo-terminal in the tests), and can
//! misbehave on purpose, so that the real drivers are tested end to end.

use std::sync::{Arc, Mutex, PoisonError};

use serde::Deserialize;

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
