//! The `cablecell` command line.

mod cli;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Robot task orchestrator for a vision- and tactile-guided cable-grasping
/// cell.
///
/// Exit status: 0 success; 1 the task failed (e.g. tolerance not reached in
/// the allowed regrasps, no cable on the pad); 2 bad input (command line,
/// task, cell, campaign or map file); 3 device fault (the cell was made
/// safe, or a bring-up command's device failed); 4 the output (a campaign's
/// journal) could not be written or read.
#[derive(Parser)]
#[command(version, about, long_about)]
struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a task on a cell, printing each state transition and the cable's
    /// pose on the pad after each grasp.
    Run {
        /// The task file, e.g. tasks/regrasp.toml.
        task: PathBuf,
        /// The cell file.
        #[arg(long, default_value = "config/cell.sim.toml")]
        cell: PathBuf,
        /// Seed of the simulated cell (default: the task file's, else random).
        #[arg(long)]
        seed: Option<u64>,
        /// Print one JSON report instead of the running commentary.
        #[arg(long)]
        json: bool,
    },
    /// Run a campaign: many seeded trials of a task, each policy of the file
    /// on identical trials, recorded to OUT/trials.jsonl as they finish, and
    /// summarised side by side.
    Campaign {
        /// The campaign file, e.g. tasks/paper-regrasp-campaign.toml.
        file: PathBuf,
        /// Trials per policy (default: the file's).
        #[arg(long)]
        trials: Option<usize>,
        /// The campaign's seed (default: the file's).
        #[arg(long)]
        seed: Option<u64>,
        /// Output folder (default: the file's).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Continue the campaign recorded in the output folder.
        #[arg(long)]
        resume: bool,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
        /// Worker threads (default: one per core). Results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Find every cable in images: its B-spline, the grasp point at s = 0.5
    /// and the cable's direction there, and the time spent in each stage.
    Detect {
        #[arg(required = true)]
        images: Vec<PathBuf>,
        #[command(flatten)]
        vision: cli::vision_io::VisionArgs,
        /// Print one JSON array of reports.
        #[arg(long)]
        json: bool,
        /// Write each cable's mask (NAME_mask_K.png) and their union
        /// (NAME_mask_all.png) here.
        #[arg(long)]
        masks: Option<PathBuf>,
        /// Write each image with its splines and grasp frames drawn here.
        #[arg(long)]
        overlay: Option<PathBuf>,
    },
    /// Score the vision pipeline on a folder laid out like cables-dev
    /// (NNNNN.jpg, NNNNN_mask_K.png, NNNNN_mask_all.png, NNNNN.txt).
    EvalVision(cli::eval_vision::EvalVisionArgs),
    /// Render synthetic images of cables with exact masks and centre lines,
    /// in the layout of cables-dev (training data for the network, test
    /// data for eval-vision).
    RenderDataset(cli::render_dataset::RenderDatasetArgs),
    /// Talk to one device and print what it answered: the first thing to
    /// run when bringing up a cell.
    Device {
        #[command(subcommand)]
        device: DeviceCommand,
    },
    /// Serve an emulated device on a new pseudo-terminal, whose path is
    /// printed, until stopped.
    Emulate {
        #[arg(value_enum)]
        device: cli::emulate::Emulated,
        /// The PG70's module id.
        #[arg(long, default_value_t = 12)]
        id: u8,
        /// The cell file whose simulated pad the tactile emulator uses.
        #[arg(long, default_value = "config/cell.sim.toml")]
        cell: PathBuf,
    },
    /// Validate task, cell and campaign files without running them.
    Check {
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// Fit the cable on one 5×5 Δv map (25 numbers, row-major c11..c55, as a
    /// JSON array or separated by white space or commas) and print the
    /// direction, centroids and linear and quadratic fits as JSON.
    TactileFit {
        /// The map file; standard input if absent or `-`.
        file: Option<PathBuf>,
        /// Taxel pitch.
        #[arg(long, default_value_t = 3.55)]
        pitch_mm: f64,
        /// Peak Δv below which the pad touches nothing.
        #[arg(long, default_value_t = 0.05)]
        contact_threshold_v: f64,
    },
}

#[derive(Subcommand)]
enum DeviceCommand {
    /// The Schunk PG70 over SMP.
    Gripper {
        /// The serial port, e.g. /dev/ttyUSB0.
        #[arg(long)]
        port: String,
        #[arg(long, default_value_t = 9600)]
        baud: u32,
        /// The module id set in the gripper.
        #[arg(long, default_value_t = 12)]
        id: u8,
        #[command(subcommand)]
        action: cli::device::GripperAction,
    },
    /// The tactile finger's microcontroller.
    Tactile {
        #[arg(long)]
        port: String,
        #[arg(long, default_value_t = 1_000_000)]
        baud: u32,
        #[command(subcommand)]
        action: cli::device::TactileAction,
    },
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_writer(std::io::stderr)
        .init();
    let status = match Args::parse().command {
        Command::Run {
            task,
            cell,
            seed,
            json,
        } => cli::run::run(&task, &cell, seed, json),
        Command::Campaign {
            file,
            trials,
            seed,
            out,
            resume,
            json,
            threads,
        } => {
            let overrides = cablecell::campaign::run::Overrides { trials, seed, out };
            let threads = threads.unwrap_or_else(|| {
                std::thread::available_parallelism().map_or(1, std::num::NonZero::get)
            });
            cli::campaign::campaign(&file, overrides, resume, json, threads)
        }
        Command::Detect {
            images,
            vision,
            json,
            masks,
            overlay,
        } => cli::detect::detect(&images, &vision, json, masks.as_deref(), overlay.as_deref()),
        Command::EvalVision(args) => cli::eval_vision::eval_vision(&args),
        Command::RenderDataset(args) => cli::render_dataset::render_dataset(&args),
        Command::Device { device } => match device {
            DeviceCommand::Gripper {
                port,
                baud,
                id,
                action,
            } => cli::device::gripper(&port, baud, id, &action),
            DeviceCommand::Tactile { port, baud, action } => {
                cli::device::tactile(&port, baud, &action)
            }
        },
        Command::Emulate { device, id, cell } => cli::emulate::emulate(device, id, &cell),
        Command::Check { files } => cli::check::check(&files),
        Command::TactileFit {
            file,
            pitch_mm,
            contact_threshold_v,
        } => cli::tactile_fit::tactile_fit(file.as_deref(), pitch_mm, contact_threshold_v),
    };
    status.into()
}
