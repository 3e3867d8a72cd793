//! From a cable in the image to its grasp frame in the robot's base frame
//! (the paper's eq. 1). A single 2D camera gives each pixel a ray, not a
//! point: the paper places the camera at a known distance from the cable;
//! here the cable's plane is known (the fixture it hangs in, from the cell
//! file), and the ray of each image point meets it at the point in space.

use nalgebra::{
    Isometry3, Matrix3, Point3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3,
};

use super::calibration::CameraModel;
use super::spline::BSpline;
use crate::perception::shape::{SHAPE_SPACING_MM, ShapePoint, resample};

/// A plane in the base frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneInBase {
    pub point_mm: Point3<f64>,
    pub normal: Unit<Vector3<f64>>,
}

/// What places image points in the base frame: the camera's intrinsics, its
/// calibrated pose, the cable's plane, and the side the hand comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageToBase {
    pub intrinsics: CameraModel,
    pub base_from_camera: Isometry3<f64>,
    pub cable_plane: PlaneInBase,
    /// The grasp frame's y points to this side (in the base frame).
    pub approach_from: Unit<Vector3<f64>>,
    /// How well the calibration fitted the marker (RMS, pixels): an image
    /// point's error beyond the pipeline's own.
    pub reprojection_error_px: f64,
}

/// Rays nearer than this to parallel with the plane (cosine) meet it too
/// far away to be a cable in view.
const MIN_RAY_INCIDENCE: f64 = 1e-6;

impl ImageToBase {
    /// Where the ray through image point `px` meets the cable's plane, in
    /// the base frame; `None` if it runs parallel to the plane or meets it
    /// behind the camera.
    pub fn point_in_base(&self, px: [f64; 2]) -> Option<Point3<f64>> {
        let k = &self.intrinsics;
        let ray_in_camera = Vector3::new(
            (px[0] - k.cx_px) / k.fx_px,
            (px[1] - k.cy_px) / k.fy_px,
            1.0,
        );
        let ray = self.base_from_camera.rotation * ray_in_camera;
        let origin = Point3::from(self.base_from_camera.translation.vector);
        let normal = self.cable_plane.normal.into_inner();
        let incidence = ray.dot(&normal);
        if incidence.abs() < MIN_RAY_INCIDENCE * ray.norm() {
            return None;
        }
        let t = (self.cable_plane.point_mm - origin).dot(&normal) / incidence;
        (t > 0.0 && t.is_finite()).then(|| origin + t * ray)
    }

    /// Millimetres a pixel spans at `point_in_base` (seen face on): its
    /// depth in front of the camera over the focal length.
    pub fn mm_per_px(&self, point_in_base: &Point3<f64>) -> f64 {
        let depth_mm = (self.base_from_camera.inverse() * point_in_base).z;
        let focal_px = 0.5 * (self.intrinsics.fx_px + self.intrinsics.fy_px);
        depth_mm.abs() / focal_px
    }

    /// The cable's centre line in the base frame: the spline, about
    /// `length_px` long, sampled about every pixel, placed on the plane and
    /// taken every [`SHAPE_SPACING_MM`]; each point's σ is `sigma_px` (the
    /// pipeline's centre line against the true one) and the calibration's
    /// reprojection error, in quadrature, at the point's scale. Only what
    /// the spline covers: what the pipeline found of the cable.
    pub fn centre_line(&self, spline: &BSpline, length_px: f64, sigma_px: f64) -> Vec<ShapePoint> {
        let count = length_px.max(1.0).ceil() as usize + 1;
        let on_plane: Vec<Point3<f64>> = spline
            .sample(count)
            .into_iter()
            .filter_map(|px| self.point_in_base(px))
            .collect();
        let image_sigma_px = sigma_px.hypot(self.reprojection_error_px);
        resample(&on_plane, SHAPE_SPACING_MM)
            .into_iter()
            .map(|in_base_mm| ShapePoint {
                in_base_mm,
                sigma_mm: image_sigma_px * self.mm_per_px(&in_base_mm),
            })
            .collect()
    }

    /// The paper's grasp frame at s = 0.5 of the cable's spline, in the
    /// base frame: x along the cable (from its points at s = 0.45 to
    /// 0.55, placed on the plane), z the plane's normal towards the camera
    /// (for a camera facing the plane, the paper's "orthogonal to the image
    /// plane, towards the camera"), y = z × x, turned half a turn about z
    /// if need be so that y points to the side the hand comes from.
    pub fn base_from_cable(&self, spline: &BSpline) -> Option<Isometry3<f64>> {
        let grasp = self.point_in_base(spline.point(0.5))?;
        let before = self.point_in_base(spline.point(0.45))?;
        let after = self.point_in_base(spline.point(0.55))?;
        let camera_position = self.base_from_camera.translation.vector;
        let mut z = self.cable_plane.normal.into_inner();
        if z.dot(&(camera_position - grasp.coords)) < 0.0 {
            z = -z;
        }
        let along = after - before;
        let mut x = (along - along.dot(&z) * z).try_normalize(1e-9)?;
        let mut y = z.cross(&x);
        if y.dot(&self.approach_from) < 0.0 {
            x = -x;
            y = -y;
        }
        let rotation = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
        Some(Isometry3::from_parts(
            Translation3::from(grasp.coords),
            UnitQuaternion::from_rotation_matrix(&rotation),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera 400 mm in front of the plane y = 0, looking along +y, image
    /// x along base x and image y down (base −z).
    fn image_to_base() -> ImageToBase {
        let rotation = Matrix3::from_columns(&[Vector3::x(), -Vector3::z(), Vector3::y()]);
        ImageToBase {
            intrinsics: CameraModel::centred(640, 480, 1.0),
            base_from_camera: Isometry3::from_parts(
                Translation3::new(450.0, -400.0, 300.0),
                UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rotation)),
            ),
            cable_plane: PlaneInBase {
                point_mm: Point3::new(0.0, 0.0, 0.0),
                normal: Vector3::y_axis(),
            },
            approach_from: Vector3::z_axis(),
            reprojection_error_px: 0.3,
        }
    }

    fn project(to_base: &ImageToBase, point: Point3<f64>) -> [f64; 2] {
        to_base
            .intrinsics
            .project(&(to_base.base_from_camera.inverse() * point))
            .unwrap()
    }

    #[test]
    fn a_projected_point_comes_back_onto_the_plane() {
        let to_base = image_to_base();
        for point in [
            Point3::new(450.0, 0.0, 250.0),
            Point3::new(380.0, 0.0, 330.0),
            Point3::new(520.0, 0.0, 190.0),
        ] {
            let back = to_base.point_in_base(project(&to_base, point)).unwrap();
            assert!((back - point).norm() < 1e-9, "{back} vs {point}");
        }
    }

    #[test]
    fn a_ray_that_misses_the_plane_gives_no_point() {
        let mut to_base = image_to_base();
        // The plane behind the camera.
        to_base.cable_plane.point_mm = Point3::new(0.0, -500.0, 0.0);
        assert!(to_base.point_in_base([320.0, 240.0]).is_none());
    }

    #[test]
    fn the_centre_line_lies_on_the_cable_with_sigma_at_its_depth() {
        let to_base = image_to_base();
        // A cable 100 mm long in the plane, 400 mm from the camera.
        let start = Point3::new(400.0, 0.0, 260.0);
        let points: Vec<[f64; 2]> = (0..=100)
            .map(|i| project(&to_base, start + Vector3::new(f64::from(i), 0.0, 0.0)))
            .collect();
        let spline = BSpline::fit(&points, 6).unwrap();
        let length_px = 100.0 * to_base.intrinsics.fx_px / 400.0;
        let line = to_base.centre_line(&spline, length_px, 0.4);
        assert_eq!(line.len(), 101);
        // 0.4 px and 0.3 px make 0.5 px, of 400 / f mm each.
        let sigma_mm = 0.5 * 400.0 / to_base.intrinsics.fx_px;
        for (i, point) in line.iter().enumerate() {
            let expected = start + Vector3::new(i as f64, 0.0, 0.0);
            assert!((point.in_base_mm - expected).norm() < 0.05, "{point:?}");
            assert!((point.sigma_mm - sigma_mm).abs() < 1e-9, "{point:?}");
        }
    }

    #[test]
    fn the_grasp_frame_follows_the_cable_with_y_towards_the_hand() {
        let to_base = image_to_base();
        // A cable in the plane at 30° from base x, rising to the right in
        // base (so falling in the image), drawn from right to left.
        let angle = 30f64.to_radians();
        let direction = Vector3::new(angle.cos(), 0.0, angle.sin());
        let centre = Point3::new(450.0, 0.0, 250.0);
        let points: Vec<[f64; 2]> = (0..=100)
            .map(|i| project(&to_base, centre + direction * (60.0 - 1.2 * f64::from(i))))
            .collect();
        let spline = BSpline::fit(&points, 8).unwrap();
        let frame = to_base.base_from_cable(&spline).unwrap();
        assert!((frame.translation.vector - centre.coords).norm() < 0.05);
        let x = frame.rotation * Vector3::x();
        let y = frame.rotation * Vector3::y();
        let z = frame.rotation * Vector3::z();
        // Along the cable, whichever end the spline started from.
        assert!(x.dot(&direction).abs() > 0.9999, "{x}");
        // Towards the camera, and y towards the hand above.
        assert!((z - (-Vector3::y())).norm() < 1e-9, "{z}");
        assert!(y.z > 0.0, "{y}");
    }
}
