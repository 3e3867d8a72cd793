//! Where the camera is in the base frame, from the fiducial marker on one
//! finger (the paper's Section II, eq. 1): ArUco finds the marker in the
//! image, solvePnP gives `camera_from_marker`, and the arm's kinematics give
//! `base_from_marker`, so `base_from_camera = base_from_tcp · tcp_from_marker
//! · marker_from_camera`.
//!
//! The camera frame is OpenCV's: x right, y down, z along the optical axis
//! into the scene. The marker frame is the one solvePnP's IPPE_SQUARE
//! solver uses: origin at the marker's centre, x towards its right edge, y
//! towards its top edge (as printed), z out of its face.

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use opencv::aruco::{self, PREDEFINED_DICTIONARY_NAME};
use opencv::calib3d;
use opencv::core::{Mat, Point2f, Point3f, Vector};
use opencv::imgproc;
use opencv::prelude::*;

/// A pinhole camera without distortion, in OpenCV's pixel convention:
/// integer coordinates are pixel centres, so a centred principal point is
/// at ((width − 1) / 2, (height − 1) / 2).
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct CameraModel {
    pub width_px: i32,
    pub height_px: i32,
    pub fx_px: f64,
    pub fy_px: f64,
    pub cx_px: f64,
    pub cy_px: f64,
}

/// Nearer than this in front of the optical centre a point has no image.
const MIN_DEPTH_MM: f64 = 1e-6;

impl CameraModel {
    /// Square pixels, the principal point at the image's centre, and the
    /// given horizontal field of view.
    pub fn centred(width_px: i32, height_px: i32, horizontal_fov_rad: f64) -> Self {
        let f_px = f64::from(width_px) / 2.0 / (horizontal_fov_rad / 2.0).tan();
        Self {
            width_px,
            height_px,
            fx_px: f_px,
            fy_px: f_px,
            cx_px: (f64::from(width_px) - 1.0) / 2.0,
            cy_px: (f64::from(height_px) - 1.0) / 2.0,
        }
    }

    /// Where a point in the camera frame appears in the image (it may fall
    /// outside it); `None` for a point at or behind the optical centre.
    pub fn project(&self, point_in_camera: &Point3<f64>) -> Option<[f64; 2]> {
        if point_in_camera.z < MIN_DEPTH_MM || !point_in_camera.coords.iter().all(|v| v.is_finite())
        {
            return None;
        }
        Some([
            self.cx_px + self.fx_px * point_in_camera.x / point_in_camera.z,
            self.cy_px + self.fy_px * point_in_camera.y / point_in_camera.z,
        ])
    }

    /// The 3×3 camera matrix OpenCV's pose solvers take.
    pub fn camera_matrix(&self) -> opencv::Result<Mat> {
        Mat::from_slice_2d(&[
            [self.fx_px, 0.0, self.cx_px],
            [0.0, self.fy_px, self.cy_px],
            [0.0, 0.0, 1.0],
        ])
    }

    /// A positive size and focal lengths, a finite principal point.
    pub fn is_valid(&self) -> bool {
        self.width_px > 0
            && self.height_px > 0
            && [self.fx_px, self.fy_px]
                .iter()
                .all(|f| f.is_finite() && *f > 0.0)
            && [self.cx_px, self.cy_px].iter().all(|c| c.is_finite())
    }
}

/// The fiducial marker fixed to one finger: which ArUco marker it is, its
/// size, and where it sits on the hand. Its pose on the hand comes from the
/// cell file; the arm's kinematics give the hand's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarkerOnFinger {
    pub dictionary: PREDEFINED_DICTIONARY_NAME,
    pub id: i32,
    /// The side of the marker's black square (its outer border), as ArUco
    /// measures markers.
    pub side_mm: f64,
    pub tcp_from_marker: Isometry3<f64>,
}

impl MarkerOnFinger {
    /// The black square's corners in the marker frame, in ArUco's order
    /// (top left, top right, bottom right, bottom left as printed), which is
    /// also the order IPPE_SQUARE expects them in.
    pub fn corners_in_marker(&self) -> [Point3<f64>; 4] {
        let h = self.side_mm / 2.0;
        [
            Point3::new(-h, h, 0.0),
            Point3::new(h, h, 0.0),
            Point3::new(h, -h, 0.0),
            Point3::new(-h, -h, 0.0),
        ]
    }
}

/// The camera's pose in the base frame and how well the marker's corners
/// fit it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraCalibration {
    pub base_from_camera: Isometry3<f64>,
    /// Root mean square distance between the detected corners and the
    /// corners reprojected through the solved pose. Sub-pixel for a sharp
    /// view; a large value means a bad detection or a wrong camera model.
    pub reprojection_error_px: f64,
}

/// Why the camera could not be calibrated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CalibrationError {
    /// The finger's marker is not in the image: the finger is out of view,
    /// turned away, occluded or too small. Move the arm so that the marker
    /// faces the camera, or check the marker's id and dictionary in the
    /// cell file against the ones found.
    #[error("marker {id} not found in image {view} (markers found: {found:?})")]
    NoMarker {
        id: i32,
        view: usize,
        found: Vec<i32>,
    },
    /// The same id was found more than once, so the finger's marker is
    /// ambiguous. Remove the other copies from the scene.
    #[error("marker {id} found {count} times in image {view}")]
    AmbiguousMarker { id: i32, view: usize, count: usize },
    /// The image is not an 8-bit colour or gray image of the camera's size.
    /// Check that the image comes from the camera the model describes.
    #[error(
        "image {view} is {width_px}×{height_px} of OpenCV type {cv_type}, \
         the camera gives {expected_width_px}×{expected_height_px} 8-bit images"
    )]
    BadImage {
        view: usize,
        width_px: i32,
        height_px: i32,
        cv_type: i32,
        expected_width_px: i32,
        expected_height_px: i32,
    },
    /// The camera model or the marker's size is not usable (a size or focal
    /// length not positive, or not a number), or no views were given. Fix
    /// the cell file or the call.
    #[error("bad calibration input: {what}")]
    BadModel { what: &'static str },
    /// solvePnP found no pose for the marker's corners.
    #[error("no pose fits marker {id}'s corners")]
    NoPose { id: i32 },
    /// OpenCV failed while `step` ran.
    #[error("OpenCV failed to {step}")]
    OpenCv {
        step: &'static str,
        #[source]
        source: opencv::Error,
    },
}

/// Wraps an OpenCV error with the step that failed.
fn cv(step: &'static str) -> impl FnOnce(opencv::Error) -> CalibrationError {
    move |source| CalibrationError::OpenCv { step, source }
}

/// One image of the finger's marker and where the arm's TCP was when it
/// was taken.
#[derive(Clone, Copy, Debug)]
pub struct MarkerView<'a> {
    pub bgr: &'a Mat,
    pub base_from_tcp: Isometry3<f64>,
}

/// Estimates `base_from_camera` from one image showing the finger's marker,
/// taken while the arm's TCP was at `base_from_tcp`: ArUco detection, the
/// corners refined by fitting the marker's edges, `camera_from_marker` by
/// solvePnP (IPPE_SQUARE, the solver made for a square's four corners),
/// then eq. 1: `base_from_camera = base_from_tcp · tcp_from_marker ·
/// marker_from_camera`.
///
/// One small marker fixes its distance and its position across the image
/// well but the tilt of its plane poorly: a tilt of θ moves the corners by
/// about θ · side² · f / (4 z²), a fiftieth of a pixel per degree for a
/// 30 mm marker 60 px wide at 400 mm. The camera's position, seen from the
/// marker, inherits that tilt error times the distance (7 mm per degree at
/// 400 mm). `calibrate_views` takes several arm poses and does better.
pub fn calibrate(
    bgr: &Mat,
    camera: &CameraModel,
    marker: &MarkerOnFinger,
    base_from_tcp: &Isometry3<f64>,
) -> Result<CameraCalibration, CalibrationError> {
    calibrate_views(
        &[MarkerView {
            bgr,
            base_from_tcp: *base_from_tcp,
        }],
        camera,
        marker,
    )
}

/// Estimates `base_from_camera` from several images of the finger's marker
/// with the arm at different poses. Each view's corners, placed in the base
/// frame by the arm's kinematics (`base_from_tcp · tcp_from_marker`), are
/// points of one rigid set that the one camera sees, so a single PnP over
/// all of them (Levenberg–Marquardt from the best single view's IPPE
/// solution) fixes the camera's pose; poses that spread the marker over the
/// workspace, in depth too, make the tilt as well determined as the rest.
pub fn calibrate_views(
    views: &[MarkerView<'_>],
    camera: &CameraModel,
    marker: &MarkerOnFinger,
) -> Result<CameraCalibration, CalibrationError> {
    if views.is_empty() {
        return Err(CalibrationError::BadModel {
            what: "no views of the marker were given",
        });
    }
    if !camera.is_valid() {
        return Err(CalibrationError::BadModel {
            what: "the camera's size and focal lengths must be positive and finite",
        });
    }
    if !(marker.side_mm.is_finite() && marker.side_mm > 0.0) {
        return Err(CalibrationError::BadModel {
            what: "the marker's side must be positive and finite",
        });
    }
    let corners_in_marker = marker.corners_in_marker();
    let mut object_points = Vec::with_capacity(4 * views.len());
    let mut image_points = Vec::with_capacity(4 * views.len());
    // The single view whose own solution fits it best starts the search.
    let mut start: Option<(f64, Isometry3<f64>)> = None;
    for (index, view) in views.iter().enumerate() {
        let corners_px = detect_corners(view.bgr, camera, marker, index)?;
        let camera_from_marker = solve_marker_pose(&corners_px, camera, marker)?;
        let base_from_marker = view.base_from_tcp * marker.tcp_from_marker;
        let base_from_camera = base_from_marker * camera_from_marker.inverse();
        let points: Vec<Point3<f64>> = corners_in_marker
            .iter()
            .map(|corner| base_from_marker * corner)
            .collect();
        let error_px = reprojection_error_px(camera, &base_from_camera, &points, &corners_px);
        if start.is_none_or(|(best, _)| error_px < best) {
            start = Some((error_px, base_from_camera));
        }
        object_points.extend(points);
        image_points.extend(corners_px);
    }
    let Some((start_error_px, start_pose)) = start else {
        return Err(CalibrationError::BadModel {
            what: "no views of the marker were given",
        });
    };
    if views.len() == 1 {
        return Ok(CameraCalibration {
            base_from_camera: start_pose,
            reprojection_error_px: start_error_px,
        });
    }
    let base_from_camera = refine_pose(
        camera,
        &start_pose,
        &object_points,
        &image_points,
        marker.id,
    )?;
    Ok(CameraCalibration {
        base_from_camera,
        reprojection_error_px: reprojection_error_px(
            camera,
            &base_from_camera,
            &object_points,
            &image_points,
        ),
    })
}

/// Root mean square distance between `seen` and `points_in_base` projected
/// from `base_from_camera`.
fn reprojection_error_px(
    camera: &CameraModel,
    base_from_camera: &Isometry3<f64>,
    points_in_base: &[Point3<f64>],
    seen: &[Point2f],
) -> f64 {
    let camera_from_base = base_from_camera.inverse();
    let squared_sum: f64 = points_in_base
        .iter()
        .zip(seen)
        .map(
            |(point, seen)| match camera.project(&(camera_from_base * point)) {
                Some(p) => (p[0] - f64::from(seen.x)).powi(2) + (p[1] - f64::from(seen.y)).powi(2),
                None => f64::INFINITY,
            },
        )
        .sum();
    (squared_sum / points_in_base.len().max(1) as f64).sqrt()
}

/// `base_from_camera` that best reprojects all the views' corners, by
/// Levenberg–Marquardt from `start`.
fn refine_pose(
    camera: &CameraModel,
    start: &Isometry3<f64>,
    points_in_base: &[Point3<f64>],
    seen: &[Point2f],
    id: i32,
) -> Result<Isometry3<f64>, CalibrationError> {
    let object_points: Vector<Point3f> = points_in_base
        .iter()
        .map(|p| Point3f::new(p.x as f32, p.y as f32, p.z as f32))
        .collect();
    let image_points: Vector<Point2f> = seen.iter().copied().collect();
    let camera_from_base = start.inverse();
    let r = camera_from_base.rotation.scaled_axis();
    let t = camera_from_base.translation.vector;
    // Column vectors: the solver writes its result into a 3×1 matrix,
    // and into a copy when given any other shape.
    let column = |v: [f64; 3]| Mat::from_slice(&v).and_then(|m| m.reshape(1, 3)?.try_clone());
    let mut rvec = column([r.x, r.y, r.z]).map_err(cv("hold the rotation"))?;
    let mut tvec = column([t.x, t.y, t.z]).map_err(cv("hold the translation"))?;
    let camera_matrix = camera
        .camera_matrix()
        .map_err(cv("build the camera matrix"))?;
    let criteria = opencv::core::TermCriteria::new(
        opencv::core::TermCriteria_COUNT + opencv::core::TermCriteria_EPS,
        100,
        1e-12,
    )
    .map_err(cv("set the solver's criteria"))?;
    calib3d::solve_pnp_refine_lm(
        &object_points,
        &image_points,
        &camera_matrix,
        &Mat::default(),
        &mut rvec,
        &mut tvec,
        criteria,
    )
    .map_err(cv("refine the camera's pose over all views"))?;
    let camera_from_base = isometry(&rvec, &tvec).ok_or(CalibrationError::NoPose { id })?;
    Ok(camera_from_base.inverse())
}

/// The marker's four corners in the image, sub-pixel, in ArUco's order.
fn detect_corners(
    bgr: &Mat,
    camera: &CameraModel,
    marker: &MarkerOnFinger,
    view: usize,
) -> Result<[Point2f; 4], CalibrationError> {
    let cv_type = bgr.typ();
    let size_ok = bgr.cols() == camera.width_px && bgr.rows() == camera.height_px;
    let gray = if size_ok && cv_type == opencv::core::CV_8UC3 {
        let mut gray = Mat::default();
        imgproc::cvt_color_def(bgr, &mut gray, imgproc::COLOR_BGR2GRAY)
            .map_err(cv("convert the image to gray"))?;
        gray
    } else if size_ok && cv_type == opencv::core::CV_8UC1 {
        bgr.try_clone().map_err(cv("copy the image"))?
    } else {
        return Err(CalibrationError::BadImage {
            view,
            width_px: bgr.cols(),
            height_px: bgr.rows(),
            cv_type,
            expected_width_px: camera.width_px,
            expected_height_px: camera.height_px,
        });
    };

    let dictionary =
        aruco::get_predefined_dictionary(marker.dictionary).map_err(cv("load the dictionary"))?;
    let mut parameters =
        aruco::DetectorParameters::create().map_err(cv("create detector parameters"))?;
    // Sub-pixel corners to start from, and to fall back on.
    parameters.set_corner_refinement_method(aruco::CORNER_REFINE_SUBPIX);
    let mut corners: Vector<Vector<Point2f>> = Vector::new();
    let mut ids: Vector<i32> = Vector::new();
    let mut rejected: Vector<Vector<Point2f>> = Vector::new();
    aruco::detect_markers(
        &gray,
        &dictionary,
        &mut corners,
        &mut ids,
        &parameters,
        &mut rejected,
    )
    .map_err(cv("detect markers"))?;

    let found: Vec<i32> = ids.to_vec();
    let matches: Vec<usize> = (0..found.len())
        .filter(|&i| found[i] == marker.id)
        .collect();
    let index = match matches.as_slice() {
        [] => {
            return Err(CalibrationError::NoMarker {
                id: marker.id,
                view,
                found,
            });
        }
        [index] => *index,
        _ => {
            return Err(CalibrationError::AmbiguousMarker {
                id: marker.id,
                view,
                count: matches.len(),
            });
        }
    };
    let quad = corners
        .get(index)
        .map_err(cv("read the marker's corners"))?;
    let [a, b, c, d] = quad.to_vec()[..] else {
        return Err(CalibrationError::NoPose { id: marker.id });
    };
    let modules = dictionary.marker_size() + 2;
    let gray_pixels = gray.data_bytes().map_err(cv("read the gray image"))?;
    let image = GrayImage {
        pixels: gray_pixels,
        width: gray.cols(),
        height: gray.rows(),
    };
    Ok(refine_corners(&image, [a, b, c, d], modules).unwrap_or([a, b, c, d]))
}

/// A gray image's pixels, row by row.
struct GrayImage<'a> {
    pixels: &'a [u8],
    width: i32,
    height: i32,
}

impl GrayImage<'_> {
    /// Bilinear sample at (x, y), pixel centres at integers.
    fn sample(&self, x: f64, y: f64) -> Option<f64> {
        let (x0, y0) = (x.floor(), y.floor());
        let (ix, iy) = (x0 as i32, y0 as i32);
        if ix < 0 || iy < 0 || ix + 1 >= self.width || iy + 1 >= self.height {
            return None;
        }
        let (fx, fy) = (x - x0, y - y0);
        let at =
            |dx: i32, dy: i32| f64::from(self.pixels[((iy + dy) * self.width + ix + dx) as usize]);
        let top = at(0, 0) * (1.0 - fx) + at(1, 0) * fx;
        let bottom = at(0, 1) * (1.0 - fx) + at(1, 1) * fx;
        Some(top * (1.0 - fy) + bottom * fy)
    }
}

/// Along each side, the middle share of it that is searched for the edge
/// (away from the corners, where the other side's edge bends the profile).
const EDGE_SPAN: (f64, f64) = (0.15, 0.85);
/// Steps along an edge profile (pixels).
const PROFILE_STEP_PX: f64 = 0.25;
/// Below this black-to-white contrast (gray levels) a profile is not an
/// edge of the marker (an occluder, a reflection).
const MIN_EDGE_CONTRAST: f64 = 30.0;

/// The corners as the intersections of lines fitted to the marker's four
/// outer edges, each edge point found across the edge between the black
/// border and the white margin (see `edge_offset`). ArUco's own sub-pixel
/// refinement (cornerSubPix, made for chessboard saddles) pulls an L-shaped
/// corner inwards by a tenth of a pixel or so, which tilts the solved pose
/// by a degree for a small marker; the edges' lines are not biased so.
/// `None` when an edge cannot be measured, and the detector's corners
/// stand.
fn refine_corners(
    image: &GrayImage<'_>,
    corners: [Point2f; 4],
    modules: i32,
) -> Option<[Point2f; 4]> {
    let p = corners.map(|c| [f64::from(c.x), f64::from(c.y)]);
    let centre = [
        p.iter().map(|c| c[0]).sum::<f64>() / 4.0,
        p.iter().map(|c| c[1]).sum::<f64>() / 4.0,
    ];
    let mut lines = [([0.0; 2], [0.0; 2]); 4];
    for side in 0..4 {
        let (a, b) = (p[side], p[(side + 1) % 4]);
        let length = (b[0] - a[0]).hypot(b[1] - a[1]);
        if length < 4.0 {
            return None;
        }
        let along = [(b[0] - a[0]) / length, (b[1] - a[1]) / length];
        let mut normal = [along[1], -along[0]];
        let middle = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        if normal[0] * (middle[0] - centre[0]) + normal[1] * (middle[1] - centre[1]) < 0.0 {
            normal = [-normal[0], -normal[1]];
        }
        // Stay within the black border inside and the white margin
        // outside: both are one module wide.
        let reach = (0.6 * length / f64::from(modules)).clamp(1.5, 8.0);
        let samples = length.ceil() as usize;
        let mut points = Vec::with_capacity(samples);
        for i in 0..=samples {
            let t = EDGE_SPAN.0 + (EDGE_SPAN.1 - EDGE_SPAN.0) * i as f64 / samples as f64;
            let base = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            if let Some(offset) = edge_offset(image, base, normal, reach) {
                points.push([base[0] + offset * normal[0], base[1] + offset * normal[1]]);
            }
        }
        if points.len() < 5 {
            return None;
        }
        lines[side] = fit_line(&points)?;
    }
    let mut refined = corners;
    for (i, corner) in refined.iter_mut().enumerate() {
        let [x, y] = intersect(lines[(i + 3) % 4], lines[i])?;
        // A corner that moved more than a pixel or two was not refined but
        // lost.
        if (x - p[i][0]).hypot(y - p[i][1]) > 2.0 {
            return None;
        }
        *corner = Point2f::new(x as f32, y as f32);
    }
    Some(refined)
}

/// Where, along `normal` from `base`, the edge from the dark inside to the
/// light outside lies: the point that splits the profile's area as an
/// ideal step between its dark and light levels would. Unlike the
/// half-level crossing, which interpolation between pixels moves by up to
/// a tenth of a pixel, the area is kept by the pixels' averaging and by the
/// interpolation, and noise averages out over it.
fn edge_offset(image: &GrayImage<'_>, base: [f64; 2], normal: [f64; 2], reach: f64) -> Option<f64> {
    let steps = (2.0 * reach / PROFILE_STEP_PX).round() as usize;
    let profile: Vec<f64> = (0..=steps)
        .map(|i| {
            let s = -reach + i as f64 * PROFILE_STEP_PX;
            image.sample(base[0] + s * normal[0], base[1] + s * normal[1])
        })
        .collect::<Option<_>>()?;
    let end = 3.min(profile.len() / 4).max(1);
    let dark = profile[..end].iter().sum::<f64>() / end as f64;
    let light = profile[profile.len() - end..].iter().sum::<f64>() / end as f64;
    if light - dark < MIN_EDGE_CONTRAST {
        return None;
    }
    let lightness: Vec<f64> = profile
        .iter()
        .map(|v| (v - dark) / (light - dark))
        .collect();
    // The trapezoid rule over the profile.
    let area = PROFILE_STEP_PX
        * (lightness.iter().sum::<f64>() - (lightness[0] + lightness[lightness.len() - 1]) / 2.0);
    let reach_sampled = steps as f64 * PROFILE_STEP_PX / 2.0;
    Some(reach_sampled - area)
}

/// The total-least-squares line through `points`: a point on it and its
/// direction.
fn fit_line(points: &[[f64; 2]]) -> Option<([f64; 2], [f64; 2])> {
    let n = points.len() as f64;
    let mean = [
        points.iter().map(|p| p[0]).sum::<f64>() / n,
        points.iter().map(|p| p[1]).sum::<f64>() / n,
    ];
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in points {
        let (dx, dy) = (p[0] - mean[0], p[1] - mean[1]);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    // The principal axis of the scatter.
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let direction = [angle.cos(), angle.sin()];
    direction
        .iter()
        .all(|v| v.is_finite())
        .then_some((mean, direction))
}

/// Where two lines (a point and a direction each) meet.
fn intersect(first: ([f64; 2], [f64; 2]), second: ([f64; 2], [f64; 2])) -> Option<[f64; 2]> {
    let ((p, d), (q, e)) = (first, second);
    let cross = d[0] * e[1] - d[1] * e[0];
    if cross.abs() < 1e-9 {
        return None;
    }
    let t = ((q[0] - p[0]) * e[1] - (q[1] - p[1]) * e[0]) / cross;
    Some([p[0] + t * d[0], p[1] + t * d[1]])
}

/// `camera_from_marker` from the marker's corners in the image.
fn solve_marker_pose(
    corners_px: &[Point2f; 4],
    camera: &CameraModel,
    marker: &MarkerOnFinger,
) -> Result<Isometry3<f64>, CalibrationError> {
    let object_points: Vector<Point3f> = marker
        .corners_in_marker()
        .iter()
        .map(|p| Point3f::new(p.x as f32, p.y as f32, p.z as f32))
        .collect();
    let image_points: Vector<Point2f> = corners_px.iter().copied().collect();
    let camera_matrix = camera
        .camera_matrix()
        .map_err(cv("build the camera matrix"))?;
    let mut rvec = Mat::default();
    let mut tvec = Mat::default();
    let solved = calib3d::solve_pnp(
        &object_points,
        &image_points,
        &camera_matrix,
        &Mat::default(),
        &mut rvec,
        &mut tvec,
        false,
        calib3d::SOLVEPNP_IPPE_SQUARE,
    )
    .map_err(cv("solve the marker's pose"))?;
    if !solved {
        return Err(CalibrationError::NoPose { id: marker.id });
    }
    isometry(&rvec, &tvec).ok_or(CalibrationError::NoPose { id: marker.id })
}

/// The pose OpenCV's rotation vector (axis times angle, Rodrigues') and
/// translation give, if they are finite.
fn isometry(rvec: &Mat, tvec: &Mat) -> Option<Isometry3<f64>> {
    let rotation =
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_scaled_axis(vector3(rvec)?));
    Some(Isometry3::from_parts(
        Translation3::from(vector3(tvec)?),
        rotation,
    ))
}

/// A 3×1 (or 1×3) double matrix as a vector, if it is one and finite.
fn vector3(mat: &Mat) -> Option<Vector3<f64>> {
    let values = mat.data_typed::<f64>().ok()?;
    match values {
        [x, y, z] if [x, y, z].iter().all(|v| v.is_finite()) => Some(Vector3::new(*x, *y, *z)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_centred_camera_projects_the_axis_to_the_centre() {
        let camera = CameraModel::centred(640, 480, 1.0);
        let p = camera.project(&Point3::new(0.0, 0.0, 500.0)).unwrap();
        assert_eq!(p, [319.5, 239.5]);
        assert!(camera.project(&Point3::new(0.0, 0.0, -1.0)).is_none());
        let right = camera.project(&Point3::new(10.0, 0.0, 500.0)).unwrap();
        assert!((right[0] - 319.5 - camera.fx_px * 0.02).abs() < 1e-9);
    }

    /// A uniform colour image and a 30 mm marker with id 7 at the TCP.
    fn blank(width: i32, height: i32) -> (Mat, MarkerOnFinger) {
        let image = Mat::new_rows_cols_with_default(
            height,
            width,
            opencv::core::CV_8UC3,
            opencv::core::Scalar::all(200.0),
        )
        .unwrap();
        let marker = MarkerOnFinger {
            dictionary: PREDEFINED_DICTIONARY_NAME::DICT_4X4_50,
            id: 7,
            side_mm: 30.0,
            tcp_from_marker: Isometry3::identity(),
        };
        (image, marker)
    }

    #[test]
    fn a_blank_image_has_no_marker() {
        let camera = CameraModel::centred(320, 240, 1.0);
        let (image, marker) = blank(320, 240);
        let err = calibrate(&image, &camera, &marker, &Isometry3::identity()).unwrap_err();
        assert!(
            matches!(err, CalibrationError::NoMarker { id: 7, .. }),
            "{err}"
        );
    }

    #[test]
    fn an_image_of_another_size_is_refused() {
        let camera = CameraModel::centred(320, 240, 1.0);
        let (image, marker) = blank(100, 100);
        let err = calibrate(&image, &camera, &marker, &Isometry3::identity()).unwrap_err();
        assert!(matches!(err, CalibrationError::BadImage { .. }), "{err}");
    }
}
