//! A campaign run as shards (`campaign FILE --shard K/N`) and merged
//! (`campaign merge DIR…`) gives the whole campaign's trials and summary;
//! shards that do not make one campaign are refused by folder and line.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use cablecell::campaign::journal::read;
use cablecell::campaign::trial::TrialEntry;

const CAMPAIGN: &str = "tasks/paper-regrasp-campaign.toml";

/// The summary table's rows that hold wall-clock figures: the only ones
/// that differ between two runs of one seed.
const WALL_CLOCK_ROWS: [&str; 1] = ["compute per trial ms"];

/// The JSON summary's wall-clock field, in each policy.
const WALL_CLOCK_FIELD: &str = "compute_time_per_trial_s";

fn cablecell(args: &[&str]) -> Output {
    common::cablecell(args)
}

fn succeeded(output: &Output) -> String {
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// `trials` trials of `seed` into `out`, as shard `shard` if given.
fn run(out: &Path, seed: &str, trials: &str, shard: Option<&str>, more: &[&str]) -> Output {
    let mut args = vec![
        "campaign",
        CAMPAIGN,
        "--trials",
        trials,
        "--seed",
        seed,
        "--out",
        common::text(out),
        "--threads",
        "1",
    ];
    if let Some(shard) = shard {
        args.extend(["--shard", shard]);
    }
    args.extend(more);
    cablecell(&args)
}

/// Runs the three shards of 5 trials of `seed` under `dir`, recorded.
fn three_shards(dir: &Path, seed: &str) -> [PathBuf; 3] {
    ["0/3", "1/3", "2/3"].map(|shard| {
        let out = dir.join(format!("seed{seed}-shard{}", &shard[..1]));
        succeeded(&run(&out, seed, "5", Some(shard), &[]));
        out
    })
}

/// The summary table printed, without its wall-clock rows and without the
/// lines after it that name folders.
fn table(stdout: &str) -> String {
    stdout
        .lines()
        .take_while(|l| !l.starts_with("trials recorded in") && !l.starts_with("merged "))
        .filter(|l| !WALL_CLOCK_ROWS.iter().any(|row| l.starts_with(row)))
        .map(|l| format!("{l}\n"))
        .collect()
}

fn json_without_wall_clock(stdout: &str) -> serde_json::Value {
    let mut summary: serde_json::Value = serde_json::from_str(stdout).expect("JSON");
    for policy in summary["policies"].as_array_mut().expect("policies") {
        let removed = policy
            .as_object_mut()
            .expect("a policy")
            .remove(WALL_CLOCK_FIELD);
        assert!(removed.is_some(), "{WALL_CLOCK_FIELD} is in the summary");
    }
    summary
}

/// A journal's entries, ordered, without their wall-clock time.
fn entries(out: &Path) -> Vec<TrialEntry> {
    let mut entries = read::<TrialEntry>(&out.join("trials.jsonl"))
        .expect("journal")
        .entries;
    entries.iter_mut().for_each(|e| e.compute_time_s = 0.0);
    entries.sort_by(|a, b| (a.trial, &a.policy).cmp(&(b.trial, &b.policy)));
    entries
}

#[test]
fn three_shards_merged_give_the_whole_campaign_s_summary() {
    let dir = tempfile::tempdir().expect("tempdir");
    let whole_out = dir.path().join("whole");
    let whole = succeeded(&run(&whole_out, "2", "5", None, &[]));
    let shards = three_shards(dir.path(), "2");
    // Trial i is shard i mod 3's: 0 and 3, 1 and 4, 2.
    for (shard, trials) in shards.iter().zip([[0, 3].as_slice(), &[1, 4], &[2]]) {
        let held: Vec<usize> = entries(shard).iter().map(|e| e.trial).collect();
        let expected: Vec<usize> = trials.iter().flat_map(|&t| [t, t]).collect();
        assert_eq!(held, expected, "{}", shard.display());
    }

    let merged_out = dir.path().join("merged");
    let mut args = vec!["campaign", "merge"];
    args.extend(shards.iter().map(|s| common::text(s)));
    args.extend(["--out", common::text(&merged_out)]);
    let merged = succeeded(&cablecell(&args));
    assert!(whole.contains(WALL_CLOCK_ROWS[0]), "{whole}");
    assert_eq!(table(&merged), table(&whole));
    assert!(table(&whole).lines().count() > 20, "{whole}");

    // The merged folder is the whole campaign's: the same trials, each
    // recording beside them, and resuming it runs nothing and summarises
    // the same.
    assert_eq!(entries(&merged_out), entries(&whole_out));
    for entry in entries(&merged_out) {
        let name = entry.recording.expect("recorded");
        assert!(merged_out.join("recordings").join(name).is_file());
    }
    let resumed = succeeded(&run(&merged_out, "2", "5", None, &["--resume", "--json"]));
    let whole_json = succeeded(&cablecell(&[
        "campaign",
        "merge",
        common::text(&whole_out),
        "--json",
    ]));
    assert_eq!(
        json_without_wall_clock(&resumed),
        json_without_wall_clock(&whole_json)
    );
    args.truncate(5);
    args.push("--json");
    let merged_json = succeeded(&cablecell(&args));
    assert_eq!(
        json_without_wall_clock(&merged_json),
        json_without_wall_clock(&whole_json)
    );
}

/// `campaign merge FOLDERS`: its exit status and error output.
fn merge(folders: &[&Path]) -> (Option<i32>, String) {
    let mut args = vec!["campaign", "merge"];
    args.extend(folders.iter().map(|f| common::text(f)));
    let output = cablecell(&args);
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

/// A copy of the shard folder `from` at `to`, its journal edited by `edit`.
fn copy_with_journal(from: &Path, to: &Path, edit: impl Fn(&str) -> String) -> PathBuf {
    std::fs::create_dir_all(to).expect("folder");
    for file in ["campaign.json", "trials.jsonl"] {
        std::fs::copy(from.join(file), to.join(file)).expect("copy");
    }
    let journal = std::fs::read_to_string(to.join("trials.jsonl")).expect("journal");
    std::fs::write(to.join("trials.jsonl"), edit(&journal)).expect("write");
    to.to_owned()
}

#[test]
fn shards_that_are_not_one_campaign_are_refused_by_folder_and_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let [s0, s1, s2] = three_shards(dir.path(), "2");
    let shown = |p: &Path| p.display().to_string();

    let (code, err) = merge(&[&s0, &s2]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("shard(s) 1 of 3 missing"), "{err}");

    let (code, err) = merge(&[&s0, &s1, &s1, &s2]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains(&format!("{}: shard 1/3 again", shown(&s1))),
        "{err}"
    );

    // A shard of another seed is another campaign's.
    let other = dir.path().join("seed3");
    succeeded(&run(&other, "3", "5", Some("1/3"), &["--no-record"]));
    let (code, err) = merge(&[&s0, &other, &s2]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "{}:1: seed is 3, but {} has 2",
            shown(&other.join("campaign.json")),
            shown(&s0.join("campaign.json"))
        )),
        "{err}"
    );

    // A trial recorded twice, named by its line and the first's.
    let twice = copy_with_journal(&s1, &dir.path().join("twice"), |j| {
        let first = j.lines().next().expect("a line");
        format!("{j}{first}\n")
    });
    let (code, err) = merge(&[&s0, &twice, &s2]);
    assert_eq!(code, Some(2), "{err}");
    let journal = shown(&twice.join("trials.jsonl"));
    assert!(
        err.contains(&format!(
            "{journal}:5: trial 1 of policy `paper` is already recorded at {journal}:1"
        )),
        "{err}"
    );

    // Another shard's trial in a shard's journal.
    let s0_first = std::fs::read_to_string(s0.join("trials.jsonl")).expect("journal");
    let s0_first = s0_first.lines().next().expect("a line").to_owned();
    let stray = copy_with_journal(&s1, &dir.path().join("stray"), |j| {
        format!("{j}{s0_first}\n")
    });
    let (code, err) = merge(&[&s0, &stray, &s2]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "{}:5: trial 0 belongs to shard 0/3",
            shown(&stray.join("trials.jsonl"))
        )),
        "{err}"
    );

    // A shard that did not finish: its last trial is missing.
    let short = copy_with_journal(&s1, &dir.path().join("short"), |j| {
        j.lines().take(3).map(|l| format!("{l}\n")).collect()
    });
    let (code, err) = merge(&[&s0, &short, &s2]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "{}: lacks trial 4 of policy `cablecell`",
            shown(&short.join("trials.jsonl"))
        )) && err.contains("--shard 1/3"),
        "{err}"
    );

    // A folder that is no campaign's.
    let (code, err) = merge(&[&s0, dir.path(), &s2]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("no campaign.json here"), "{err}");

    // A shard folder resumed as another shard.
    let resumed = run(&s1, "2", "5", Some("2/3"), &["--resume"]);
    let err = String::from_utf8_lossy(&resumed.stderr);
    assert_eq!(resumed.status.code(), Some(2), "{err}");
    assert!(err.contains("shard is 1/3, but this command"), "{err}");

    // --shard that is no K/N with K < N.
    for (bad, says) in [
        ("3/3", "K counts from 0 and must be below N"),
        ("1", "expected K/N"),
        ("a/3", "whole numbers"),
        ("0/0", "N must be 1 to 10000"),
    ] {
        let output = run(&dir.path().join("bad"), "2", "5", Some(bad), &[]);
        let err = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{bad}: {err}");
        assert!(err.contains(says), "{bad}: {err}");
    }
}
