//! A campaign's summary: error statistics at every grasp, success rates,
//! regrasps and time per trial, per policy.

use serde::Serialize;

use super::stats::{Rate, Summary};
use super::trial::{TrialEntry, TrialOutcome};
use crate::geometry::PoseError;

#[derive(Debug, Clone, Serialize)]
pub struct CampaignSummary {
    pub name: String,
    pub seed: u64,
    pub trials: usize,
    pub policies: Vec<PolicySummary>,
}

#[derive(Debug, Clone, Serialize)]
pub struct PolicySummary {
    pub policy: String,
    pub trials: usize,
    /// True error after the trial grasp, after each regrasp, and at the end.
    pub stages: Vec<StageSummary>,
    /// The tactile estimate against the true pose, over every grasp.
    pub estimator: StageSummary,
    pub success: Option<Rate>,
    pub faults: usize,
    pub regrasps_per_trial: Option<Summary>,
    /// Duration of a trial on the cell's clock (simulated time).
    pub cell_time_per_trial_s: Option<Summary>,
    /// Computation per trial (wall clock, not reproducible).
    pub compute_time_per_trial_s: Option<Summary>,
}

/// |n| and |α| over the trials that reached a stage.
#[derive(Debug, Clone, Serialize)]
pub struct StageSummary {
    pub stage: String,
    pub n_mm: Option<Summary>,
    pub alpha_rad: Option<Summary>,
}

impl StageSummary {
    fn of<'a>(stage: String, errors: impl Iterator<Item = &'a PoseError>) -> Self {
        let (n, alpha): (Vec<f64>, Vec<f64>) =
            errors.map(|e| (e.n_mm.abs(), e.alpha_rad.abs())).unzip();
        Self {
            stage,
            n_mm: Summary::of(&n),
            alpha_rad: Summary::of(&alpha),
        }
    }
}

/// Summarises `entries` (any order) per policy, in the order given.
pub fn summarise(
    name: &str,
    seed: u64,
    trials: usize,
    policies: &[String],
    entries: &[TrialEntry],
) -> CampaignSummary {
    let policies = policies
        .iter()
        .map(|policy| {
            let mine: Vec<&TrialEntry> = entries.iter().filter(|e| &e.policy == policy).collect();
            policy_summary(policy, &mine)
        })
        .collect();
    CampaignSummary {
        name: name.to_owned(),
        seed,
        trials,
        policies,
    }
}

fn policy_summary(policy: &str, entries: &[&TrialEntry]) -> PolicySummary {
    let most_grasps = entries.iter().map(|e| e.grasps.len()).max().unwrap_or(0);
    let mut stages: Vec<StageSummary> = (0..most_grasps)
        .map(|k| {
            let stage = if k == 0 {
                "trial grasp".to_owned()
            } else {
                format!("regrasp {k}")
            };
            StageSummary::of(
                stage,
                entries
                    .iter()
                    .filter_map(|e| e.grasps.get(k)?.error.as_ref()),
            )
        })
        .collect();
    stages.push(StageSummary::of(
        "final".to_owned(),
        entries
            .iter()
            .filter_map(|e| e.grasps.last()?.error.as_ref()),
    ));
    let estimator = StageSummary::of(
        "estimator".to_owned(),
        entries
            .iter()
            .flat_map(|e| e.grasps.iter().filter_map(|g| g.estimate_error.as_ref())),
    );
    let successes = entries
        .iter()
        .filter(|e| e.outcome == TrialOutcome::Success)
        .count();
    let regrasps: Vec<f64> = entries
        .iter()
        .map(|e| e.grasps.len().saturating_sub(1) as f64)
        .collect();
    let cell_time: Vec<f64> = entries.iter().map(|e| e.cell_time_s).collect();
    let compute_time: Vec<f64> = entries.iter().map(|e| e.compute_time_s).collect();
    PolicySummary {
        policy: policy.to_owned(),
        trials: entries.len(),
        stages,
        estimator,
        success: Rate::wilson(successes, entries.len()),
        faults: entries
            .iter()
            .filter(|e| e.outcome == TrialOutcome::Fault)
            .count(),
        regrasps_per_trial: Summary::of(&regrasps),
        cell_time_per_trial_s: Summary::of(&cell_time),
        compute_time_per_trial_s: Summary::of(&compute_time),
    }
}

/// The summary as a table, the policies side by side.
pub fn render_table(summary: &CampaignSummary) -> String {
    const LABEL: usize = 24;
    const CELL: usize = 40;
    let mut out = format!(
        "campaign {}: {} trials per policy, seed {}\n{:LABEL$}",
        summary.name, summary.trials, summary.seed, ""
    );
    for policy in &summary.policies {
        out += &format!(
            "{:<CELL$}",
            format!("{} ({} trials)", policy.policy, policy.trials)
        );
    }
    out += &format!("\n{:LABEL$}", "");
    for _ in &summary.policies {
        out += &format!("{:<CELL$}", "mean ± sd   (median, p95, max)");
    }
    out.push('\n');
    let mut row = |label: String, cell: &dyn Fn(&PolicySummary) -> String| {
        out += &format!("{label:<LABEL$}");
        for policy in &summary.policies {
            out += &format!("{:<CELL$}", cell(policy));
        }
        out.push('\n');
    };
    let stage_names: Vec<String> = summary
        .policies
        .iter()
        .max_by_key(|p| p.stages.len())
        .map(|p| p.stages.iter().map(|s| s.stage.clone()).collect())
        .unwrap_or_default();
    let find = |policy: &PolicySummary, name: &str| -> Option<StageSummary> {
        if name == "estimator" {
            Some(policy.estimator.clone())
        } else {
            policy.stages.iter().find(|s| s.stage == name).cloned()
        }
    };
    for name in stage_names.iter().map(String::as_str).chain(["estimator"]) {
        row(format!("{name} |n| mm"), &|p| {
            cell(find(p, name).and_then(|s| s.n_mm), 1.0, 3)
        });
        row(format!("{name} |α| rad"), &|p| {
            cell(find(p, name).and_then(|s| s.alpha_rad), 1.0, 4)
        });
    }
    row("success".into(), &|p| match &p.success {
        Some(r) => format!(
            "{}/{} = {:.0} % [{:.0}, {:.0}] (95 % CI)",
            r.successes,
            r.trials,
            100.0 * r.rate,
            100.0 * r.ci95_low,
            100.0 * r.ci95_high
        ),
        None => "—".into(),
    });
    row("faults".into(), &|p| p.faults.to_string());
    row("regrasps per trial".into(), &|p| {
        cell(p.regrasps_per_trial, 1.0, 2)
    });
    row("cell time per trial s".into(), &|p| {
        cell(p.cell_time_per_trial_s, 1.0, 2)
    });
    row("compute per trial ms".into(), &|p| {
        cell(p.compute_time_per_trial_s, 1e3, 2)
    });
    out
}

fn cell(summary: Option<Summary>, scale: f64, digits: usize) -> String {
    match summary {
        Some(s) => format!(
            "{:.d$} ± {:.d$} ({:.d$}, {:.d$}, {:.d$})",
            s.mean * scale,
            s.std_dev * scale,
            s.median * scale,
            s.p95 * scale,
            s.max * scale,
            d = digits
        ),
        None => "—".into(),
    }
}
