//! The choice of estimator: the paper's centroids, cablecell's ridge, or,
//! on a simulated cell, the truth itself.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::fit::{FitConfig, FitError, WireFit, fit_wire};
use super::map::TactileMap;
use super::ridge_fit::{RidgeFit, fit_ridge};
use crate::geometry::LineInSensor;

/// How a Δv map becomes the cable's line on the pad.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Estimator {
    /// The paper's: row or column centroids and a least-squares line.
    Centroids,
    /// cablecell's: a line-spread ridge fitted to every taxel by
    /// Levenberg–Marquardt; no centroid truncation at the pad's edge.
    Ridge,
    /// The cable's true pose instead of the pad's estimate: a simulated
    /// cell's error budget uses it to switch the estimator's error off.
    Oracle,
}

/// An estimator's answer, with its own details.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(tag = "estimator", rename_all = "snake_case")]
// The paper's fit holds its centroids inline (no allocation on the
// per-frame path); an estimate is 264 bytes, moved once a grasp.
#[allow(clippy::large_enum_variant)]
pub enum Estimate {
    Centroids(WireFit),
    Ridge(RidgeFit),
    Oracle { line: LineInSensor },
}

impl Estimator {
    /// Estimates the cable's line from `map`; `true_line` is where it
    /// really lies, when the cell knows.
    pub fn estimate(
        self,
        map: &TactileMap,
        config: &FitConfig,
        true_line: Option<LineInSensor>,
    ) -> Result<Estimate, FitError> {
        match self {
            Estimator::Centroids => fit_wire(map, config).map(Estimate::Centroids),
            Estimator::Ridge => fit_ridge(map, config).map(Estimate::Ridge),
            Estimator::Oracle => true_line
                .map(|line| Estimate::Oracle { line })
                .ok_or(FitError::NoTruth),
        }
    }
}

impl Estimate {
    pub fn line(&self) -> LineInSensor {
        match self {
            Estimate::Centroids(fit) => fit.line,
            Estimate::Ridge(fit) => fit.line,
            Estimate::Oracle { line } => *line,
        }
    }

    /// The condition number of the least squares that gave the line (the
    /// paper's line fit, or the ridge's last Gauss–Newton step); `None`
    /// for the oracle and for a singular ridge.
    pub fn condition(&self) -> Option<f64> {
        match self {
            Estimate::Centroids(fit) => Some(fit.condition.line),
            Estimate::Ridge(fit) => fit.condition,
            Estimate::Oracle { .. } => None,
        }
    }
}
