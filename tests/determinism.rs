//! One seed, one run: `run --json` reports and recordings of the simulated
//! cell are the same, run after run, apart from the fields declared to
//! hold wall-clock time. Recordings are compared message by message on
//! every channel they hold, whatever channels there are.

mod common;

use std::collections::BTreeMap;
use std::path::Path;

use cablecell::recording::Recording;
use serde_json::Value;

/// Fields that may hold wall-clock time, wherever they appear: in reports,
/// journals, summaries and recorded messages (JSON objects at any depth),
/// and `log_time` for an MCAP message's log time. docs/testing.md lists
/// them. `timestamp` and `log_time` are the cell's clock today; recordings
/// dated on the wall clock (start + the cell's clock) only shift them,
/// and `/state`'s `t_s` keeps the cell's clock compared.
const WALL_CLOCK_FIELDS: [&str; 4] = [
    "compute_time_s",
    "compute_time_per_trial_s",
    "timestamp",
    "log_time",
];

/// `value` without the wall-clock fields; whether it held any.
fn without_wall_clock(value: &mut Value) -> bool {
    match value {
        Value::Object(map) => {
            let before = map.len();
            map.retain(|key, _| !WALL_CLOCK_FIELDS.contains(&key.as_str()));
            let mut removed = map.len() != before;
            for inner in map.values_mut() {
                removed |= without_wall_clock(inner);
            }
            removed
        }
        Value::Array(items) => items
            .iter_mut()
            .fold(false, |removed, item| without_wall_clock(item) | removed),
        _ => false,
    }
}

/// A recorded message as compared: its JSON without the wall-clock fields
/// and, unless declared, its log time; a message that is no JSON
/// (a binary encoding) by its channel and order alone.
fn comparable(log_time_ns: u64, data: &[u8]) -> Value {
    let mut message = match serde_json::from_slice::<Value>(data) {
        Ok(value) => serde_json::json!({ "data": value }),
        Err(_) => serde_json::json!({ "data": "not JSON" }),
    };
    message["log_time"] = log_time_ns.into();
    without_wall_clock(&mut message);
    message
}

/// Each channel's messages in order, comparable.
fn channels(path: &Path) -> BTreeMap<String, Vec<Value>> {
    let recording = Recording::read(path).expect("a recording");
    assert!(recording.truncated.is_none(), "{:?}", recording.truncated);
    let mut channels: BTreeMap<String, Vec<Value>> = BTreeMap::new();
    for message in &recording.messages {
        channels
            .entry(message.topic.clone())
            .or_default()
            .push(comparable(message.log_time_ns, &message.data));
    }
    channels
}

/// `run TASK --seed SEED --json`, recorded to `recording`: its report.
fn run(task: &str, seed: &str, recording: &Path) -> Vec<u8> {
    let output = common::cablecell(&[
        "run",
        task,
        "--seed",
        seed,
        "--json",
        "--record",
        common::text(recording),
    ]);
    assert!(
        matches!(output.status.code(), Some(0 | 1)),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    output.stdout
}

fn assert_reproducible(task: &str, seed: &str) {
    let dir = tempfile::tempdir().expect("tempdir");
    let (first, second) = (dir.path().join("1.mcap"), dir.path().join("2.mcap"));
    let reports = [run(task, seed, &first), run(task, seed, &second)];
    let mut parsed = reports
        .clone()
        .map(|report| serde_json::from_slice::<Value>(&report).expect("a JSON report"));
    let held_wall_clock = parsed
        .iter_mut()
        .fold(false, |held, report| without_wall_clock(report) | held);
    assert_eq!(parsed[0], parsed[1], "{task} seed {seed}: the reports");
    if !held_wall_clock {
        assert_eq!(
            reports[0], reports[1],
            "byte for byte, with no wall clock in them"
        );
    }

    let (first, second) = (channels(&first), channels(&second));
    assert!(first.len() >= 8, "{:?}", first.keys());
    assert_eq!(
        first.keys().collect::<Vec<_>>(),
        second.keys().collect::<Vec<_>>()
    );
    for (channel, messages) in &first {
        let again = &second[channel];
        assert_eq!(messages.len(), again.len(), "{channel}: message count");
        for (k, (a, b)) in messages.iter().zip(again).enumerate() {
            assert_eq!(a, b, "{task} seed {seed}: {channel} message {k}");
        }
    }
}

#[test]
fn a_seed_gives_the_same_report_and_recording_every_time() {
    assert_reproducible("tasks/regrasp.toml", "3");
    assert_reproducible("tasks/regrasp.toml", "7");
}

#[test]
fn wall_clock_fields_are_removed_at_any_depth_and_nothing_else() {
    let mut value = serde_json::json!({
        "t_s": 1.5,
        "timestamp": { "sec": 1, "nsec": 2 },
        "grasps": [{ "compute_time_s": 0.1, "n_mm": 0.2 }],
    });
    assert!(without_wall_clock(&mut value));
    assert_eq!(
        value,
        serde_json::json!({ "t_s": 1.5, "grasps": [{ "n_mm": 0.2 }] })
    );
    assert!(!without_wall_clock(&mut value));
}
