//! `cablecell emulate pg70|tactile`: a device emulator on a new
//! pseudo-terminal, for trying the bring-up commands and the cell without
//! hardware.

use std::io::Write;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use cablecell::cell::load_cell;
use cablecell::geometry::LineInSensor;
use cablecell::hw::gripper::pg70_emulator::{FreeJaws, Pg70Emulator};
use cablecell::hw::tactile::remodel_emulator::TactileEmulator;
use cablecell::sim::tactile_model::TactileModel;
use cablecell::sim::{Stream, rng};
use serialport::{SerialPort, TTYPort};

use super::Status;

#[derive(clap::ValueEnum, Debug, Clone, Copy)]
pub enum Emulated {
    Pg70,
    Tactile,
}

pub fn emulate(device: Emulated, module_id: u8, cell: &std::path::Path) -> Status {
    let (mut master, slave) = match TTYPort::pair() {
        Ok(pair) => pair,
        Err(error) => {
            eprintln!("error: cannot make a pseudo-terminal: {error}");
            return Status::OutputFailed;
        }
    };
    let path = slave.name().unwrap_or_default();
    if let Err(error) = master.set_timeout(Duration::from_millis(10)) {
        eprintln!("error: {path}: {error}");
        return Status::OutputFailed;
    }
    // Held open for as long as we serve: with no slave open, the master's
    // reads fail, and clients come and go.
    let _slave = slave;
    let never = AtomicBool::new(false);
    match device {
        Emulated::Pg70 => {
            announce(&path, &format!("a PG70, module id {module_id}"));
            Pg70Emulator::new(module_id, FreeJaws::new(None)).serve(master, &never);
        }
        Emulated::Tactile => {
            let mut file = match load_cell(cell) {
                Ok(file) => file,
                Err(error) => {
                    eprintln!("error: {error}");
                    return Status::BadInput;
                }
            };
            let pitch_mm = file.tactile.pitch_mm;
            let Some(config) = file.tactile.backend.sim_pad_mut() else {
                eprintln!(
                    "error: {}: [tactile.backend] has no simulated pad to sample \
                     (use a cell file with a sim or emulated_remodel tactile backend)",
                    cell.display()
                );
                return Status::BadInput;
            };
            let model =
                TactileModel::new(config, pitch_mm, &mut rng(1, Stream::TactileCalibration));
            let mut noise = rng(1, Stream::Tactile);
            // A 2.5 mm cable lying across the pad, slightly off its axis.
            let cable = Some((LineInSensor::new(0.1, 1.0), 2.5));
            let identity = std::array::from_fn(|k| k);
            announce(
                &path,
                "the tactile finger's microcontroller, a cable on the pad",
            );
            TactileEmulator::new(identity, move || Some(model.frame(cable, &mut noise)))
                .serve(master, &never);
        }
    }
    Status::Success
}

fn announce(path: &str, what: &str) {
    println!("{path}");
    let _ = std::io::stdout().flush();
    eprintln!("emulating {what} on {path}; Ctrl-C stops it");
}
