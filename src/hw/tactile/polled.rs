//! A tactile sensor polled on its own thread at a fixed rate, so that the
//! state machine never waits on the serial link: the thread publishes each
//! timestamped frame (or the sensor's error), and `read` takes the next
//! one sampled after it was called.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::{TactileFrame, TactileSensor};
use crate::hw::{DeviceError, DeviceKind};

/// The last thing the polling thread got from the sensor.
struct Latest {
    /// Counts the polls: a reader takes each frame at most once.
    poll: u64,
    /// When the poll's request went out: a reader takes only frames
    /// requested after it asked, never one sampled before a grasp ended.
    requested_at: Instant,
    result: Result<TactileFrame, DeviceError>,
}

struct Shared {
    latest: Mutex<Option<Latest>>,
    published: Condvar,
    stop: AtomicBool,
}

impl Shared {
    fn latest(&self) -> MutexGuard<'_, Option<Latest>> {
        self.latest.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

pub struct PolledTactile {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    /// The last poll handed to a reader.
    last_poll: u64,
    /// How long `read` waits for a frame before it calls the poller dead;
    /// the sensor's own deadline reports a silent sensor well before.
    patience: Duration,
}

impl PolledTactile {
    /// Polls `sensor` every `1 / rate_hz` seconds until dropped.
    pub fn start<S: TactileSensor + 'static>(mut sensor: S, rate_hz: f64) -> Self {
        let period = Duration::from_secs_f64(1.0 / rate_hz);
        let shared = Arc::new(Shared {
            latest: Mutex::new(None),
            published: Condvar::new(),
            stop: AtomicBool::new(false),
        });
        let polling = Arc::clone(&shared);
        let thread = std::thread::spawn(move || {
            let mut next_poll = Instant::now();
            let mut poll = 0;
            while !polling.stop.load(Ordering::Relaxed) {
                let requested_at = Instant::now();
                let result = sensor.read();
                poll += 1;
                *polling.latest() = Some(Latest {
                    poll,
                    requested_at,
                    result,
                });
                polling.published.notify_all();
                // A fixed rate: a late poll is followed at once, not made up.
                next_poll = (next_poll + period).max(Instant::now());
                std::thread::sleep(next_poll.saturating_duration_since(Instant::now()));
            }
        });
        Self {
            shared,
            thread: Some(thread),
            last_poll: 0,
            patience: period * 10 + Duration::from_millis(500),
        }
    }
}

impl TactileSensor for PolledTactile {
    fn read(&mut self) -> Result<TactileFrame, DeviceError> {
        let asked_at = Instant::now();
        let deadline = asked_at + self.patience;
        let mut latest = self.shared.latest();
        loop {
            if let Some(fresh) = latest
                .as_ref()
                .filter(|l| l.poll > self.last_poll && l.requested_at >= asked_at)
            {
                self.last_poll = fresh.poll;
                return fresh.result.clone();
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(DeviceError::Timeout {
                    device: DeviceKind::Tactile,
                    waited_ms: self.patience.as_millis() as u64,
                });
            }
            latest = self
                .shared
                .published
                .wait_timeout(latest, deadline - now)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
        }
    }
}

impl Drop for PolledTactile {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            // A panic on the polling thread has already been reported.
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frame n reads n on every taxel; once `failing` is set it answers
    /// with a timeout, after hanging for `hang` when that is set.
    struct Scripted {
        n: u16,
        failing: Arc<AtomicBool>,
        hang: Option<Duration>,
    }

    impl TactileSensor for Scripted {
        fn read(&mut self) -> Result<TactileFrame, DeviceError> {
            if self.failing.load(Ordering::SeqCst) {
                if let Some(hang) = self.hang {
                    std::thread::sleep(hang);
                }
                return Err(DeviceError::Timeout {
                    device: DeviceKind::Tactile,
                    waited_ms: 20,
                });
            }
            self.n += 1;
            Ok(TactileFrame {
                t_s: f64::from(self.n),
                raw: [self.n; crate::perception::tactile::TAXEL_COUNT],
            })
        }
    }

    #[test]
    fn readers_get_fresh_frames_each_once_then_the_sensors_error() {
        let failing = Arc::new(AtomicBool::new(false));
        let sensor = Scripted {
            n: 0,
            failing: Arc::clone(&failing),
            hang: None,
        };
        let mut polled = PolledTactile::start(sensor, 1000.0);
        let mut last = 0;
        for _ in 0..5 {
            let frame = polled.read().expect("a frame");
            assert!(frame.raw[0] > last, "{} after {last}", frame.raw[0]);
            last = frame.raw[0];
        }
        // The sensor fails from now on: the next read is a poll made after
        // it, so it gets the error.
        failing.store(true, Ordering::SeqCst);
        assert_eq!(
            polled.read(),
            Err(DeviceError::Timeout {
                device: DeviceKind::Tactile,
                waited_ms: 20
            })
        );
    }

    #[test]
    fn a_sensor_that_hangs_is_a_timeout_for_the_reader() {
        let sensor = Scripted {
            n: 0,
            failing: Arc::new(AtomicBool::new(true)),
            hang: Some(Duration::from_secs(2)),
        };
        let mut polled = PolledTactile::start(sensor, 500.0);
        match polled.read() {
            Err(DeviceError::Timeout { waited_ms, .. }) => assert_eq!(waited_ms, 520),
            other => panic!("{other:?}"),
        }
    }
}
