//! A simulated tactile pad polled at its rate, reading the simulated cable.

use rand_chacha::ChaCha8Rng;

use super::{TactileFrame, TactileSensor};
use crate::hw::{DeviceError, DeviceKind};
use crate::sim::tactile_model::{Contact, Dents, TactileModel};
use crate::sim::world::{SharedWorld, lock};

pub struct SimTactile {
    world: SharedWorld,
    model: TactileModel,
    period_s: f64,
    rng: ChaCha8Rng,
    last_t_s: Option<f64>,
    frames_read: u64,
    /// Fault injection: stop answering after this many frames.
    silent_after_frames: Option<u64>,
    /// The last contact and the cap's deformation under it: a held cable
    /// does not move between frames, so it is computed once per grasp.
    dented: Option<(Contact, Dents)>,
}

impl SimTactile {
    pub fn new(
        world: SharedWorld,
        model: TactileModel,
        rate_hz: f64,
        silent_after_frames: Option<u64>,
        rng: ChaCha8Rng,
    ) -> Self {
        Self {
            world,
            model,
            period_s: 1.0 / rate_hz,
            rng,
            last_t_s: None,
            frames_read: 0,
            silent_after_frames,
            dented: None,
        }
    }
}

impl TactileSensor for SimTactile {
    fn read(&mut self) -> Result<TactileFrame, DeviceError> {
        let mut world = lock(&self.world);
        if self
            .silent_after_frames
            .is_some_and(|n| self.frames_read >= n)
        {
            // A silent sensor costs the caller its whole deadline.
            let waited_ms = 100;
            world.now_s += waited_ms as f64 / 1000.0;
            return Err(DeviceError::Timeout {
                device: DeviceKind::Tactile,
                waited_ms,
            });
        }
        // The next sample tick at or after now.
        let t_s = match self.last_t_s {
            Some(last) => (last + self.period_s).max(world.now_s),
            None => world.now_s,
        };
        world.now_s = t_s;
        self.last_t_s = Some(t_s);
        self.frames_read += 1;
        let contact = world.held().map(|line| Contact {
            line,
            diameter_mm: world.cable_diameter_mm,
            squeeze_fraction: world.squeeze_fraction,
        });
        let dents = match contact {
            None => [0.0; crate::perception::tactile::TAXEL_COUNT],
            Some(contact) => match self.dented {
                Some((last, dents)) if last == contact => dents,
                _ => {
                    let dents = self.model.dents(&contact);
                    self.dented = Some((contact, dents));
                    dents
                }
            },
        };
        Ok(TactileFrame {
            t_s,
            raw: self.model.frame_from_dents(&dents, &mut self.rng),
        })
    }
}
