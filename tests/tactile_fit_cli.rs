//! `cablecell tactile-fit` on maps given on standard input or in a file.

mod common;

use std::io::Write;
use std::process::{Output, Stdio};

fn tactile_fit(args: &[&str], stdin: &str) -> Output {
    let mut child = common::command()
        .arg("tactile-fit")
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("cablecell starts");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(stdin.as_bytes())
        .expect("write map");
    child.wait_with_output().expect("cablecell ends")
}

/// A map with `value` on the taxels where `hot(row, col)`, 0 elsewhere,
/// written as five lines of five numbers.
fn map(hot: impl Fn(usize, usize) -> bool, value: f64) -> String {
    (0..5)
        .map(|i| {
            (0..5)
                .map(|j| {
                    if hot(i, j) {
                        value.to_string()
                    } else {
                        "0".into()
                    }
                })
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn a_cable_across_the_middle_row_is_horizontal_through_the_centre() {
    let out = tactile_fit(&[], &map(|i, _| i == 2, 0.8));
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let fit: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    common::assert_follows_schema("tactile-fit", &fit);
    assert_eq!(fit["direction"], "horizontal");
    assert_eq!(fit["centroids"].as_array().map(Vec::len), Some(5));
    assert!(fit["line"]["alpha_rad"].as_f64().expect("alpha").abs() < 1e-9);
    assert!(fit["line"]["n_mm"].as_f64().expect("offset").abs() < 1e-9);
    assert!(fit["slope_m"].as_f64().expect("m").abs() < 1e-9);
    assert!(fit["quadratic"]["a_per_mm"].as_f64().expect("a").abs() < 1e-9);
}

#[test]
fn a_cable_down_the_last_column_is_vertical_and_finite() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("map.json");
    let values: Vec<f64> = (0..25)
        .map(|k| if k % 5 == 4 { 0.5 } else { 0.0 })
        .collect();
    std::fs::write(&path, serde_json::to_string(&values).expect("json")).expect("write");
    let out = tactile_fit(&[path.to_str().expect("utf-8")], "");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let fit: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(fit["direction"], "vertical");
    let alpha = fit["line"]["alpha_rad"].as_f64().expect("alpha");
    assert!(
        (alpha - std::f64::consts::FRAC_PI_2).abs() < 1e-9,
        "{alpha}"
    );
    // x = +2 pitches; the normal of a line at +π/2 is -x.
    let offset = fit["line"]["n_mm"].as_f64().expect("offset");
    assert!((offset + 7.1).abs() < 1e-9, "{offset}");
    assert!(fit["slope_m"].is_null(), "no slope for a vertical cable");
}

#[test]
fn a_bad_number_is_named_with_its_place() {
    let out = tactile_fit(&["--pitch-mm", "3.55"], "0 0 0 0 0\n0 0 x 0 0\n");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("<stdin>: line 2, column 5: `x`"), "{err}");
}

#[test]
fn a_short_map_says_how_many_numbers_it_found() {
    let out = tactile_fit(&[], "1 2 3");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains('3') && err.contains("25"), "{err}");
}

#[test]
fn an_empty_pad_is_no_contact() {
    let out = tactile_fit(&[], &map(|_, _| false, 0.0));
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.to_lowercase().contains("contact"), "{err}");
}

#[test]
fn a_nonsense_pitch_is_bad_input() {
    let out = tactile_fit(&["--pitch-mm", "0"], &map(|i, _| i == 2, 0.8));
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("pitch"));
}
