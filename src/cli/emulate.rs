//! `cablecell emulate pg70|tactile`: a device emulator on a new
//! pseudo-terminal, for trying the bring-up commands and the cell without
//! hardware.

use crate::cli::output::outln;
use std::io::Write;
use std::sync::atomic::AtomicBool;

use cablecell::cell::load_cell;
use cablecell::geometry::LineInSensor;
use cablecell::hw::emulator::PtyEmulator;
use cablecell::hw::gripper::pg70_emulator::{FreeJaws, Pg70Emulator};
use cablecell::hw::tactile::remodel_emulator::TactileEmulator;
use cablecell::sim::tactile_model::TactileModel;
use cablecell::sim::{Stream, rng};
use serialport::TTYPort;

use super::Status;

#[derive(clap::ValueEnum, Debug, Clone, Copy)]
pub enum Emulated {
    /// The Schunk PG70 gripper, speaking SMP.
    Pg70,
    /// The tactile finger's microcontroller, with the simulated pad.
    Tactile,
}

/// What an emulator does with its end of the pseudo-terminal.
type Serve = Box<dyn FnOnce(TTYPort, &AtomicBool) + Send>;

pub fn emulate(device: Emulated, module_id: u8, cell: &std::path::Path) -> Status {
    let (what, serve): (String, Serve) = match device {
        Emulated::Pg70 => (
            format!("a PG70, module id {module_id}"),
            Box::new(move |master, stop| {
                Pg70Emulator::new(module_id, FreeJaws::new(None)).serve(master, stop)
            }),
        ),
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
            (
                "the tactile finger's microcontroller, a cable on the pad".to_owned(),
                Box::new(move |master, stop| {
                    TactileEmulator::new(identity, move || Some(model.frame(cable, &mut noise)))
                        .serve(master, stop)
                }),
            )
        }
    };
    // The slave end is held open for as long as we serve: with no slave
    // open, the master's reads fail, and clients come and go.
    let (emulator, _slave) = match PtyEmulator::start(serve) {
        Ok(started) => started,
        Err(error) => {
            eprintln!("error: cannot make a pseudo-terminal: {error}");
            return Status::OutputFailed;
        }
    };
    announce(emulator.path(), &what);
    match emulator.wait() {
        Ok(()) => Status::Success,
        Err(_) => Status::DeviceFault,
    }
}

fn announce(path: &str, what: &str) {
    outln!("{path}");
    let _ = std::io::stdout().flush();
    eprintln!("emulating {what} on {path}; Ctrl-C stops it");
}
