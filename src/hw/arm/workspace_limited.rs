//! The arm's safety limits as a wrapper of the `Arm` trait, whatever the
//! arm and whatever the caller: no move may end outside the cell's
//! workspace box or go faster than the cell allows. A straight move
//! between two poses inside a box stays inside it, so checking the target
//! is enough.

use nalgebra::Isometry3;
use serde::Deserialize;

use super::Arm;
use crate::hw::{DeviceError, DeviceKind};

/// An axis-aligned box in the base frame that the TCP must stay in.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorkspaceBox {
    pub min_mm: [f64; 3],
    pub max_mm: [f64; 3],
}

impl WorkspaceBox {
    pub fn contains(&self, point_mm: [f64; 3]) -> bool {
        (0..3).all(|axis| (self.min_mm[axis]..=self.max_mm[axis]).contains(&point_mm[axis]))
    }
}

pub struct WorkspaceLimited<A: Arm> {
    arm: A,
    workspace: WorkspaceBox,
    max_speed_mm_s: f64,
}

impl<A: Arm> WorkspaceLimited<A> {
    pub fn new(arm: A, workspace: WorkspaceBox, max_speed_mm_s: f64) -> Self {
        Self {
            arm,
            workspace,
            max_speed_mm_s,
        }
    }
}

impl<A: Arm> Arm for WorkspaceLimited<A> {
    fn base_from_tcp(&mut self) -> Result<Isometry3<f64>, DeviceError> {
        self.arm.base_from_tcp()
    }

    fn move_linear(
        &mut self,
        base_from_tcp: &Isometry3<f64>,
        speed_mm_s: f64,
    ) -> Result<(), DeviceError> {
        if !(speed_mm_s > 0.0 && speed_mm_s <= self.max_speed_mm_s) {
            return Err(DeviceError::TooFast {
                device: DeviceKind::Arm,
                command: "move_linear",
                speed_mm_s,
                limit_mm_s: self.max_speed_mm_s,
            });
        }
        let target_mm: [f64; 3] = base_from_tcp.translation.vector.into();
        if !self.workspace.contains(target_mm) {
            return Err(DeviceError::OutsideWorkspace {
                device: DeviceKind::Arm,
                command: "move_linear",
                target_mm,
                min_mm: self.workspace.min_mm,
                max_mm: self.workspace.max_mm,
            });
        }
        self.arm.move_linear(base_from_tcp, speed_mm_s)
    }

    fn stop(&mut self) -> Result<(), DeviceError> {
        self.arm.stop()
    }
}

/// So that the cell can wrap whichever arm its file names.
impl Arm for Box<dyn Arm> {
    fn base_from_tcp(&mut self) -> Result<Isometry3<f64>, DeviceError> {
        (**self).base_from_tcp()
    }

    fn move_linear(
        &mut self,
        base_from_tcp: &Isometry3<f64>,
        speed_mm_s: f64,
    ) -> Result<(), DeviceError> {
        (**self).move_linear(base_from_tcp, speed_mm_s)
    }

    fn stop(&mut self) -> Result<(), DeviceError> {
        (**self).stop()
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Translation3, UnitQuaternion};

    use super::*;

    /// Counts the moves that reached it.
    struct Counting {
        moves: usize,
    }

    impl Arm for Counting {
        fn base_from_tcp(&mut self) -> Result<Isometry3<f64>, DeviceError> {
            Ok(Isometry3::identity())
        }

        fn move_linear(&mut self, _: &Isometry3<f64>, _: f64) -> Result<(), DeviceError> {
            self.moves += 1;
            Ok(())
        }

        fn stop(&mut self) -> Result<(), DeviceError> {
            Ok(())
        }
    }

    fn limited() -> WorkspaceLimited<Counting> {
        let workspace = WorkspaceBox {
            min_mm: [300.0, -200.0, 100.0],
            max_mm: [600.0, 200.0, 500.0],
        };
        WorkspaceLimited::new(Counting { moves: 0 }, workspace, 250.0)
    }

    fn at(x: f64, y: f64, z: f64) -> Isometry3<f64> {
        Isometry3::from_parts(Translation3::new(x, y, z), UnitQuaternion::identity())
    }

    #[test]
    fn moves_inside_the_box_and_below_the_speed_limit_go_through() {
        let mut arm = limited();
        arm.move_linear(&at(300.0, 200.0, 100.0), 250.0)
            .expect("on the box's corner");
        arm.move_linear(&at(450.0, 0.0, 260.0), 10.0)
            .expect("inside");
        assert_eq!(arm.arm.moves, 2);
    }

    #[test]
    fn a_pose_outside_the_box_is_refused_before_the_arm_moves() {
        let mut arm = limited();
        // What a wild regrasp correction would ask: 40 mm below the table.
        match arm.move_linear(&at(450.0, 0.0, 60.0), 100.0) {
            Err(DeviceError::OutsideWorkspace { target_mm, .. }) => {
                assert_eq!(target_mm, [450.0, 0.0, 60.0])
            }
            other => panic!("{other:?}"),
        }
        for outside in [
            at(299.0, 0.0, 200.0),
            at(450.0, 201.0, 200.0),
            at(450.0, 0.0, f64::NAN),
        ] {
            assert!(arm.move_linear(&outside, 100.0).is_err(), "{outside:?}");
        }
        assert_eq!(arm.arm.moves, 0);
    }

    #[test]
    fn too_fast_or_not_a_speed_is_refused() {
        let mut arm = limited();
        for speed_mm_s in [250.1, 0.0, -5.0, f64::NAN, f64::INFINITY] {
            match arm.move_linear(&at(450.0, 0.0, 200.0), speed_mm_s) {
                Err(DeviceError::TooFast { limit_mm_s, .. }) => assert_eq!(limit_mm_s, 250.0),
                other => panic!("{speed_mm_s}: {other:?}"),
            }
        }
        assert_eq!(arm.arm.moves, 0);
        let message = arm
            .move_linear(&at(450.0, 0.0, 20.0), 100.0)
            .expect_err("below the box")
            .to_string();
        assert!(message.contains("outside the workspace box"), "{message}");
    }
}
