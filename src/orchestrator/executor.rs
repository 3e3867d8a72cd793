//! Carries out the machine's commands on a cell; all of the sequence's I/O
//! is here.

use nalgebra::{Isometry3, Translation3};

use super::command::{Command, Event};
use crate::cell::CellDevices;
use crate::hw::DeviceError;
use crate::hw::tactile::TactileFrame;

/// Runs `command` and answers with its event; a device error becomes
/// `Event::DeviceFault`.
pub fn execute(cell: &mut CellDevices, command: &Command) -> Event {
    let result = match command {
        Command::Prepare {
            open_mm,
            bias_frames,
        } => prepare(cell, *open_mm, *bias_frames),
        Command::Detect => cell
            .detector
            .detect(cell.camera.as_mut())
            .map(Event::Detected),
        Command::MoveTo {
            base_from_tcp,
            speed_mm_s,
        } => cell
            .arm
            .move_linear(base_from_tcp, *speed_mm_s)
            .map(|()| Event::Arrived),
        Command::Grasp {
            base_from_tcp,
            speed_mm_s,
            grip_current_a,
        } => grasp(cell, base_from_tcp, *speed_mm_s, *grip_current_a),
        Command::ReadTactile { frames } => read_tactile(cell, *frames),
        Command::Regrasp {
            base_from_tcp,
            speed_mm_s,
            open_mm,
            retreat_mm,
            grip_current_a,
        }
        | Command::Probe {
            base_from_tcp,
            speed_mm_s,
            open_mm,
            retreat_mm,
            grip_current_a,
        } => regrasp(
            cell,
            base_from_tcp,
            *speed_mm_s,
            *open_mm,
            *retreat_mm,
            *grip_current_a,
        ),
        Command::SafeStop { open_mm } => Ok(safe_stop(cell, *open_mm)),
    };
    result.unwrap_or_else(Event::DeviceFault)
}

fn prepare(cell: &mut CellDevices, open_mm: f64, bias_frames: usize) -> Result<Event, DeviceError> {
    cell.gripper.reference()?;
    cell.gripper.move_to(open_mm)?;
    read_tactile(cell, bias_frames)
}

fn read_tactile(cell: &mut CellDevices, count: usize) -> Result<Event, DeviceError> {
    Ok(Event::Tactile {
        frames: read_frames(cell, count)?,
        true_line: cell.cable_on_pad_truth(),
    })
}

fn read_frames(cell: &mut CellDevices, count: usize) -> Result<Vec<TactileFrame>, DeviceError> {
    (0..count).map(|_| cell.tactile.read()).collect()
}

fn grasp(
    cell: &mut CellDevices,
    base_from_tcp: &Isometry3<f64>,
    speed_mm_s: f64,
    grip_current_a: f64,
) -> Result<Event, DeviceError> {
    cell.arm.move_linear(base_from_tcp, speed_mm_s)?;
    let grip = cell.gripper.grip(grip_current_a)?;
    Ok(Event::Grasped {
        base_from_tcp: cell.arm.base_from_tcp()?,
        grip,
    })
}

/// Release, back off along the approach axis, move over the corrected
/// pose (or the search's next one), and grasp again.
fn regrasp(
    cell: &mut CellDevices,
    base_from_tcp: &Isometry3<f64>,
    speed_mm_s: f64,
    open_mm: f64,
    retreat_mm: f64,
    grip_current_a: f64,
) -> Result<Event, DeviceError> {
    let back_off = Translation3::new(0.0, 0.0, -retreat_mm);
    cell.gripper.move_to(open_mm)?;
    let released_at = cell.arm.base_from_tcp()?;
    cell.arm
        .move_linear(&(released_at * back_off), speed_mm_s)?;
    cell.arm
        .move_linear(&(base_from_tcp * back_off), speed_mm_s)?;
    grasp(cell, base_from_tcp, speed_mm_s, grip_current_a)
}

/// Best effort: every device is asked, whatever the others answer.
fn safe_stop(cell: &mut CellDevices, open_mm: f64) -> Event {
    let problems = [
        cell.arm.stop(),
        cell.gripper.stop(),
        cell.gripper.move_to(open_mm),
    ]
    .into_iter()
    .filter_map(Result::err)
    .collect();
    Event::Stopped { problems }
}
