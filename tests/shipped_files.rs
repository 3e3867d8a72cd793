//! Every task and cell file shipped in `tasks/` and `config/` is valid.

mod common;

use cablecell::task::{FileKind, check_file};

fn toml_files(dir: &str) -> Vec<std::path::PathBuf> {
    let dir = common::root().join(dir);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.expect("directory entry").path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "toml"))
        .collect();
    files.sort();
    files
}

#[test]
fn every_file_in_tasks_is_a_valid_task_or_campaign() {
    let kinds: Vec<FileKind> = toml_files("tasks")
        .iter()
        .map(|file| check_file(file).unwrap_or_else(|e| panic!("{e}")))
        .collect();
    assert!(kinds.contains(&FileKind::Task));
    assert!(kinds.contains(&FileKind::Campaign));
    assert!(
        kinds
            .iter()
            .all(|k| matches!(k, FileKind::Task | FileKind::Campaign))
    );
}

#[test]
fn every_campaign_names_a_task_and_cell_that_load() {
    for file in toml_files("tasks") {
        if check_file(&file).ok() == Some(FileKind::Campaign) {
            let overrides = cablecell::campaign::run::Overrides::default();
            if let Err(e) = cablecell::campaign::run::Campaign::load(&file, overrides) {
                panic!("{e}");
            }
        }
    }
}

#[test]
fn every_cell_file_is_a_valid_cell() {
    let files = toml_files("config");
    assert!(!files.is_empty());
    for file in files {
        // The lab's cell needs two things only its lab has: a build with
        // the Panda driver, and the camera's pose from `calibrate-camera`.
        // Its refusal must say so, and nothing else.
        if file.ends_with("cell.lab.toml") {
            let error = check_file(&file)
                .expect_err("not yet calibrated")
                .to_string();
            assert!(
                error.contains("--features panda")
                    || error.contains("cablecell calibrate-camera --cell"),
                "{error}"
            );
            continue;
        }
        match check_file(&file) {
            Ok(kind) => assert_eq!(kind, FileKind::Cell, "{}", file.display()),
            Err(e) => panic!("{e}"),
        }
    }
}
