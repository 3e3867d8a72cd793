//! Task, cell and campaign files: the text read as each of the three, by
//! the parse their loaders use (the cell's with its checks across tables),
//! as if it lay beside the shipped cell files so that their relative paths
//! resolve. An error names a place inside the text.

#![no_main]

use std::path::Path;

use cablecell::cell::load::parse_cell;
use cablecell::schema::toml_file::{ConfigError, parse};
use cablecell::task::{CampaignFile, TaskFile};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../config/fuzz.toml"));
    let lines = text.lines().count();
    let check = |error: ConfigError| {
        if let ConfigError::Invalid { line, column, .. } = error {
            assert!((1..=lines + 1).contains(&line), "line {line} of {lines}");
            assert!(column >= 1);
        }
    };
    let errors = [
        parse::<TaskFile>(path, text).err(),
        parse_cell(path, text).err(),
        parse::<CampaignFile>(path, text).err(),
    ];
    errors.into_iter().flatten().for_each(check);
});
