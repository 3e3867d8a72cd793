//! The arm's hand as the camera sees it: the gripper's two fingers, its
//! housing and the arm's wrist above it, boxes placed by the TCP's pose
//! and the jaws' opening, each drawn as its silhouette, the farthest first.
//! Sizes are a PG70 on a Panda, to a centimetre or so: enough to cover
//! the cable where the real hand would.

use nalgebra::{Isometry3, Point3};
use opencv::core::{Point2f, Vector};
use opencv::imgproc;

use super::{OccluderSpec, RenderError, cv};
use crate::perception::vision::calibration::CameraModel;

/// A box of the hand in the TCP frame (x along the fingers' width, y the
/// closing axis, z the approach: the hand lies at negative z).
struct Part {
    min_mm: [f64; 3],
    max_mm: [f64; 3],
    bgr: [u8; 3],
}

/// The tactile fingers: the 5×5 pad (18 mm) in its frame, 70 mm from the
/// tips to the jaws.
const FINGER_WIDTH_MM: f64 = 24.0;
const FINGER_THICKNESS_MM: f64 = 10.0;
const FINGER_LENGTH_MM: f64 = 70.0;
/// The PG70's housing: 70 mm across the jaws' travel, 100 mm along it,
/// 95 mm tall.
const HOUSING_MM: [f64; 3] = [70.0, 100.0, 95.0];
/// The Panda's wrist and flange, 200 mm of it: the arm beyond leaves the
/// view.
const WRIST_MM: [f64; 3] = [80.0, 80.0, 200.0];
/// Anodised fingers, a dark housing, the Panda's white wrist.
const FINGER_BGR: [u8; 3] = [60, 60, 64];
const HOUSING_BGR: [u8; 3] = [45, 42, 40];
const WRIST_BGR: [u8; 3] = [205, 205, 200];

/// The hand's boxes with the jaws `opening_mm` apart.
fn parts(opening_mm: f64) -> [Part; 4] {
    let inner = opening_mm.max(0.0) / 2.0;
    let half_width = FINGER_WIDTH_MM / 2.0;
    let finger = |y0: f64, y1: f64| Part {
        min_mm: [-half_width, y0, -FINGER_LENGTH_MM],
        max_mm: [half_width, y1, 0.0],
        bgr: FINGER_BGR,
    };
    let stacked = |size: [f64; 3], below_mm: f64, bgr: [u8; 3]| Part {
        min_mm: [-size[0] / 2.0, -size[1] / 2.0, -below_mm - size[2]],
        max_mm: [size[0] / 2.0, size[1] / 2.0, -below_mm],
        bgr,
    };
    [
        finger(inner, inner + FINGER_THICKNESS_MM),
        finger(-inner - FINGER_THICKNESS_MM, -inner),
        stacked(HOUSING_MM, FINGER_LENGTH_MM, HOUSING_BGR),
        stacked(WRIST_MM, FINGER_LENGTH_MM + HOUSING_MM[2], WRIST_BGR),
    ]
}

/// The hand's parts in the image, the farthest first; a part reaching
/// behind the camera is left out.
pub(super) fn hand(
    camera: &CameraModel,
    camera_from_tcp: &Isometry3<f64>,
    opening_mm: f64,
) -> Result<Vec<OccluderSpec>, RenderError> {
    let mut seen: Vec<(f64, OccluderSpec)> = Vec::new();
    for part in parts(opening_mm) {
        let corners: Vec<Point3<f64>> = (0..8)
            .map(|i| {
                let pick = |axis: usize| {
                    if i & (1 << axis) == 0 {
                        part.min_mm[axis]
                    } else {
                        part.max_mm[axis]
                    }
                };
                camera_from_tcp * Point3::new(pick(0), pick(1), pick(2))
            })
            .collect();
        let Some(corners_px) = corners
            .iter()
            .map(|corner| camera.project(corner))
            .collect::<Option<Vec<[f64; 2]>>>()
        else {
            continue;
        };
        let points: Vector<Point2f> = corners_px
            .iter()
            .map(|&[x, y]| Point2f::new(x as f32, y as f32))
            .collect();
        let mut hull = Vector::<Point2f>::new();
        imgproc::convex_hull(&points, &mut hull, false, true)
            .map_err(cv("outline a part of the hand"))?;
        if hull.len() < 3 {
            continue;
        }
        let depth_mm = corners.iter().map(|c| c.z).sum::<f64>() / 8.0;
        seen.push((
            depth_mm,
            OccluderSpec {
                outline_px: hull
                    .iter()
                    .map(|p| [f64::from(p.x), f64::from(p.y)])
                    .collect(),
                bgr: part.bgr,
                texture: 0.0,
                grain_px: 1.0,
                texture_seed: 0,
            },
        ));
    }
    seen.sort_by(|a, b| b.0.total_cmp(&a.0));
    Ok(seen.into_iter().map(|(_, occluder)| occluder).collect())
}
