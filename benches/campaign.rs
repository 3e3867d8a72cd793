//! Campaign throughput: the computation of one trial (the cell's motion
//! time is simulated, never slept), per policy, recorded to an MCAP file
//! or not, and a whole campaign on every core, both ways. Trials per
//! second = 1 / (time per trial).

use std::path::Path;

use cablecell::campaign::run::{Campaign, Overrides};
use cablecell::campaign::trial::run_trial;
use criterion::{Criterion, criterion_group, criterion_main};

fn campaign(trials: usize, out: &Path, record: bool) -> Campaign {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/paper-regrasp-campaign.toml");
    let overrides = Overrides {
        trials: Some(trials),
        seed: Some(1),
        out: Some(out.to_owned()),
        no_record: !record,
        shard: None,
    };
    Campaign::load(&path, overrides).unwrap_or_else(|e| panic!("{e}"))
}

fn one_trial(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("tempdir");
    let campaign = campaign(1, dir.path(), true);
    let recordings = campaign.recordings_folder();
    let mut group = c.benchmark_group("trial");
    for policy in &campaign.file.policies {
        for (name, folder) in [("", None), (" recorded", Some(recordings.as_path()))] {
            let mut index = 0;
            group.bench_function(format!("{}{name}", policy.name), |b| {
                b.iter(|| {
                    // A few hundred files, rewritten: the cost of creating
                    // each, not of a folder of millions.
                    index = (index + 1) % 256;
                    run_trial(
                        &campaign.task,
                        &campaign.cell,
                        policy,
                        &campaign.file.perturbation,
                        campaign.seed,
                        index,
                        folder,
                    )
                })
            });
        }
    }
    group.finish();
}

/// 1000 trials of each policy on every core, journal included, with and
/// without recordings.
fn thousand_trials(c: &mut Criterion) {
    let threads = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    let mut group = c.benchmark_group("campaign");
    group.sample_size(10);
    for (name, record) in [
        ("1000 trials x 2 policies", false),
        ("1000 trials x 2 policies recorded", true),
    ] {
        group.bench_function(name, |b| {
            b.iter_batched(
                || tempfile::tempdir().expect("tempdir"),
                |dir| {
                    let entries = campaign(1000, dir.path(), record)
                        .run(false, threads, |_| {})
                        .unwrap_or_else(|e| panic!("{e}"));
                    assert_eq!(entries.len(), 2000);
                },
                criterion::BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, one_trial, thousand_trials);
criterion_main!(benches);
