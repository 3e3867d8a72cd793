//! The cell's time. Simulated cells advance it by the durations their
//! devices would take, so a run is deterministic and takes no wall time.

pub trait Clock: Send {
    /// Seconds since the cell started.
    fn now_s(&self) -> f64;
}

/// A real cell's clock: seconds since it was made (its clones share that
/// start).
#[derive(Clone)]
pub struct MonotonicClock {
    start: std::time::Instant,
}

impl MonotonicClock {
    pub fn new() -> Self {
        Self {
            start: std::time::Instant::now(),
        }
    }
}

impl Default for MonotonicClock {
    fn default() -> Self {
        Self::new()
    }
}

impl Clock for MonotonicClock {
    fn now_s(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
}

/// The simulated world's clock, advanced by the simulated devices.
pub struct SimClock {
    world: crate::sim::world::SharedWorld,
}

impl SimClock {
    pub fn new(world: crate::sim::world::SharedWorld) -> Self {
        Self { world }
    }
}

impl Clock for SimClock {
    fn now_s(&self) -> f64 {
        crate::sim::world::lock(&self.world).now_s
    }
}
