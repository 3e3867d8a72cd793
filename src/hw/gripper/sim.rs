//! A simulated gripper: refuses to move until referenced (as the PG70
//! does), and closes until the jaws meet the cable or each other; opening
//! lets the cable go.

use super::{GripOutcome, Gripper};
use crate::hw::{DeviceError, DeviceKind};
use crate::sim::world::{SharedWorld, lock};

/// The most the jaws can squeeze a cable, as a fraction of its diameter:
/// beyond it the insulation, not the silicone, takes the force.
const MAX_SQUEEZE_FRACTION: f64 = 0.3;

pub struct SimGripper {
    world: SharedWorld,
    stroke_mm: f64,
    speed_mm_s: f64,
    squeeze_fraction_per_a: f64,
    referenced: bool,
}

impl SimGripper {
    pub fn new(
        world: SharedWorld,
        stroke_mm: f64,
        speed_mm_s: f64,
        squeeze_fraction_per_a: f64,
    ) -> Self {
        Self {
            world,
            stroke_mm,
            speed_mm_s,
            squeeze_fraction_per_a,
            referenced: false,
        }
    }

    fn refuse(&self, command: &'static str, reason: String) -> DeviceError {
        DeviceError::Refused {
            device: DeviceKind::Gripper,
            command,
            reason,
        }
    }
}

impl Gripper for SimGripper {
    fn reference(&mut self) -> Result<(), DeviceError> {
        let mut world = lock(&self.world);
        world.now_s += (self.stroke_mm - world.opening_mm) / self.speed_mm_s;
        world.opening_mm = self.stroke_mm;
        world.release();
        self.referenced = true;
        Ok(())
    }

    fn move_to(&mut self, opening_mm: f64) -> Result<(), DeviceError> {
        if !self.referenced {
            return Err(self.refuse("move_to", "not referenced".into()));
        }
        if !(0.0..=self.stroke_mm).contains(&opening_mm) {
            return Err(self.refuse(
                "move_to",
                format!(
                    "{opening_mm} mm is outside the stroke 0..{} mm",
                    self.stroke_mm
                ),
            ));
        }
        let mut world = lock(&self.world);
        world.now_s += (opening_mm - world.opening_mm).abs() / self.speed_mm_s;
        world.opening_mm = opening_mm;
        if world.grasp.is_some() && opening_mm > world.cable_diameter_mm {
            world.release();
        }
        Ok(())
    }

    fn grip(&mut self, current_a: f64) -> Result<GripOutcome, DeviceError> {
        if !self.referenced {
            return Err(self.refuse("grip", "not referenced".into()));
        }
        if current_a <= 0.0 {
            return Err(self.refuse("grip", format!("current {current_a} A is not positive")));
        }
        let squeeze_fraction = (self.squeeze_fraction_per_a * current_a).min(MAX_SQUEEZE_FRACTION);
        let mut world = lock(&self.world);
        let closed_mm = if world.close_on_cable(squeeze_fraction).is_some() {
            world.cable_diameter_mm * (1.0 - squeeze_fraction)
        } else {
            0.0
        };
        world.now_s += (world.opening_mm - closed_mm).max(0.0) / self.speed_mm_s;
        world.opening_mm = closed_mm;
        Ok(if world.grasp.is_some() {
            GripOutcome::Holding {
                opening_mm: closed_mm,
            }
        } else {
            GripOutcome::Empty
        })
    }

    fn stop(&mut self) -> Result<(), DeviceError> {
        Ok(())
    }
}
