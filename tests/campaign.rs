//! Campaigns through the `cablecell campaign` command: reproducible for a
//! seed whatever the thread count, resumable after a kill without losing
//! or repeating a trial, and clear about bad input.

mod common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use cablecell::campaign::journal::read;
use cablecell::campaign::trial::TrialEntry;

const CAMPAIGN: &str = "tasks/paper-regrasp-campaign.toml";

fn command(args: &[&str]) -> Command {
    let mut command = common::command();
    command.arg("campaign").args(args);
    command
}

fn campaign(args: &[&str]) -> Output {
    command(args).output().expect("cablecell runs")
}

/// The journal's entries, ordered, without the wall-clock time (the one
/// field that is not reproducible).
fn entries(out: &Path) -> Vec<TrialEntry> {
    let recovered = read::<TrialEntry>(&out.join("trials.jsonl")).expect("journal");
    let mut entries: Vec<TrialEntry> = recovered
        .entries
        .into_iter()
        .map(|mut e| {
            e.compute_time_s = 0.0;
            e
        })
        .collect();
    entries.sort_by(|a, b| (a.trial, &a.policy).cmp(&(b.trial, &b.policy)));
    entries
}

#[test]
fn a_seed_gives_the_same_trials_on_one_thread_or_two() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    for (out, threads) in [(&one, "1"), (&two, "2")] {
        let status = campaign(&[
            CAMPAIGN,
            "--trials",
            "12",
            "--seed",
            "5",
            "--out",
            common::text(out),
            "--threads",
            threads,
        ]);
        assert_eq!(
            status.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&status.stderr)
        );
    }
    let (a, b) = (entries(&one), entries(&two));
    assert_eq!(a.len(), 24, "12 trials × 2 policies");
    assert_eq!(a, b);
    // Both policies meet identical trials.
    for pair in a.chunks(2) {
        assert_eq!(pair[0].seed, pair[1].seed);
        assert_eq!(pair[0].perturbation, pair[1].perturbation);
    }
}

#[test]
fn a_killed_campaign_resumes_without_losing_or_repeating_a_trial() {
    const TRIALS: usize = 1500;
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("killed");
    let journal = out.join("trials.jsonl");
    let trials = TRIALS.to_string();
    let args = [
        CAMPAIGN,
        "--trials",
        &trials,
        "--seed",
        "9",
        "--out",
        common::text(&out),
    ];
    let mut child = command(&args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    // Kill it once some trials are recorded.
    let started = Instant::now();
    loop {
        let lines = std::fs::read(&journal)
            .map_or(0, |bytes| bytes.iter().filter(|&&b| b == b'\n').count());
        if lines >= 50 || started.elapsed() > Duration::from_secs(60) {
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().expect("kill");
    child.wait().expect("reap");
    let at_kill = entries(&out).len();
    assert!(
        at_kill >= 50,
        "the campaign recorded trials before the kill"
    );
    assert!(
        at_kill < 2 * TRIALS,
        "the kill came too late to test resuming: raise TRIALS"
    );

    let resumed = campaign(&[&args[..], &["--resume"]].concat());
    assert_eq!(
        resumed.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    let after = entries(&out);
    let keys: BTreeSet<(usize, String)> =
        after.iter().map(|e| (e.trial, e.policy.clone())).collect();
    assert_eq!(keys.len(), after.len(), "no trial is recorded twice");
    assert_eq!(after.len(), 2 * TRIALS, "every trial is recorded");

    // The same as a campaign that was never interrupted.
    let whole = dir.path().join("whole");
    let args = [
        CAMPAIGN,
        "--trials",
        &trials,
        "--seed",
        "9",
        "--out",
        common::text(&whole),
    ];
    assert_eq!(campaign(&args).status.code(), Some(0));
    assert_eq!(after, entries(&whole));
}

#[test]
fn an_existing_campaign_is_not_overwritten_and_a_seed_change_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("c");
    let args = [
        CAMPAIGN,
        "--trials",
        "2",
        "--seed",
        "3",
        "--out",
        common::text(&out),
    ];
    assert_eq!(campaign(&args).status.code(), Some(0));
    let again = campaign(&args);
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("already holds trials"));
    let other_seed = campaign(&[
        CAMPAIGN,
        "--trials",
        "2",
        "--seed",
        "4",
        "--out",
        common::text(&out),
        "--resume",
    ]);
    assert_eq!(other_seed.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&other_seed.stderr).contains("run with seed 3, not 4"));
    // Resuming a finished campaign runs nothing and keeps every trial.
    let before = entries(&out);
    assert_eq!(
        campaign(&[&args[..], &["--resume"]].concat()).status.code(),
        Some(0)
    );
    assert_eq!(entries(&out), before);
}

#[test]
fn the_json_summary_has_every_stage_and_rate() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = campaign(&[
        CAMPAIGN,
        "--trials",
        "8",
        "--out",
        common::text(&dir.path().join("j")),
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(summary["trials"], 8);
    let paper = &summary["policies"][0];
    assert_eq!(paper["policy"], "paper");
    assert_eq!(paper["trials"], 8);
    assert_eq!(paper["stages"][0]["stage"], "trial grasp");
    for key in ["mean", "std_dev", "median", "p95", "max"] {
        assert!(paper["stages"][0]["n_mm"][key].as_f64().is_some(), "{key}");
    }
    let rate = &paper["success"];
    assert!(rate["ci95_low"].as_f64() <= rate["rate"].as_f64());
    assert!(rate["rate"].as_f64() <= rate["ci95_high"].as_f64());
    assert!(paper["regrasps_per_trial"]["mean"].as_f64().is_some());
    assert!(
        paper["cell_time_per_trial_s"]["mean"]
            .as_f64()
            .expect("time")
            > 1.0
    );
}

/// Writes the shipped campaign with `from` replaced by `to` into `dir`,
/// its task and cell named by absolute paths, and returns its path.
fn edited_campaign(dir: &Path, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(common::root().join(CAMPAIGN)).expect("campaign");
    assert!(text.contains(from), "{from:?}");
    let absolute = |relative: &str| format!("{:?}", common::root().join(relative));
    let text = text
        .replacen(from, to, 1)
        .replace("\"regrasp.toml\"", &absolute("tasks/regrasp.toml"))
        .replace(
            "\"../config/cell.sim.toml\"",
            &absolute("config/cell.sim.toml"),
        );
    let path = dir.join("campaign.toml");
    std::fs::write(&path, text).expect("write");
    path
}

fn refused(from: &str, to: &str) -> (String, PathBuf, tempfile::TempDir) {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = edited_campaign(dir.path(), from, to);
    let out = campaign(&[common::text(&path)]);
    assert_eq!(out.status.code(), Some(2));
    (String::from_utf8_lossy(&out.stderr).into_owned(), path, dir)
}

#[test]
fn a_bad_campaign_file_says_what_and_where() {
    let (err, path, _dir) = refused("estimator = \"centroids\"", "estimator = \"magic\"");
    let text = std::fs::read_to_string(&path).expect("read");
    let line = text
        .lines()
        .position(|l| l.contains("magic"))
        .expect("edited line")
        + 1;
    let expected = format!(
        "{}:{line}:13: policy[0].estimator: unknown variant `magic`",
        path.display()
    );
    assert!(err.contains(&expected), "{err}");

    let (err, _, _dir) = refused("name = \"cablecell\"", "name = \"paper\"");
    assert!(err.contains("policy name `paper` is used twice"), "{err}");

    let (err, _, _dir) = refused("task = \"regrasp.toml\"", "task = \"missing.toml\"");
    assert!(err.contains("missing.toml: cannot read the file"), "{err}");

    let (err, _, _dir) = refused("start_offset_max_mm = 10.0", "start_offset_max_mm = -5.0");
    assert!(
        err.contains("perturbation.start_offset_max_mm: expected a number ≥ 0, found -5"),
        "{err}"
    );
}

#[test]
fn a_trial_that_faults_is_recorded_and_the_campaign_goes_on() {
    let dir = tempfile::tempdir().expect("tempdir");
    // A cell whose tactile sensor falls silent during the first evaluation.
    let cell = common::sim_cell_copy(dir.path(), |cell| {
        cell.replace(
            "noise_fraction = 0.02",
            "noise_fraction = 0.02\nsilent_after_frames = 55",
        )
    });
    assert!(
        std::fs::read_to_string(cell)
            .expect("cell")
            .contains("silent_after_frames = 55")
    );
    let campaign = edited_campaign(dir.path(), "\"../config/cell.sim.toml\"", "\"cell.toml\"");
    let out = dir.path().join("out");
    let status = command(&[
        common::text(&campaign),
        "--trials",
        "3",
        "--out",
        common::text(&out),
    ])
    .output()
    .expect("runs");
    assert_eq!(
        status.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let entries = entries(&out);
    assert_eq!(entries.len(), 6);
    for entry in &entries {
        assert_eq!(
            entry.outcome,
            cablecell::campaign::trial::TrialOutcome::Fault
        );
        assert!(
            entry
                .detail
                .as_deref()
                .is_some_and(|d| d.contains("no answer")),
            "{entry:?}"
        );
        // What came before the fault is kept.
        assert!(entry.states.iter().any(|(state, _)| state == "trial_grasp"));
    }
    let table = String::from_utf8_lossy(&status.stdout);
    assert!(table.contains("faults                  3"), "{table}");
}
