//! Task, cell and campaign files: their schemas, and loading that names
//! the file, line, column and field of every error.
//!
//! A task file says what to do (target pose, tolerance, how many regrasps);
//! a cell file says with what (which backend each device uses, its limits
//! and calibration); a campaign file runs a task many times. Each begins
//! with its own table, `[task]`, `[cell]` or `[campaign]`, so that
//! `cablecell check` can tell them apart.

pub mod campaign_file;
pub mod load;
pub mod task_file;

pub use campaign_file::CampaignFile;
pub use load::{
    FileKind, check_file, check_on_cell, load_campaign, load_task, load_task_on_cell, parse_task,
};
pub use task_file::TaskFile;
