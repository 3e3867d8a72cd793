//! The choice of estimator: the paper's centroids, or cablecell's ridge.

use serde::{Deserialize, Serialize};

use super::fit::{FitConfig, FitError, WireFit, fit_wire};
use super::map::TactileMap;
use crate::geometry::LineInSensor;

/// How a Δv map becomes the cable's line on the pad.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Estimator {
    /// The paper's: row or column centroids and a least-squares line.
    Centroids,
}

/// An estimator's answer, with its own details.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "estimator", rename_all = "snake_case")]
pub enum Estimate {
    Centroids(WireFit),
}

impl Estimator {
    pub fn estimate(self, map: &TactileMap, config: &FitConfig) -> Result<Estimate, FitError> {
        match self {
            Estimator::Centroids => fit_wire(map, config).map(Estimate::Centroids),
        }
    }
}

impl Estimate {
    pub fn line(&self) -> LineInSensor {
        match self {
            Estimate::Centroids(fit) => fit.line,
        }
    }
}
