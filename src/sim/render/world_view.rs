//! The simulated camera's view of the simulated world.

use nalgebra::{Isometry3, Point3, Vector3};
use rand::Rng;

use super::hand::hand;
use super::occluder::board_over;
use super::{
    Appearance, CableSpec, MarkerSpec, RenderError, RenderedScene, SceneSpec, clip_to_image, render,
};
use crate::perception::vision::calibration::{CameraModel, MarkerOnFinger};
use crate::sim::world::SimWorld;

/// The simulated camera's view of the simulated world: the cable (its
/// sagging centre line from `sim::cable`, placed by the world, projected
/// through `base_from_camera` and the intrinsics) drawn as a shaded tube of
/// the cable's diameter in pixels at its mean depth over the background;
/// what the appearance puts in front of it (a board over a stretch of the
/// cable as the image shows it, the arm's hand where the TCP is); and the
/// finger's marker when it faces the camera. While the jaws hold the cable
/// it is drawn where it lay when they closed.
pub fn render_world(
    world: &SimWorld,
    camera: &CameraModel,
    base_from_camera: &Isometry3<f64>,
    marker: Option<&MarkerOnFinger>,
    appearance: &Appearance,
    rng: &mut impl Rng,
) -> Result<RenderedScene, RenderError> {
    let camera_from_base = base_from_camera.inverse();
    let camera_from_cable = camera_from_base * world.base_from_cable;
    let half_span_mm = world.cable.span_mm / 2.0;
    let point_at = |u_mm: f64| {
        let (height_mm, _) = world.cable.height_and_slope(u_mm);
        camera_from_cable * Point3::new(u_mm, height_mm, 0.0)
    };
    // About one point per pixel along the cable's image.
    let chord_px = match (
        camera.project(&point_at(-half_span_mm)),
        camera.project(&point_at(half_span_mm)),
    ) {
        (Some(a), Some(b)) => (a[0] - b[0]).hypot(a[1] - b[1]),
        _ => 0.0,
    };
    let samples = (chord_px.ceil() as usize).clamp(64, 4096);
    let in_camera: Vec<Point3<f64>> = (0..=samples)
        .map(|i| point_at(-half_span_mm + 2.0 * half_span_mm * i as f64 / samples as f64))
        .filter(|p| p.z > 0.0)
        .collect();
    let centerline_px: Vec<[f64; 2]> = in_camera.iter().filter_map(|p| camera.project(p)).collect();

    let mut cables = Vec::new();
    if centerline_px.len() >= 2 {
        let mean_depth_mm = in_camera.iter().map(|p| p.z).sum::<f64>() / in_camera.len() as f64;
        let focal_px = (camera.fx_px + camera.fy_px) / 2.0;
        cables.push(CableSpec {
            centerline_px,
            diameter_px: focal_px * world.cable_diameter_mm / mean_depth_mm,
            bgr: appearance.cable_bgr,
            gloss: appearance.cable_gloss,
            metal_end_px: 0.0,
        });
    }

    let mut occluders = Vec::new();
    if let (Some(board), Some(cable)) = (&appearance.occlusion.board, cables.first()) {
        let seen_px = clip_to_image(&cable.centerline_px, camera.width_px, camera.height_px);
        occluders.extend(board_over(&seen_px, cable.diameter_px / 2.0, board));
    }
    if appearance.occlusion.arm_in_view {
        let camera_from_tcp = camera_from_base * world.base_from_tcp;
        occluders.extend(hand(camera, &camera_from_tcp, world.opening_mm)?);
    }

    let marker = marker.and_then(|marker| {
        let camera_from_marker = camera_from_base * world.base_from_tcp * marker.tcp_from_marker;
        let normal = camera_from_marker.rotation * Vector3::z();
        // Seen from behind, or edge on, the marker shows nothing.
        if normal.dot(&-camera_from_marker.translation.vector) <= 0.0 {
            return None;
        }
        let corners = marker.corners_in_marker();
        let mut corners_px = [[0.0; 2]; 4];
        for (corner_px, corner) in corners_px.iter_mut().zip(&corners) {
            *corner_px = camera.project(&(camera_from_marker * corner))?;
        }
        Some(MarkerSpec {
            dictionary: marker.dictionary,
            id: marker.id,
            corners_px,
        })
    });

    render(
        &SceneSpec {
            width_px: camera.width_px,
            height_px: camera.height_px,
            background: appearance.background.clone(),
            cables,
            light: appearance.light,
            noise_sigma: appearance.noise_sigma,
            blur_sigma_px: appearance.blur_sigma_px,
            occluders,
            marker,
        },
        rng,
    )
}
