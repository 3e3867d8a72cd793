//! `cablecell emulate` and `cablecell device` together, as an integrator
//! would try them: the emulator prints its port, the bring-up commands talk
//! to it.

mod common;

use std::io::{BufRead, BufReader};

use std::process::{Child, Output, Stdio};

/// An emulator process and the port it serves; killed when dropped.
struct Emulator {
    child: Child,
    port: String,
}

impl Emulator {
    fn start(device: &str) -> Self {
        let mut child = common::command()
            .args(["emulate", device])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("emulator starts");
        let stdout = child.stdout.take().expect("stdout");
        let mut port = String::new();
        BufReader::new(stdout)
            .read_line(&mut port)
            .expect("the port's path");
        let port = port.trim().to_owned();
        assert!(port.starts_with("/dev/pts/"), "{port}");
        Self { child, port }
    }

    fn device(&self, args: &[&str]) -> Output {
        let (kind, rest) = args.split_first().expect("device kind");
        common::command()
            .args(["device", kind, "--port", &self.port])
            .args(rest)
            .output()
            .expect("device command runs")
    }
}

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

#[test]
fn the_gripper_bring_up_commands_talk_to_the_emulated_pg70() {
    let emulator = Emulator::start("pg70");
    let refused = emulator.device(&["gripper", "move-pos", "20"]);
    assert_eq!(refused.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("not referenced"));
    let referenced = emulator.device(&["gripper", "reference"]);
    assert_eq!(
        referenced.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&referenced.stderr)
    );
    assert_eq!(stdout(&referenced).trim(), "referenced");
    assert_eq!(
        emulator
            .device(&["gripper", "move-pos", "20"])
            .status
            .code(),
        Some(0)
    );
    let state = emulator.device(&["gripper", "state"]);
    assert!(
        stdout(&state).contains("position 20.000 mm"),
        "{}",
        stdout(&state)
    );
    assert!(stdout(&state).contains("referenced"));
    // A speed and an acceleration go together in the MOVE_POS frame.
    let paced = emulator.device(&[
        "gripper", "move-pos", "30", "--speed", "40", "--accel", "200",
    ]);
    assert_eq!(
        paced.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&paced.stderr)
    );
    assert!(stdout(&emulator.device(&["gripper", "state"])).contains("position 30.000 mm"));
    let half = emulator.device(&["gripper", "move-pos", "30", "--speed", "40"]);
    assert_eq!(half.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&half.stderr).contains("--accel"));
    assert_eq!(
        stdout(&emulator.device(&["gripper", "grip", "1.0"])).trim(),
        "closed on nothing"
    );
}

#[test]
fn the_tactile_bring_up_commands_read_the_emulated_pad() {
    let emulator = Emulator::start("tactile");
    assert_eq!(stdout(&emulator.device(&["tactile", "id"])).trim(), "F001");
    assert_eq!(stdout(&emulator.device(&["tactile", "count"])).trim(), "25");
    let read = emulator.device(&["tactile", "read", "--samples", "60", "--json"]);
    assert_eq!(
        read.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&read.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&read.stdout).expect("JSON");
    common::assert_follows_schema("device-tactile-read", &report);
    assert_eq!(report["samples"], 60);
    assert!(report["rate_hz"].as_f64().expect("rate") > 0.0);
    // The emulated cable lies across the middle row: the bias-removed
    // map is near zero, the raw map is not.
    let dv = report["dv_v"].as_array().expect("Δv rows");
    assert!(
        dv.iter()
            .flat_map(|r| r.as_array().expect("row"))
            .all(|v| v.as_f64().expect("Δv").abs() < 0.2)
    );
    assert!(report["raw_v"][2][2].as_f64().expect("centre taxel") > 0.5);
}

#[test]
fn a_missing_port_is_named() {
    let out = common::command()
        .args(["device", "gripper", "--port", "/dev/no-such-port", "state"])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("/dev/no-such-port: cannot open the port")
    );
}

#[test]
fn numbers_no_gripper_takes_are_refused_before_anything_is_sent() {
    let emulator = Emulator::start("pg70");
    let before = stdout(&emulator.device(&["gripper", "state"]));
    for (args, message) in [
        (
            &["gripper", "move-pos", "nan"][..],
            "expected a value in [0, 68] mm, found NaN",
        ),
        (
            &["gripper", "move-pos", "69"],
            "expected a value in [0, 68] mm, found 69",
        ),
        (
            &[
                "gripper", "move-pos", "30", "--speed", "nan", "--accel", "200",
            ],
            "expected a value in [0.1, 1000] mm/s, found NaN",
        ),
        (
            &[
                "gripper", "move-pos", "30", "--speed", "40", "--accel", "inf",
            ],
            "expected a value in [1, 10000] mm/s², found inf",
        ),
        (
            &["gripper", "grip", "nan"],
            "expected a value in [0.1, 10] A, found NaN",
        ),
        (
            &["tactile", "read", "--samples", "4294967296"],
            "expected a value in [1, 10000] samples, found 4294967296",
        ),
    ] {
        let refused = emulator.device(args);
        let err = String::from_utf8_lossy(&refused.stderr);
        assert_eq!(refused.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
    }
    // The module heard nothing: still unreferenced, where it was.
    assert_eq!(stdout(&emulator.device(&["gripper", "state"])), before);
}
