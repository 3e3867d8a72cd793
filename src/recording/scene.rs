//! What Foxglove draws of the cell, as its well-known messages: the
//! cell's frames (`/tf`), the 3D scene (the pad and its taxels, the
//! cable's shapes), the tactile map as an image, and the detector's
//! findings over the camera image with the camera's calibration.
//! Foxglove's positions are metres (the cell's are mm) and its
//! quaternions x, y, z, w.

use foxglove::messages::{
    CameraCalibration, Color, CubePrimitive, FrameTransform, FrameTransforms, ImageAnnotations,
    LinePrimitive, Point2, Point3, PointsAnnotation, Pose, Quaternion, RawImage, SceneEntity,
    SceneUpdate, SpherePrimitive, TextAnnotation, Vector3, line_primitive, points_annotation,
};
use nalgebra::{Isometry3, Point3 as NaPoint3, Vector3 as NaVector3};
use plotters::prelude::RGBColor;

use super::schema::Timestamp;
use crate::cell::CellFile;
use crate::detector::CableDetection;
use crate::perception::shape::ShapePoint;
use crate::perception::tactile::map::{taxel_x_mm, taxel_y_mm};
use crate::perception::tactile::{PAD_HALF_SIDE_PITCH, TAXEL_COLS, TAXEL_ROWS, TactileMap};
use crate::perception::vision::calibration::CameraModel;
use crate::plot::colour;
use crate::record::GraspShapes;

/// The cell's fixed frames and its camera, from the cell file.
#[derive(Debug, Clone, PartialEq)]
pub struct CellView {
    pub tcp_from_sensor: Isometry3<f64>,
    pub tcp_from_marker: Isometry3<f64>,
    /// `None` when the cell file holds no camera calibration yet.
    pub camera: Option<CameraView>,
    pub pitch_mm: f64,
}

/// The camera as the detector knows it: the calibrated pose and the
/// intrinsics.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraView {
    pub base_from_camera: Isometry3<f64>,
    pub model: CameraModel,
}

impl CellView {
    pub fn of(cell: &CellFile) -> Self {
        Self {
            tcp_from_sensor: cell.tactile.tcp_from_sensor.isometry(),
            tcp_from_marker: cell.camera.marker.tcp_from_marker.isometry(),
            camera: cell.camera.calibration.as_ref().map(|c| CameraView {
                base_from_camera: c.base_from_camera.isometry(),
                model: cell.camera.intrinsics,
            }),
            pitch_mm: cell.tactile.pitch_mm,
        }
    }
}

/// Δv at which a taxel's sphere and colour are full: about the peak of a
/// firm grasp on the paper's pad.
const FULL_SCALE_V: f64 = 1.0;

/// The cell's frames at `timestamp`: `base` → `tcp` (the arm's measured
/// pose) → `sensor`, `marker`; `base` → `camera` (calibrated), `cable`
/// (the detected grasp frame). A frame not known yet is left out.
pub fn frame_transforms(
    view: &CellView,
    timestamp: Timestamp,
    base_from_tcp: Option<&Isometry3<f64>>,
    base_from_cable: Option<&Isometry3<f64>>,
) -> FrameTransforms {
    let transform = |parent: &str, child: &str, parent_from_child: &Isometry3<f64>| {
        let pose = pose(parent_from_child);
        FrameTransform {
            timestamp: Some(timestamp.into()),
            parent_frame_id: parent.into(),
            child_frame_id: child.into(),
            translation: pose.position,
            rotation: pose.orientation,
        }
    };
    let mut transforms = vec![
        transform("tcp", "sensor", &view.tcp_from_sensor),
        transform("tcp", "marker", &view.tcp_from_marker),
    ];
    transforms.extend(base_from_tcp.map(|t| transform("base", "tcp", t)));
    transforms.extend(
        view.camera
            .as_ref()
            .map(|c| transform("base", "camera", &c.base_from_camera)),
    );
    transforms.extend(base_from_cable.map(|t| transform("base", "cable", t)));
    FrameTransforms { transforms }
}

/// The pad in its own frame, locked to it as the arm moves: a thin plate,
/// and a sphere a taxel whose size and colour grow with its Δv.
pub fn pad_scene(view: &CellView, timestamp: Timestamp, map: &TactileMap) -> SceneUpdate {
    let pitch_m = view.pitch_mm / 1000.0;
    let side_m = 2.0 * PAD_HALF_SIDE_PITCH * pitch_m;
    let plate = CubePrimitive {
        pose: Some(pose(&Isometry3::translation(0.0, 0.0, -0.0005))),
        size: Some(Vector3 {
            x: side_m,
            y: side_m,
            z: 0.001,
        }),
        color: Some(rgba(colour::REGION, 0.6)),
    };
    let mut spheres = Vec::with_capacity(TAXEL_ROWS * TAXEL_COLS);
    for (row, values) in map.dv_v.iter().enumerate() {
        for (col, dv_v) in values.iter().enumerate() {
            let level = full_scale_fraction(*dv_v);
            let diameter_m = pitch_m * (0.2 + 0.7 * level);
            let centre_mm = NaVector3::new(
                taxel_x_mm(col, view.pitch_mm),
                taxel_y_mm(row, view.pitch_mm),
                0.0,
            );
            spheres.push(SpherePrimitive {
                pose: Some(pose(&Isometry3::from_parts(
                    centre_mm.into(),
                    nalgebra::UnitQuaternion::identity(),
                ))),
                size: Some(Vector3 {
                    x: diameter_m,
                    y: diameter_m,
                    z: diameter_m,
                }),
                color: Some(heat(level)),
            });
        }
    }
    SceneUpdate {
        deletions: Vec::new(),
        entities: vec![SceneEntity {
            timestamp: Some(timestamp.into()),
            frame_id: "sensor".into(),
            id: "pad".into(),
            frame_locked: true,
            cubes: vec![plate],
            spheres,
            ..Default::default()
        }],
    }
}

/// The cable's shapes at a grasp, in the base frame: what the camera saw,
/// the pad's fits (line, curve, ridge), the fused shape, and on a
/// simulated cell the true cable; one entity each, replaced at the next
/// grasp.
pub fn shapes_scene(timestamp: Timestamp, shapes: &GraspShapes) -> SceneUpdate {
    let along = |points: &Option<Vec<ShapePoint>>| {
        points
            .as_ref()
            .map(|p| p.iter().map(|p| p.in_base_mm).collect::<Vec<_>>())
    };
    let lines = [
        ("cable/vision", along(&shapes.vision), colour::VISION),
        (
            "cable/tactile_linear",
            along(&shapes.tactile_linear),
            colour::TACTILE_LINEAR,
        ),
        (
            "cable/tactile_quadratic",
            along(&shapes.tactile_quadratic),
            colour::TACTILE_QUADRATIC,
        ),
        (
            "cable/tactile_ridge",
            along(&shapes.tactile_ridge),
            colour::TACTILE_RIDGE,
        ),
        ("cable/fused", along(&shapes.fused), colour::FUSED),
        ("cable/truth", shapes.truth.clone(), colour::TRUTH),
    ];
    SceneUpdate {
        deletions: Vec::new(),
        entities: lines
            .into_iter()
            .filter_map(|(id, points, colour)| Some(line_entity(timestamp, id, &points?, colour)))
            .collect(),
    }
}

/// The detected cable's centre line, in the base frame, as soon as it is
/// seen.
pub fn vision_scene(timestamp: Timestamp, centre_line: &[ShapePoint]) -> SceneUpdate {
    let points: Vec<_> = centre_line.iter().map(|p| p.in_base_mm).collect();
    SceneUpdate {
        deletions: Vec::new(),
        entities: vec![line_entity(
            timestamp,
            "cable/vision",
            &points,
            colour::VISION,
        )],
    }
}

fn line_entity(
    timestamp: Timestamp,
    id: &str,
    in_base_mm: &[NaPoint3<f64>],
    colour: RGBColor,
) -> SceneEntity {
    SceneEntity {
        timestamp: Some(timestamp.into()),
        frame_id: "base".into(),
        id: id.into(),
        lines: vec![LinePrimitive {
            r#type: line_primitive::Type::LineStrip as i32,
            pose: Some(pose(&Isometry3::identity())),
            thickness: 2.0,
            scale_invariant: true,
            points: in_base_mm.iter().map(point_m).collect(),
            color: Some(rgba(colour, 1.0)),
            ..Default::default()
        }],
        ..Default::default()
    }
}

/// Pixels a taxel takes in the tactile image.
const TAXEL_PX: usize = 10;

/// The Δv map as an `rgb8` image, row 0 (c11..c15) at the top as the
/// paper draws it, a block of pixels a taxel, dark at no pressure to
/// bright yellow at [`FULL_SCALE_V`].
pub fn tactile_image(timestamp: Timestamp, map: &TactileMap) -> RawImage {
    let (width, height) = (TAXEL_COLS * TAXEL_PX, TAXEL_ROWS * TAXEL_PX);
    let mut data = Vec::with_capacity(width * height * 3);
    for values in &map.dv_v {
        let row: Vec<[u8; 3]> = values
            .iter()
            .map(|dv_v| {
                let colour = heat(full_scale_fraction(*dv_v));
                [colour.r, colour.g, colour.b].map(|c| (c * 255.0).round() as u8)
            })
            .collect();
        for _ in 0..TAXEL_PX {
            for pixel in &row {
                for _ in 0..TAXEL_PX {
                    data.extend_from_slice(pixel);
                }
            }
        }
    }
    RawImage {
        timestamp: Some(timestamp.into()),
        frame_id: "sensor".into(),
        width: width as u32,
        height: height as u32,
        encoding: "rgb8".into(),
        step: (width * 3) as u32,
        data: data.into(),
    }
}

/// The camera's pinhole model: no distortion, as the detector assumes.
pub fn camera_calibration(camera: &CameraView, timestamp: Timestamp) -> CameraCalibration {
    let m = &camera.model;
    CameraCalibration {
        timestamp: Some(timestamp.into()),
        frame_id: "camera".into(),
        width: u32::try_from(m.width_px).unwrap_or(0),
        height: u32::try_from(m.height_px).unwrap_or(0),
        distortion_model: "plumb_bob".into(),
        d: vec![0.0; 5],
        k: vec![m.fx_px, 0.0, m.cx_px, 0.0, m.fy_px, m.cy_px, 0.0, 0.0, 1.0],
        r: vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        p: vec![
            m.fx_px, 0.0, m.cx_px, 0.0, 0.0, m.fy_px, m.cy_px, 0.0, 0.0, 0.0, 1.0, 0.0,
        ],
    }
}

/// Length of the grasp frame's axes drawn over the image.
const AXIS_MM: f64 = 15.0;

/// The detections over the camera image: each cable's centre line, its
/// grasp frame (x red, y green) and its number, projected through the
/// calibrated camera.
pub fn annotations(
    camera: &CameraView,
    timestamp: Timestamp,
    cables: &[CableDetection],
) -> ImageAnnotations {
    let camera_from_base = camera.base_from_camera.inverse();
    let project = |in_base_mm: &NaPoint3<f64>| {
        let [x, y] = camera.model.project(&(camera_from_base * in_base_mm))?;
        Some(Point2 { x, y })
    };
    let stamp = Some(timestamp.into());
    let mut annotations = ImageAnnotations {
        timestamp: stamp,
        ..Default::default()
    };
    for (k, cable) in cables.iter().enumerate() {
        annotations.points.push(PointsAnnotation {
            timestamp: stamp,
            r#type: points_annotation::Type::LineStrip as i32,
            points: cable
                .centre_line
                .iter()
                .filter_map(|p| project(&p.in_base_mm))
                .collect(),
            outline_color: Some(rgba(colour::VISION, 1.0)),
            thickness: 2.0,
            ..Default::default()
        });
        let origin = cable.base_from_cable * NaPoint3::origin();
        for (axis, colour) in [
            (NaVector3::x(), RGBColor(230, 30, 30)),
            (NaVector3::y(), RGBColor(30, 200, 30)),
        ] {
            let tip = cable.base_from_cable * NaPoint3::from(axis * AXIS_MM);
            let (Some(from), Some(to)) = (project(&origin), project(&tip)) else {
                continue;
            };
            annotations.points.push(PointsAnnotation {
                timestamp: stamp,
                r#type: points_annotation::Type::LineList as i32,
                points: vec![from, to],
                outline_color: Some(rgba(colour, 1.0)),
                thickness: 2.0,
                ..Default::default()
            });
        }
        if let Some(at) = project(&origin) {
            annotations.texts.push(TextAnnotation {
                timestamp: stamp,
                position: Some(Point2 {
                    x: at.x + 8.0,
                    y: at.y - 8.0,
                }),
                text: format!("cable {k}"),
                font_size: 14.0,
                text_color: Some(rgba(RGBColor(255, 255, 255), 1.0)),
                background_color: Some(rgba(RGBColor(0, 0, 0), 0.6)),
                ..Default::default()
            });
        }
    }
    annotations
}

/// A transform in Foxglove's units: metres, quaternion x, y, z, w.
fn pose(parent_from_child: &Isometry3<f64>) -> Pose {
    let t = parent_from_child.translation.vector / 1000.0;
    let q = parent_from_child.rotation;
    Pose {
        position: Some(Vector3 {
            x: t.x,
            y: t.y,
            z: t.z,
        }),
        orientation: Some(Quaternion {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        }),
    }
}

fn point_m(p: &NaPoint3<f64>) -> Point3 {
    Point3 {
        x: p.x / 1000.0,
        y: p.y / 1000.0,
        z: p.z / 1000.0,
    }
}

fn rgba(colour: RGBColor, a: f64) -> Color {
    Color {
        r: f64::from(colour.0) / 255.0,
        g: f64::from(colour.1) / 255.0,
        b: f64::from(colour.2) / 255.0,
        a,
    }
}

/// Δv as a fraction of full scale, in [0, 1] (a NaN as 0).
fn full_scale_fraction(dv_v: f64) -> f64 {
    if dv_v.is_nan() {
        return 0.0;
    }
    (dv_v / FULL_SCALE_V).clamp(0.0, 1.0)
}

/// Dark blue at 0 through red to yellow at 1.
fn heat(level: f64) -> Color {
    Color {
        r: (1.6 * level).min(1.0) * 0.95 + 0.05,
        g: (2.0 * level - 1.0).clamp(0.0, 1.0),
        b: 0.35 * (1.0 - 2.0 * level).max(0.0),
        a: 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_are_metres_and_quaternions_xyzw() {
        let rotation = nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, 0.5);
        let pose = pose(&Isometry3::from_parts(
            nalgebra::Translation3::new(450.0, -20.0, 300.0),
            rotation,
        ));
        let position = pose.position.unwrap();
        assert_eq!((position.x, position.y, position.z), (0.45, -0.02, 0.3));
        let q = pose.orientation.unwrap();
        assert!((q.z - (0.25f64).sin()).abs() < 1e-12 && (q.w - (0.25f64).cos()).abs() < 1e-12);
    }

    #[test]
    fn the_tactile_image_is_a_block_a_taxel_row_c11_first() {
        let mut values = [0.0; 25];
        values[0] = 2.0; // c11, beyond full scale
        let map = TactileMap::from_row_major(&values).unwrap();
        let image = tactile_image(Timestamp::of_ns(0), &map);
        assert_eq!((image.width, image.height, image.step), (50, 50, 150));
        assert_eq!(image.data.len(), 50 * 150);
        // Top-left block bright, the next one dark.
        assert_eq!(&image.data[..3], &[255, 255, 0]);
        assert_eq!(&image.data[(9 * 150 + 9 * 3)..][..3], &[255, 255, 0]);
        assert_eq!(image.data[10 * 3], 13);
    }

    #[test]
    fn a_nan_taxel_is_drawn_as_no_pressure() {
        assert_eq!(full_scale_fraction(f64::NAN), 0.0);
        assert_eq!(full_scale_fraction(-1.0), 0.0);
    }
}
