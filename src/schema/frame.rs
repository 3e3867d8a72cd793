//! A rigid transform as a file writes it.

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use serde::Deserialize;

use crate::schema::validate::vector3;

/// A rigid transform as written in a cell file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameConfig {
    #[serde(deserialize_with = "vector3")]
    pub translation_mm: [f64; 3],
    /// Roll, pitch, yaw (about x, y, z of the parent, applied in that order).
    #[serde(deserialize_with = "vector3")]
    pub rotation_rpy_rad: [f64; 3],
}

impl FrameConfig {
    pub fn from_isometry(isometry: &Isometry3<f64>) -> Self {
        let (roll, pitch, yaw) = isometry.rotation.euler_angles();
        Self {
            translation_mm: isometry.translation.vector.into(),
            rotation_rpy_rad: [roll, pitch, yaw],
        }
    }

    pub fn isometry(&self) -> Isometry3<f64> {
        let [x, y, z] = self.translation_mm;
        let [roll, pitch, yaw] = self.rotation_rpy_rad;
        Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_euler_angles(roll, pitch, yaw),
        )
    }
}
