//! A campaign's summary: error statistics at every grasp, success rates,
//! regrasps and time per trial, per policy.

use schemars::JsonSchema;
use serde::Serialize;

use super::stats::{Rate, Summary};
use super::trial::{TrialEntry, TrialOutcome};
use crate::geometry::PoseError;
use crate::perception::shape::{Distances, StretchErrors};
use crate::record::ShapeErrors;

#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct CampaignSummary {
    pub name: String,
    pub seed: u64,
    pub trials: usize,
    pub policies: Vec<PolicySummary>,
}

#[derive(Debug, Clone, Serialize, JsonSchema)]
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
    /// Grasps a search by touch made per trial, over the trials that
    /// searched; left out of the JSON when none did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub search_moves_per_trial: Option<Summary>,
    /// How far each shape of the cable lay from the true one at the first
    /// grasp that held it; left out of the JSON when no trial measured it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shape_errors: Option<ShapeErrorSummary>,
    /// Duration of a trial on the cell's clock (simulated time).
    pub cell_time_per_trial_s: Option<Summary>,
    /// Computation per trial (wall clock, not reproducible).
    pub compute_time_per_trial_s: Option<Summary>,
}

/// The mean distance of each shape of the cable from the true one, over
/// the grasped stretch (the pad) and beyond it, across trials.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct ShapeErrorSummary {
    /// The length measured beyond each end of the pad.
    pub beyond_mm: f64,
    pub vision: StretchSummary,
    pub tactile_quadratic: StretchSummary,
    pub fused: StretchSummary,
}

/// A shape's mean distance from the true cable, in mm, over the trials
/// that had it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct StretchSummary {
    pub grasped_mm: Option<Summary>,
    pub beyond_mm: Option<Summary>,
}

impl ShapeErrorSummary {
    fn of(trials: &[&ShapeErrors]) -> Option<Self> {
        let first = trials.first()?;
        let stretch = |shape: fn(&ShapeErrors) -> Option<StretchErrors>| {
            let means = |part: fn(&StretchErrors) -> Option<Distances>| -> Vec<f64> {
                trials
                    .iter()
                    .filter_map(|t| part(&shape(t)?))
                    .map(|d| d.mean_mm)
                    .collect()
            };
            StretchSummary {
                grasped_mm: Summary::of(&means(|s| s.grasped)),
                beyond_mm: Summary::of(&means(|s| s.beyond)),
            }
        };
        Some(Self {
            beyond_mm: first.beyond_mm,
            vision: stretch(|t| t.vision),
            tactile_quadratic: stretch(|t| t.tactile_quadratic),
            fused: stretch(|t| t.fused),
        })
    }
}

/// |n| and |α| over the trials that reached a stage.
#[derive(Debug, Clone, Serialize, JsonSchema)]
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
    let search_moves: Vec<f64> = entries
        .iter()
        .filter_map(|e| e.search_moves.map(f64::from))
        .collect();
    let shapes: Vec<&ShapeErrors> = entries
        .iter()
        .filter_map(|e| e.shape_errors.as_ref())
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
        search_moves_per_trial: Summary::of(&search_moves),
        shape_errors: ShapeErrorSummary::of(&shapes),
        cell_time_per_trial_s: Summary::of(&cell_time),
        compute_time_per_trial_s: Summary::of(&compute_time),
    }
}

/// The summary as a table, the policies side by side.
pub fn render_table(summary: &CampaignSummary) -> String {
    let header = format!(
        "campaign {}: {} trials per policy, seed {}\n",
        summary.name, summary.trials, summary.seed
    );
    let blocks: Vec<String> = summary
        .policies
        .chunks(POLICIES_PER_BLOCK)
        .map(render_block)
        .collect();
    header + &blocks.join("\n")
}

/// How many policies stand side by side before the table goes on below.
const POLICIES_PER_BLOCK: usize = 3;

/// The table's rows for `policies`, side by side.
fn render_block(policies: &[PolicySummary]) -> String {
    const LABEL: usize = 24;
    const CELL: usize = 60;
    let mut out = format!("{:LABEL$}", "");
    for policy in policies {
        out += &format!(
            "{:<CELL$}",
            format!("{} ({} trials)", policy.policy, policy.trials)
        );
    }
    out += &format!("\n{:LABEL$}", "");
    for _ in policies {
        out += &format!("{:<CELL$}", "mean [95 % CI] ± sd (median, p95, max)");
    }
    out.push('\n');
    let mut row = |label: String, cell: &dyn Fn(&PolicySummary) -> String| {
        out += &format!("{label:<LABEL$}");
        for policy in policies {
            out += &format!("{:<CELL$}", cell(policy));
        }
        out.push('\n');
    };
    let stage_names: Vec<String> = policies
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
    if let Some(beyond_mm) = policies
        .iter()
        .find_map(|p| Some(p.shape_errors.as_ref()?.beyond_mm))
    {
        // The pad's quadratic fit stands for touch: the paper's curve.
        type Part = fn(&ShapeErrorSummary) -> StretchSummary;
        let shapes: [(&str, Part); 3] = [
            ("vision", |s| s.vision),
            ("touch", |s| s.tactile_quadratic),
            ("fused", |s| s.fused),
        ];
        for (name, part) in shapes {
            row(format!("{name} shape, pad mm"), &|p| {
                cell(
                    p.shape_errors.as_ref().and_then(|s| part(s).grasped_mm),
                    1.0,
                    3,
                )
            });
            row(format!("{name} shape, ±{beyond_mm:.0} mm"), &|p| {
                cell(
                    p.shape_errors.as_ref().and_then(|s| part(s).beyond_mm),
                    1.0,
                    3,
                )
            });
        }
    }
    if policies.iter().any(|p| p.search_moves_per_trial.is_some()) {
        row("search moves per trial".into(), &|p| {
            cell(p.search_moves_per_trial, 1.0, 2)
        });
    }
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
            "{:.d$} {} ± {:.d$} ({:.d$}, {:.d$}, {:.d$})",
            s.mean * scale,
            s.mean_ci95.map_or("[—]".to_owned(), |[low, high]| format!(
                "[{:.d$}, {:.d$}]",
                low * scale,
                high * scale,
                d = digits
            )),
            s.std_dev * scale,
            s.median * scale,
            s.p95 * scale,
            s.max * scale,
            d = digits
        ),
        None => "—".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::trial::{GraspResult, Perturbation};
    use approx::assert_relative_eq;

    fn entry(trial: usize, errors_n_mm: &[f64], outcome: TrialOutcome) -> TrialEntry {
        TrialEntry {
            campaign_seed: 1,
            trial,
            policy: "p".into(),
            seed: trial as u64,
            perturbation: Perturbation {
                start_offset_mm: 0.0,
                start_angle_rad: 0.0,
                cable_diameter_mm: 2.5,
                cable_stiffness_n_mm2: 60.0,
                sensor_noise_fraction: 0.02,
            },
            outcome,
            detail: None,
            grasps: errors_n_mm
                .iter()
                .map(|&n_mm| GraspResult {
                    estimate: None,
                    truth: None,
                    error: Some(PoseError {
                        n_mm,
                        alpha_rad: -n_mm / 10.0,
                    }),
                    estimate_error: None,
                })
                .collect(),
            states: Vec::new(),
            cell_time_s: 4.0 + trial as f64,
            compute_time_s: 0.001,
            recording: None,
            search_moves: None,
            shape_errors: None,
        }
    }

    #[test]
    fn a_hand_computed_campaign() {
        let entries = [
            entry(0, &[1.0, 0.2], TrialOutcome::Success),
            entry(1, &[-2.0], TrialOutcome::Failed),
            entry(2, &[6.0, -0.4], TrialOutcome::Success),
        ];
        let summary = summarise("c", 1, 3, &["p".into(), "q".into()], &entries);
        let p = &summary.policies[0];
        assert_eq!(p.trials, 3);
        // Trial grasp |n| = 1, 2, 6: mean 3; sd √((4 + 1 + 9) / 2) = √7;
        // median 2; p95 at rank 0.95·2 = 1.9: 2 + 0.9·(6 − 2) = 5.6.
        let trial = p.stages[0].n_mm.expect("trial grasp");
        assert_eq!(p.stages[0].stage, "trial grasp");
        assert_relative_eq!(trial.mean, 3.0);
        assert_relative_eq!(trial.std_dev, 7.0_f64.sqrt());
        assert_relative_eq!(trial.median, 2.0);
        assert_relative_eq!(trial.p95, 5.6, epsilon = 1e-12);
        assert_relative_eq!(trial.max, 6.0);
        assert_relative_eq!(p.stages[0].alpha_rad.expect("α").mean, 0.3);
        // Regrasp 1 only in trials 0 and 2: |n| 0.2, 0.4.
        assert_eq!(p.stages[1].stage, "regrasp 1");
        assert_eq!(p.stages[1].n_mm.expect("regrasp").count, 2);
        assert_relative_eq!(
            p.stages[1].n_mm.expect("regrasp").mean,
            0.3,
            epsilon = 1e-12
        );
        // Final: 0.2, 2, 0.4.
        assert_eq!(p.stages[2].stage, "final");
        assert_relative_eq!(
            p.stages[2].n_mm.expect("final").mean,
            2.6 / 3.0,
            epsilon = 1e-12
        );
        let success = p.success.expect("rate");
        assert_eq!((success.successes, success.trials), (2, 3));
        assert_relative_eq!(
            p.regrasps_per_trial.expect("regrasps").mean,
            2.0 / 3.0,
            epsilon = 1e-12
        );
        assert_relative_eq!(p.cell_time_per_trial_s.expect("time").mean, 5.0);
        // A policy with no trials has no numbers, and the table says so.
        let q = &summary.policies[1];
        assert_eq!(q.trials, 0);
        assert!(q.success.is_none());
        let table = render_table(&summary);
        assert!(
            // t₀.₉₇₅,₂ = 4.3027: 3 ± 4.3027 · 2.646 / √3 = 3 ± 6.572.
            table.contains(
                "trial grasp |n| mm      3.000 [-3.572, 9.572] ± 2.646 (2.000, 5.600, 6.000)"
            ),
            "{table}"
        );
        assert!(table.contains("2/3 = 67 %"), "{table}");
    }
}
