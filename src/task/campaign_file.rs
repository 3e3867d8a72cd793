//! The campaign file: which task on which cell, how many trials, the
//! seeded perturbations of each trial, and the policies to compare.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Deserializer, de::Error};

use super::task_file::Tolerance;
use crate::geometry::CorrectionGain;
use crate::perception::tactile::Estimator;
use crate::schema::toml_file::{ConfigError, parse, read};
use crate::schema::validate::{at_least_one, non_negative, non_negative_range, some_fraction};

/// A campaign file, e.g. `tasks/paper-regrasp-campaign.toml`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignFile {
    pub campaign: CampaignSection,
    pub perturbation: Perturbations,
    /// The policies to run on identical trials, side by side.
    #[serde(rename = "policy", deserialize_with = "policies")]
    pub policies: Vec<Policy>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignSection {
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// The task file, relative to the campaign file.
    pub task: PathBuf,
    /// The cell file, relative to the campaign file.
    pub cell: PathBuf,
    /// Trials per policy (the paper made 20).
    #[serde(default = "paper_trials", deserialize_with = "at_least_one")]
    pub trials: usize,
    pub seed: u64,
    /// Output folder, relative to the working directory.
    pub out: PathBuf,
}

fn paper_trials() -> usize {
    20
}

/// What varies from trial to trial; each trial draws its own values from
/// its seed.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Perturbations {
    /// Largest offset of the start grasp frame across the cable, drawn
    /// uniformly within ± (the paper's "small random offset on the initial
    /// reference frame"; a uniform draw keeps every start within reach).
    #[serde(deserialize_with = "non_negative")]
    pub start_offset_max_mm: f64,
    /// Largest angle of the start grasp frame about the pad's normal,
    /// likewise.
    #[serde(deserialize_with = "non_negative")]
    pub start_angle_max_rad: f64,
    /// Range of the cable's diameter, drawn uniformly.
    #[serde(deserialize_with = "non_negative_range")]
    pub cable_diameter_mm: [f64; 2],
    /// Range of the cable's bending stiffness EI, drawn uniformly.
    #[serde(deserialize_with = "non_negative_range")]
    pub cable_stiffness_n_mm2: [f64; 2],
    /// Range of the tactile noise (fraction of the taxels' swing).
    #[serde(deserialize_with = "non_negative_range")]
    pub sensor_noise_fraction: [f64; 2],
    /// What finds the cable at each trial's start.
    #[serde(default)]
    pub start: TrialStart,
}

/// What finds the cable at a trial's start.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrialStart {
    /// An oracle in place of the cell's detector, off by the drawn start
    /// offset and angle: the paper's experiment, which starts each trial
    /// from a chosen error.
    #[default]
    Oracle,
    /// The cell's own detector (its camera and the vision pipeline, which
    /// an occlusion hides from), so each start is as good as it finds; the
    /// start offset and angle ranges go unused.
    Detector,
}

/// An estimator and a regrasp budget.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Policy {
    pub name: String,
    pub estimator: Estimator,
    /// Regrasps allowed; a policy stops regrasping once within tolerance.
    pub max_regrasps: u32,
    /// The tolerance it regrasps towards, if not the task's.
    #[serde(default)]
    pub tolerance: Option<Tolerance>,
    /// How much of T_corr it applies, if not the task's.
    #[serde(default)]
    pub correction_gain: Option<CorrectionGain>,
    /// Error sources switched off for this policy, to show what each one
    /// costs (an error budget). Simulated cells only.
    #[serde(default)]
    pub perfect: Vec<ErrorSource>,
    /// The share of the cable a board hides from the simulated camera in
    /// this policy's trials, if not the cell's `hidden_fraction` (0 to 1).
    /// Simulated cameras only.
    #[serde(default, deserialize_with = "some_fraction")]
    pub occlusion_fraction: Option<f64>,
    /// Which senses find the cable.
    #[serde(default)]
    pub sensing: Sensing,
}

/// Which senses a policy finds the cable with.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Sensing {
    /// The camera, and where it cannot place the cable a search by touch
    /// from the task's `[prior]`, if it has one.
    #[default]
    Both,
    /// The camera alone: the task's prior is dropped, so a cable the camera
    /// cannot place fails the trial.
    Vision,
    /// Touch alone: a search from the task's `[prior]` without looking, its
    /// mean at the trial's start offset from the true grasp frame.
    Touch,
}

/// A source of error of the simulated cell that a policy can switch off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorSource {
    /// The tactile estimate: the cable's true pose is used instead.
    Estimator,
    /// The arm's repeatability: it reaches every pose exactly.
    Arm,
    /// The taxels' noise.
    SensorNoise,
    /// The cable's spring-back when the jaws open.
    SpringBack,
}

/// At least one policy, with distinct names.
fn policies<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Policy>, D::Error> {
    let policies = Vec::<Policy>::deserialize(d)?;
    if policies.is_empty() {
        return Err(D::Error::custom("expected at least one [[policy]]"));
    }
    for (i, policy) in policies.iter().enumerate() {
        if policies[..i].iter().any(|p| p.name == policy.name) {
            return Err(D::Error::custom(format!(
                "policy name `{}` is used twice",
                policy.name
            )));
        }
    }
    Ok(policies)
}

impl CampaignFile {
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        parse(path, &read(path)?)
    }

    /// The task file's path as the campaign file names it.
    pub fn task_path(&self, campaign_path: &Path) -> PathBuf {
        relative_to(campaign_path, &self.campaign.task)
    }

    pub fn cell_path(&self, campaign_path: &Path) -> PathBuf {
        relative_to(campaign_path, &self.campaign.cell)
    }
}

fn relative_to(file: &Path, path: &Path) -> PathBuf {
    file.parent().unwrap_or(Path::new("")).join(path)
}
