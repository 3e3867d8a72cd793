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

/// The shipped campaign's arguments for `trials` trials of `seed` into
/// `out`, unrecorded, then `more`.
fn unrecorded<'a>(trials: &'a str, seed: &'a str, out: &'a Path, more: &[&'a str]) -> Vec<&'a str> {
    let args = [
        CAMPAIGN,
        "--trials",
        trials,
        "--seed",
        seed,
        "--out",
        common::text(out),
        "--no-record",
    ];
    [&args[..], more].concat()
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
    common::assert_follows_schema("campaign", &summary);
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

/// The line (1-based) of the first line of `path` holding `needle`.
fn text_line(path: &Path, needle: &str) -> usize {
    std::fs::read_to_string(path)
        .expect("read")
        .lines()
        .position(|l| l.contains(needle))
        .expect("needle")
        + 1
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

    let (err, path, _dir) = refused("task = \"regrasp.toml\"", "task = \"missing.toml\"");
    let line = text_line(&path, "missing.toml");
    assert!(
        err.contains(&format!(
            "{}:{line}:1: campaign.task: {}: cannot read the file",
            path.display(),
            path.with_file_name("missing.toml").display()
        )),
        "{err}"
    );
    let check = common::cablecell(&["check", common::text(&path)]);
    assert_eq!(check.status.code(), Some(2));
    assert_eq!(String::from_utf8_lossy(&check.stderr), err);

    let (err, _, _dir) = refused("start_angle_max_rad = 0.7", "start_angle_max_rad = 1e308");
    assert!(
        err.contains("perturbation.start_angle_max_rad: expected a value in [0, 1.5707963267948966] rad, found 1e308"),
        "{err}"
    );
    let (err, _, _dir) = refused(
        "cable_diameter_mm = [2.5, 2.5]",
        "cable_diameter_mm = [0.0, 2.5]",
    );
    assert!(
        err.contains("perturbation.cable_diameter_mm: expected [low, high] with 0.1 ≤ low ≤ high ≤ 20 mm, found [0, 2.5]"),
        "{err}"
    );
    let (err, _, _dir) = refused("trials = 20", "trials = 4294967296");
    assert!(
        err.contains("campaign.trials: expected a value in [1, 10000] trials, found 4294967296"),
        "{err}"
    );
    let (err, _, _dir) = refused(
        "correction_gain = { n = 1.2,",
        "correction_gain = { n = nan,",
    );
    assert!(
        err.contains("policy[1].correction_gain.n: expected a value in [0, 2], found NaN"),
        "{err}"
    );

    let (err, _, _dir) = refused("start_offset_max_mm = 10.0", "start_offset_max_mm = -5.0");
    assert!(
        err.contains("perturbation.start_offset_max_mm: expected a value in [0, 50] mm, found -5"),
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

#[test]
fn a_summary_read_back_from_the_journal_equals_the_live_one() {
    // Seed 1, 4 trials: before serde_json parsed floats exactly, six of the
    // summary's figures read back differed in their last digit.
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("s");
    let live = campaign(&unrecorded("4", "1", &out, &["--json"]));
    assert_eq!(live.status.code(), Some(0));
    // Resuming a finished campaign runs nothing: its summary is read back.
    let read_back = campaign(&unrecorded("4", "1", &out, &["--json", "--resume"]));
    assert_eq!(read_back.status.code(), Some(0));
    assert_eq!(
        String::from_utf8_lossy(&read_back.stdout),
        String::from_utf8_lossy(&live.stdout)
    );
}

/// Resumes a campaign of `trials` trials, seed 3, whose journal is `edit`
/// of `journal`, and returns the exit status and error output.
fn resumed_with(journal: &str, edit: impl Fn(&str) -> String, trials: &str) -> (i32, String) {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("r");
    std::fs::create_dir_all(&out).expect("folder");
    std::fs::write(out.join("trials.jsonl"), edit(journal)).expect("write");
    let result = campaign(&unrecorded(trials, "3", &out, &["--resume"]));
    (
        result.status.code().expect("exit status"),
        String::from_utf8_lossy(&result.stderr).into_owned(),
    )
}

#[test]
fn a_resumed_journal_that_is_not_the_campaign_s_is_refused_at_its_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("c");
    assert_eq!(
        campaign(&unrecorded("2", "3", &out, &[])).status.code(),
        Some(0)
    );
    let journal = std::fs::read_to_string(out.join("trials.jsonl")).expect("journal");
    let lines: Vec<&str> = journal.lines().collect();
    assert_eq!(lines.len(), 4);

    // A line written twice: the journal itself is damaged.
    let (code, err) = resumed_with(&journal, |j| format!("{j}{}\n", lines[1]), "2");
    assert_eq!(code, 4, "{err}");
    assert!(
        err.contains("trials.jsonl:5: not a valid journal entry: trial")
            && err.contains("is already recorded on line 2"),
        "{err}"
    );
    // A trial beyond the campaign's, and a policy its file lacks: the
    // journal is another campaign's.
    let (code, err) = resumed_with(&journal, str::to_owned, "1");
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("is beyond the campaign's 1 trials: resume with --trials 2 or more"),
        "{err}"
    );
    let (code, err) = resumed_with(
        &journal,
        |j| j.replacen("\"policy\":\"cablecell\"", "\"policy\":\"magic\"", 1),
        "2",
    );
    assert_eq!(code, 2, "{err}");
    let line = lines
        .iter()
        .position(|l| l.contains("\"policy\":\"cablecell\""))
        .expect("a cablecell trial")
        + 1;
    assert!(
        err.contains(&format!(
            "trials.jsonl:{line}: policy `magic` is not one of the campaign file's (paper, cablecell)"
        )),
        "{err}"
    );
}

#[test]
fn a_journal_that_is_no_regular_file_is_refused_unread() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("c");
    std::fs::create_dir_all(&out).expect("folder");
    let journal = out.join("trials.jsonl");
    std::os::unix::fs::symlink("/dev/zero", &journal).expect("link");
    for resume in [&["--resume"][..], &[]] {
        let result = campaign(&unrecorded("1", "1", &out, resume));
        assert_eq!(result.status.code(), Some(4));
        assert!(
            String::from_utf8_lossy(&result.stderr)
                .contains("trials.jsonl: not a regular file, so not a journal"),
            "{}",
            String::from_utf8_lossy(&result.stderr)
        );
    }
    std::fs::remove_file(&journal).expect("unlink");
    std::fs::create_dir(&journal).expect("a folder in its place");
    for resume in [&["--resume"][..], &[]] {
        let result = campaign(&unrecorded("1", "1", &out, resume));
        assert_eq!(result.status.code(), Some(4));
        let err = String::from_utf8_lossy(&result.stderr);
        assert!(err.contains("not a regular file"), "{err}");
        assert!(!err.contains("already holds trials"), "{err}");
    }
}

/// The occlusion campaign, `trials` per policy, as JSON without the wall
/// clock's figures.
fn occlusion_summary(out: &Path, threads: &str) -> serde_json::Value {
    let output = campaign(&[
        "tasks/occluded-camera-campaign.toml",
        "--trials",
        "1",
        "--threads",
        threads,
        "--no-record",
        "--json",
        "--out",
        common::text(out),
    ]);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let mut summary: serde_json::Value = serde_json::from_slice(&output.stdout).expect("JSON");
    for policy in summary["policies"].as_array_mut().expect("policies") {
        policy
            .as_object_mut()
            .expect("a policy")
            .remove("compute_time_per_trial_s");
    }
    summary
}

#[test]
fn the_occlusion_campaign_is_reproducible_for_a_seed_and_compares_the_senses() {
    let dir = tempfile::tempdir().expect("tempdir");
    let one = occlusion_summary(&dir.path().join("one"), "1");
    let two = occlusion_summary(&dir.path().join("two"), "2");
    assert_eq!(
        one, two,
        "the same seed gives the same summary on any thread count"
    );
    let policy = |name: &str| {
        one["policies"]
            .as_array()
            .expect("policies")
            .iter()
            .find(|p| p["policy"] == name)
            .unwrap_or_else(|| panic!("policy {name}"))
            .clone()
    };
    // With the cable wholly hidden the camera alone finds no cable, touch
    // searches, and both fall back to the search.
    assert_eq!(policy("vision 100 %")["success"]["successes"], 0);
    assert_eq!(policy("touch 100 %")["success"]["successes"], 1);
    assert_eq!(policy("both 100 %")["success"]["successes"], 1);
    assert!(policy("both 100 %")["search_moves_per_trial"]["mean"].as_f64() >= Some(1.0));
    // With the camera seeing, the fused shape lies on the pad nearer the
    // true cable than the vision shape does.
    let shapes = &policy("both 30 %")["shape_errors"];
    let pad = |shape: &str| {
        shapes[shape]["grasped_mm"]["mean"]
            .as_f64()
            .expect("a mean")
    };
    assert!(pad("fused") < pad("vision"), "{shapes}");
}
