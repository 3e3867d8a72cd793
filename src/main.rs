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
/// task, cell, campaign or map file, a task beyond its cell's limits, a
/// model that is no network, shards that are not one campaign); 3 device
/// fault (the cell was made safe, or a bring-up command's device failed);
/// 4 the output (a journal, a file, a folder) could not be written or read
/// back.
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
        #[command(flatten)]
        record: cli::run::RecordArgs,
    },
    /// Step a task interactively: breakpoints, pauses, the sensors' view,
    /// parameters changed on the way (`help` inside lists the commands).
    Repl {
        /// The task file to load first, e.g. tasks/regrasp.toml.
        task: Option<PathBuf>,
        /// The cell file.
        #[arg(long, default_value = "config/cell.sim.toml")]
        cell: PathBuf,
        /// Seed of the simulated cell (default: the task file's, else random).
        #[arg(long)]
        seed: Option<u64>,
        /// Cell seconds per wall-clock second while a task runs (a simulated
        /// cell runs at a real one's speed with 1); 0: as fast as it goes.
        #[arg(long, default_value_t = 1.0, value_parser = pace)]
        pace: f64,
        #[command(flatten)]
        record: cli::run::RecordArgs,
    },
    /// Print a recording's timeline, and fit its tactile frames again.
    Replay {
        /// The recording (MCAP), e.g. runs/regrasp-seed3-….mcap.
        file: PathBuf,
        /// Fit the recorded frames again with these estimators (centroids,
        /// ridge, oracle), to compare them on the same inputs.
        #[arg(long, value_delimiter = ',', value_parser = parse_estimator)]
        estimator: Vec<cablecell::perception::tactile::Estimator>,
        /// Run the vision pipeline again on the recorded camera images (with
        /// the pipeline's options below, or the cell's with --cell), to
        /// compare settings on the same inputs.
        #[arg(long)]
        vision: bool,
        /// With --vision: the cell file the run used; its detector's own
        /// settings replace the options below, so the cables are those the
        /// task's detect state found.
        #[arg(long, requires = "vision")]
        cell: Option<PathBuf>,
        #[command(flatten)]
        vision_args: cli::vision_io::VisionArgs,
    },
    /// Print the task's state machine as Graphviz DOT (`| dot -Tsvg`).
    Graph {
        /// The task file whose machine to draw, e.g. tasks/regrasp.toml.
        task: PathBuf,
    },
    /// Print the JSON Schema of a command's JSON output (docs/schemas/
    /// holds them all).
    JsonSchema {
        /// Which output.
        output: cli::json::JsonOutput,
    },
    /// Draw a figure from a recording, as PNG or SVG.
    Plot {
        #[command(subcommand)]
        figure: cli::plot::PlotCommand,
    },
    /// Run the bench: the cell's main settings (estimator, regrasp policy
    /// and tolerance, tactile averaging, the camera's shape fused or not)
    /// on the same seeded trials of tasks/paper-regrasp-campaign.toml, each
    /// one's error against its computation and cell time with the Pareto
    /// front marked; the vision pipeline's settings (network input size,
    /// mask and instance method) and skips on rendered images with exact
    /// labels, error against time; and the latency of each stage. Run from
    /// the repository's root.
    Bench {
        /// Fewer trials and images (20 trials a setting instead of 100, 10
        /// rendered images instead of 40): about a minute in a release
        /// build.
        #[arg(long)]
        quick: bool,
        /// Print the tables as JSON.
        #[arg(long)]
        json: bool,
        /// Draw final |n| against the cell's time and the vision's union
        /// DICE against its time, the fronts joined, to this file (PNG or
        /// SVG by its extension).
        #[arg(long, value_name = "FILE")]
        plot: Option<PathBuf>,
        /// Also score the vision settings on the labelled photographs of
        /// this folder (cables-dev's layout, e.g. /work/shared/data/cables-dev).
        #[arg(long, value_name = "DIR")]
        photos: Option<PathBuf>,
    },
    /// Run a campaign: many seeded trials of a task, each policy of the file
    /// on identical trials, recorded to OUT/trials.jsonl as they finish, and
    /// summarised side by side; or merge a sharded campaign's folders
    /// (`campaign merge DIR…`).
    #[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
    Campaign {
        #[command(subcommand)]
        merge: Option<CampaignCommand>,
        /// The campaign file, e.g. tasks/paper-regrasp-campaign.toml.
        #[arg(required = true)]
        file: Option<PathBuf>,
        /// Trials per policy (default: the file's).
        #[arg(long, value_parser = trials)]
        trials: Option<usize>,
        /// The campaign's seed (default: the file's).
        #[arg(long)]
        seed: Option<u64>,
        /// Output folder (default: the file's; OUT/shard-K-of-N with --shard).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Run only shard K of N (0 ≤ K < N): the trials i with i mod N = K.
        /// `campaign merge` gathers the shards' folders.
        #[arg(long, value_parser = shard)]
        shard: Option<cablecell::campaign::shard::Shard>,
        /// Continue the campaign recorded in the output folder.
        #[arg(long)]
        resume: bool,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
        /// Worker threads (default: one per core). Results do not depend on it.
        #[arg(long, value_parser = threads)]
        threads: Option<usize>,
        /// Write no recordings (by default each trial is recorded to
        /// OUT/recordings/trial-NNNNNN-POLICY.mcap).
        #[arg(long)]
        no_record: bool,
    },
    /// Find every cable in images: its B-spline, the grasp point at s = 0.5
    /// and the cable's direction there, and the time spent in each stage
    /// (by a warmed-up pipeline: the first image is run once beforehand,
    /// untimed, to load the network and set OpenCV up).
    Detect {
        /// The images (PNG, JPEG, any OpenCV reads), each detected in turn.
        #[arg(required = true)]
        images: Vec<PathBuf>,
        #[command(flatten)]
        vision: cli::vision_io::VisionArgs,
        /// A cell file whose calibrated camera took the images: the cell's
        /// own vision settings (region of interest, network, its scale,
        /// straight edges, confidence floor) replace the options above, so
        /// that the cables are those the task's detect state finds, and each
        /// grasp frame is also given in the robot's base frame.
        #[arg(long)]
        cell: Option<PathBuf>,
        /// Print one JSON object of reports.
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
    /// Estimate the camera's pose in the base frame from the marker on the
    /// finger: the arm shows the marker from the cell file's
    /// `camera.calibration_poses`, and the pose is stored in the file's
    /// `[camera.calibration]`.
    CalibrateCamera {
        /// The cell file.
        #[arg(long, default_value = "config/cell.sim.toml")]
        cell: PathBuf,
        /// Seed of the simulated cell.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Speed of the arm between poses.
        #[arg(long, default_value_t = 100.0)]
        speed_mm_s: f64,
        /// Print the calibration without storing it.
        #[arg(long)]
        dry_run: bool,
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
        /// Which device to emulate.
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
        /// Task, cell and campaign files, each checked by its top table.
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
        #[arg(long, default_value_t = 3.55, value_parser = pitch_mm)]
        pitch_mm: f64,
        /// Peak Δv below which the pad touches nothing.
        #[arg(long, default_value_t = 0.05, value_parser = contact_threshold_v)]
        contact_threshold_v: f64,
    },
}

#[derive(Subcommand)]
enum CampaignCommand {
    /// Check that the folders are every shard of one campaign, each once,
    /// holding every trial once, and print the whole campaign's summary.
    Merge {
        /// The shards' output folders (each with campaign.json and
        /// trials.jsonl).
        #[arg(required = true)]
        folders: Vec<PathBuf>,
        /// Also write the merged campaign here, as the whole campaign's
        /// output folder (journal, campaign.json, recordings).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
enum DeviceCommand {
    /// The Schunk PG70 over SMP.
    Gripper {
        /// The serial port, e.g. /dev/ttyUSB0.
        #[arg(long)]
        port: String,
        /// The link's speed, bit/s (the PG70's factory setting).
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
        /// The serial port, e.g. /dev/ttyACM0.
        #[arg(long)]
        port: String,
        /// The link's speed, bit/s (the microcontroller's firmware setting).
        #[arg(long, default_value_t = 1_000_000)]
        baud: u32,
        #[command(subcommand)]
        action: cli::device::TactileAction,
    },
    /// A Franka Panda over its FCI link (cablecell built with `--features panda`).
    Arm {
        /// The controller's host name or IPv4 address, e.g. 172.16.0.2.
        #[arg(long)]
        address: String,
        #[command(subcommand)]
        action: cli::device::ArmAction,
    },
}

/// 0 (as fast as it goes) to 1000 cell seconds a second.
fn pace(text: &str) -> Result<f64, String> {
    cli::number_within(text, 0.0..=1000.0, "")
}

fn shard(text: &str) -> Result<cablecell::campaign::shard::Shard, String> {
    text.parse()
        .map_err(|e: cablecell::campaign::run::CampaignError| e.to_string())
}

fn trials(text: &str) -> Result<usize, String> {
    cli::number_within(text, cablecell::task::campaign_file::TRIALS, "trials")
}

/// 1 to 1024 threads: more than any machine's cores, each a cell's memory.
fn threads(text: &str) -> Result<usize, String> {
    cli::number_within(text, 1..=1024, "threads")
}

fn pitch_mm(text: &str) -> Result<f64, String> {
    cli::number_within(text, cablecell::hw::tactile::config::PITCH_MM, "mm")
}

fn contact_threshold_v(text: &str) -> Result<f64, String> {
    cli::number_within(
        text,
        cablecell::perception::tactile::CONTACT_THRESHOLD_V,
        "V",
    )
}

fn parse_estimator(text: &str) -> Result<cablecell::perception::tactile::Estimator, String> {
    serde_json::from_value(serde_json::Value::String(text.to_owned()))
        .map_err(|_| format!("`{text}`: expected centroids, ridge or oracle"))
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
            record,
        } => cli::run::run(&task, &cell, seed, json, &record),
        Command::Repl {
            task,
            cell,
            seed,
            pace,
            record,
        } => cli::repl::repl(task.as_deref(), &cell, seed, record, pace),
        Command::Replay {
            file,
            estimator,
            vision,
            cell,
            vision_args,
        } => cli::replay::replay(
            &file,
            &estimator,
            vision.then_some(&vision_args),
            cell.as_deref(),
        ),
        Command::Graph { task } => cli::graph::graph(&task),
        Command::JsonSchema { output } => cli::json::json_schema(output),
        Command::Plot { figure } => cli::plot::plot(&figure),
        Command::Bench {
            quick,
            json,
            plot,
            photos,
        } => cli::bench::bench(quick, json, plot.as_deref(), photos.as_deref()),
        Command::Campaign {
            merge: Some(CampaignCommand::Merge { folders, out, json }),
            ..
        } => cli::campaign::merge(&folders, out.as_deref(), json),
        Command::Campaign {
            merge: None,
            file: Some(file),
            trials,
            seed,
            out,
            shard,
            resume,
            json,
            threads,
            no_record,
        } => {
            let overrides = cablecell::campaign::run::Overrides {
                trials,
                seed,
                out,
                no_record,
                shard,
            };
            let threads = threads.unwrap_or_else(|| {
                std::thread::available_parallelism().map_or(1, std::num::NonZero::get)
            });
            cli::campaign::campaign(&file, overrides, resume, json, threads)
        }
        Command::Campaign { file: None, .. } => {
            eprintln!("error: the campaign file is missing: cablecell campaign FILE");
            cli::Status::BadInput
        }
        Command::Detect {
            images,
            vision,
            cell,
            json,
            masks,
            overlay,
        } => cli::detect::detect(
            &images,
            &vision,
            cell.as_deref(),
            json,
            masks.as_deref(),
            overlay.as_deref(),
        ),
        Command::CalibrateCamera {
            cell,
            seed,
            speed_mm_s,
            dry_run,
        } => cli::calibrate_camera::calibrate_camera(&cell, seed, speed_mm_s, dry_run),
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
            DeviceCommand::Arm { address, action } => cli::device::arm(&address, &action),
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

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// Every argument of every command, as `COMMAND … ARGUMENT`, that
    /// `--help` would list without a word on it.
    fn undocumented(command: &clap::Command, path: &str, found: &mut Vec<String>) {
        for arg in command.get_arguments() {
            if arg.get_help().is_none() && arg.get_long_help().is_none() {
                found.push(format!("{path} {}", arg.get_id()));
            }
        }
        for sub in command.get_subcommands() {
            let sub_path = format!("{path} {}", sub.get_name());
            if sub.get_about().is_none() {
                found.push(sub_path.clone());
            }
            undocumented(sub, &sub_path, found);
        }
    }

    #[test]
    fn every_argument_has_help_text() {
        let mut command = super::Args::command();
        command.build();
        let mut found = Vec::new();
        undocumented(&command, "cablecell", &mut found);
        assert!(found.is_empty(), "arguments without help: {found:#?}");
    }
}
