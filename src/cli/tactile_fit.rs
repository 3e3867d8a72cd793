//! `cablecell tactile-fit [FILE]`

use std::io::Read;
use std::path::Path;

use cablecell::perception::tactile::{FitConfig, FitError, TactileMap, fit_wire};

use super::Status;

pub fn tactile_fit(file: Option<&Path>, pitch_mm: f64, contact_threshold_v: f64) -> Status {
    let (source, text) = match read_input(file) {
        Ok(input) => input,
        Err((source, error)) => {
            eprintln!("error: {source}: cannot read: {error}");
            return Status::BadInput;
        }
    };
    let map = match TactileMap::parse(&text) {
        Ok(map) => map,
        Err(error) => {
            eprintln!("error: {source}: {error}");
            return Status::BadInput;
        }
    };
    let config = FitConfig {
        pitch_mm,
        contact_threshold_v,
    };
    match fit_wire(&map, &config) {
        Ok(fit) => super::json::print(&fit),
        Err(error @ FitError::InvalidConfig { .. }) => {
            eprintln!("error: {error}");
            Status::BadInput
        }
        Err(error) => {
            eprintln!("error: {source}: {error}");
            Status::TaskFailed
        }
    }
}

fn read_input(file: Option<&Path>) -> Result<(String, String), (String, std::io::Error)> {
    match file {
        Some(path) if path != Path::new("-") => {
            let source = path.display().to_string();
            std::fs::read_to_string(path)
                .map(|text| (source.clone(), text))
                .map_err(|error| (source, error))
        }
        _ => {
            let mut text = String::new();
            std::io::stdin()
                .read_to_string(&mut text)
                .map(|_| ("<stdin>".to_owned(), text))
                .map_err(|error| ("<stdin>".to_owned(), error))
        }
    }
}
