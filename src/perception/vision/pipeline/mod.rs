//! The vision pipeline: image → mask → one path per cable → B-spline →
//! grasp point and direction, each stage timed.

use std::borrow::Cow;
use std::time::Instant;

use opencv::core::{self, Mat, Point, Rect, Scalar, Vector};
use opencv::imgproc;
use opencv::prelude::*;

use super::error::{VisionError, cv};
use super::mask::{self, BackgroundStats};
use super::paths;
use super::skeleton;
use super::spline::{self, BSpline};

/// How the cables' mask is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MaskMethod {
    /// The classical threshold when the background is plain and its mask
    /// not in doubt (see [`mask::classical_doubt`]), else the
    /// network (or, with no network, the classical threshold with a note).
    Auto,
    /// Colour distance from the background, Otsu, morphology.
    Classical,
    /// The segmentation network.
    Network,
}

/// How the mask is split into cables.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InstanceMethod {
    /// Skeleton graph, its branches paired at junctions by least bending
    /// and by colour (fast).
    Skeleton,
    /// The paper's: SLIC superpixels on the mask and walks on their
    /// adjacency graph.
    Superpixels,
}

/// What the pipeline does and where. Lengths and areas in px are those
/// of the image as worked on, [`Self::work_width_px`] wide.
#[derive(Clone, Debug)]
pub struct VisionConfig {
    pub mask: MaskMethod,
    pub instances: InstanceMethod,
    /// Images are worked on at this width, a wider one shrunk and a
    /// narrower one enlarged (by at most [`MAX_ENLARGEMENT`]), and what is
    /// found is mapped back to the image's pixels: the network and the
    /// lengths here were tuned on 640 px wide images, where a wire is
    /// about 6 px across; at a finer camera's resolution they would take
    /// edges and scraps for cables and several times as long, at a coarser
    /// one they would lose the wires. 0 works at the image's own size.
    pub work_width_px: u32,
    /// Bound all work to this region when known (the table, the fixture):
    /// it saves time and keeps clutter outside it from becoming cables.
    pub roi_px: Option<Rect>,
    /// Paths shorter than this are dropped: scraps of mask, not cables.
    pub min_cable_length_px: f64,
    /// Paths that run out of the region worked on and are shorter than
    /// this are dropped too: too little of such a cable is in view to
    /// grasp it, and the middle of what is seen is not the cable's middle.
    pub min_border_cable_length_px: f64,
    /// Paths straighter than an arc of this radius (px), and within 3 px
    /// of straight, are dropped, as are paths within 1.5 px of straight
    /// however short: the network takes edges of paper, folders and tables
    /// for cables, and a cable lying loose is never that straight (the
    /// straightest in cables-dev's training photographs bends like a 730 px
    /// arc). On a background plain around each pixel (see
    /// [`mask::plain_locally`]), such a path is kept when the background is
    /// alike on its two sides (see [`EDGE_SIDES_RATIO`]): an edge has two
    /// different sides. 0 keeps every path: for a cell whose cable is
    /// held taut.
    pub straight_edge_radius_px: f64,
    /// Mask blobs smaller than this are dropped as noise before the
    /// instances are looked for.
    pub min_blob_area_px: f64,
    /// Points sampled along each spline at uniform s (for display and
    /// scoring).
    pub samples_per_cable: usize,
    /// Superpixel side in cable widths for [`InstanceMethod::Superpixels`]
    /// (smaller: more superpixels, slower).
    pub superpixel_widths: f64,
    /// Draw each cable's mask and their union, in the image's size, for
    /// writing and scoring them. Grasp frames need neither, and at
    /// 1920 × 1440 the masks take about as long as the network, so the
    /// cell's detector leaves them out.
    pub cable_masks: bool,
}

impl Default for VisionConfig {
    fn default() -> Self {
        VisionConfig {
            mask: MaskMethod::Auto,
            instances: InstanceMethod::Skeleton,
            work_width_px: 640,
            roi_px: None,
            min_cable_length_px: 40.0,
            min_border_cable_length_px: 80.0,
            straight_edge_radius_px: 1500.0,
            min_blob_area_px: 80.0,
            samples_per_cable: 50,
            superpixel_widths: super::superpixels::DEFAULT_REGION_WIDTHS,
            cable_masks: true,
        }
    }
}

/// A segmentation network that gives the cables' mask; implemented by the
/// ONNX network so that the pipeline does not depend on its runtime.
pub trait MaskNetwork {
    /// The cables' mask for a BGR 8-bit image: one channel, the image's size
    /// (or any size: it is resized), 8-bit 0/255 (or 0/1) or 32-bit float
    /// probabilities.
    fn mask(&mut self, bgr: &Mat) -> Result<Mat, VisionError>;
}

/// One cable found in the image, in full-image pixel coordinates (x right,
/// y down), whatever the region of interest.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CableInstance {
    /// The cable's model, s = 0 at one end (the one with the smaller x) and
    /// s = 1 at the other.
    pub spline: BSpline,
    /// Points at uniform s from 0 to 1.
    pub samples_px: Vec<[f64; 2]>,
    /// The grasp point: the spline at s = 0.5.
    pub grasp_px: [f64; 2],
    /// The cable's direction at the grasp point: atan2(dy, dx) of the chord
    /// from s = 0.45 to s = 0.55, in image coordinates (y down).
    pub direction_rad: f64,
    /// Length of the skeleton path the spline was fitted to.
    pub length_px: f64,
    /// This cable's pixels: CV_8U 0/255, the image's size (cables overlap
    /// at crossings); `None` unless [`VisionConfig::cable_masks`].
    #[serde(skip)]
    pub mask: Option<Mat>,
}

/// What the pipeline found, and how.
#[derive(Debug)]
pub struct VisionOutput {
    pub cables: Vec<CableInstance>,
    /// The mask method actually run: `Classical` or `Network`.
    pub mask_used: MaskMethod,
    /// Whether the background was judged plain (see
    /// [`mask::PLAIN_MIN_FRACTION`]).
    pub plain_background: bool,
    /// The background statistics behind that judgement.
    pub background: BackgroundStats,
    /// The union of the cables' masks: CV_8U 0/255, the image's size.
    /// Mask pixels no cable took (scraps, stubs at the border) are not in
    /// it. `None` unless [`VisionConfig::cable_masks`].
    pub union_mask: Option<Mat>,
    /// The cables' typical width (mask area over skeleton length).
    pub cable_width_px: f64,
    /// The image's size as worked on over its own (see
    /// [`VisionConfig::work_width_px`]).
    pub work_scale: f64,
    /// Milliseconds per stage, in order: "prepare", "mask", "instances",
    /// "spline", and "instance_masks" when the cables' masks are drawn.
    pub timings_ms: Vec<(&'static str, f64)>,
    /// What a user should know about this run (fallbacks taken,
    /// detections dropped as edges or as cables too little in view).
    pub notes: Vec<String>,
}

/// The instances found in a given mask (for testing the later stages on
/// ground-truth masks).
#[derive(Debug)]
pub struct MaskInstances {
    pub cables: Vec<CableInstance>,
    pub cable_width_px: f64,
    /// Paths dropped as straight edges (see
    /// [`VisionConfig::straight_edge_radius_px`]).
    pub straight_dropped: usize,
    /// Paths dropped as running out of view too short (see
    /// [`VisionConfig::min_border_cable_length_px`]).
    pub border_dropped: usize,
    /// Milliseconds for "instances", "spline", and "instance_masks" when
    /// the cables' masks are drawn.
    pub timings_ms: Vec<(&'static str, f64)>,
}

/// The vision pipeline, configured once and run per image.
pub struct Pipeline {
    config: VisionConfig,
}

fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

impl Pipeline {
    pub fn new(config: VisionConfig) -> Self {
        Pipeline { config }
    }

    pub fn config(&self) -> &VisionConfig {
        &self.config
    }

    /// Finds the cables in a BGR image (gray, BGRA and 16-bit are accepted
    /// and converted). `network`: how to get a network mask when the
    /// configuration asks for one; without it `Network` is
    /// [`VisionError::NoNetwork`] and `Auto` on a busy background (or with
    /// a classical mask in doubt) falls back to the classical mask, saying
    /// so in the notes.
    pub fn detect(
        &mut self,
        bgr: &Mat,
        network: Option<&mut dyn MaskNetwork>,
    ) -> Result<VisionOutput, VisionError> {
        let mut timings_ms = Vec::new();
        let mut notes = Vec::new();
        let start = Instant::now();
        let image = mask::to_bgr8(bgr)?;
        let full = Rect::new(0, 0, image.cols(), image.rows());
        let roi = match self.config.roi_px {
            None => full,
            Some(r) => {
                let clipped = r & full;
                if clipped.width <= 0 || clipped.height <= 0 {
                    return Err(VisionError::RoiOutside {
                        x: r.x,
                        y: r.y,
                        width: r.width,
                        height: r.height,
                        cols: full.width,
                        rows: full.height,
                    });
                }
                if clipped != r {
                    notes.push(format!(
                        "region of interest clipped to the image: x={} y={} {}x{} px",
                        clipped.x, clipped.y, clipped.width, clipped.height
                    ));
                }
                clipped
            }
        };
        let cropped = if roi == full {
            image
        } else {
            Cow::Owned(
                Mat::roi(&*image, roi)
                    .and_then(|m| m.try_clone())
                    .map_err(cv("crop to region of interest"))?,
            )
        };
        let scale = work_scale(full.width, self.config.work_width_px);
        let work = to_work_size(cropped, scale)?;
        timings_ms.push(("prepare", ms_since(start)));

        let start = Instant::now();
        let background = mask::background_stats(&work)?;
        let network_mask = |net: &mut dyn MaskNetwork| -> Result<Mat, VisionError> {
            let raw = net.mask(&work)?;
            let size = work.size().map_err(cv("image size"))?;
            let binary = mask::binarize_network_mask(&raw, size)?;
            mask::clean_mask(&binary, self.config.min_blob_area_px)
        };
        let (mask_roi, mask_used, background) = match (self.config.mask, network) {
            (MaskMethod::Network, None) => return Err(VisionError::NoNetwork),
            (MaskMethod::Network, Some(net)) => {
                (network_mask(net)?, MaskMethod::Network, background)
            }
            (MaskMethod::Auto, Some(net)) if !background.plain => {
                (network_mask(net)?, MaskMethod::Network, background)
            }
            (method, network) => {
                let auto = method == MaskMethod::Auto;
                if auto && !background.plain {
                    notes.push(format!(
                        "background not plain ({:.0}% of pixels near its colour, plain needs {:.0}%) and no network given: used the classical mask, expect clutter in it",
                        100.0 * background.near_fraction,
                        100.0 * mask::PLAIN_MIN_FRACTION
                    ));
                }
                let (m, stats) =
                    mask::classical_mask(&work, &background, self.config.min_blob_area_px)?;
                let doubt = if auto && stats.plain {
                    mask::classical_doubt(&m, &stats)?
                } else {
                    None
                };
                match (doubt, network) {
                    (Some(why), Some(net)) => {
                        notes.push(format!("plain background, but {why}: used the network"));
                        (network_mask(net)?, MaskMethod::Network, stats)
                    }
                    (doubt, _) => {
                        if let Some(why) = doubt {
                            notes.push(format!(
                                "plain background, but {why}, and no network given: used the classical mask, expect cables cut along their length or in pieces"
                            ));
                        }
                        (m, MaskMethod::Classical, stats)
                    }
                }
            }
        };
        timings_ms.push(("mask", ms_since(start)));

        let found = self.cables_in(&work, &mask_roi, roi, full)?;
        timings_ms.extend(found.timings_ms);
        if found.straight_dropped > 0 {
            notes.push(format!(
                "dropped {} straight detection(s) as edges: they bend less than a {:.0} px arc, or lie within {EDGE_NOISE_SAGITTA_PX} px of straight (a straight-edge radius of 0 keeps them)",
                found.straight_dropped, self.config.straight_edge_radius_px
            ));
        }
        if found.border_dropped > 0 {
            notes.push(format!(
                "dropped {} cable(s) that run out of view shorter than {:.0} px: too little of them is in view to grasp (a minimum border length of 0 keeps them)",
                found.border_dropped, self.config.min_border_cable_length_px
            ));
        }
        let union_mask = if self.config.cable_masks {
            let mut union_mask = mask::zeros_u8(full.height, full.width)?;
            for own in found.cables.iter().filter_map(|c| c.mask.as_ref()) {
                union_mask
                    .set_to(&Scalar::all(255.0), own)
                    .map_err(cv("union of the cables' masks"))?;
            }
            Some(union_mask)
        } else {
            None
        };
        Ok(VisionOutput {
            cables: found.cables,
            mask_used,
            plain_background: background.plain,
            background,
            union_mask,
            cable_width_px: found.cable_width_px,
            work_scale: scale,
            timings_ms,
            notes,
        })
    }

    /// The instance, spline and instance-mask stages on a given CV_8U mask
    /// (non-zero = cable) of the whole image, ignoring the region of
    /// interest: to test and time them on ground-truth masks.
    pub fn instances_from_mask(&mut self, mask: &Mat) -> Result<MaskInstances, VisionError> {
        if mask.empty() || mask.rows() <= 0 || mask.cols() <= 0 {
            return Err(VisionError::EmptyImage { path: None });
        }
        if mask.typ() != core::CV_8UC1 {
            return Err(VisionError::UnsupportedImage {
                channels: mask.channels(),
                depth: mask.depth(),
            });
        }
        let full = Rect::new(0, 0, mask.cols(), mask.rows());
        self.cables_in(mask, mask, full, full)
    }

    /// Instances, splines and per-cable masks for `mask_roi`, the mask of
    /// `image_roi`, region `roi` of an image of extent `full`, perhaps
    /// resized (see [`VisionConfig::work_width_px`]): what is found is given
    /// in the image's pixels.
    fn cables_in(
        &self,
        image_roi: &Mat,
        mask_roi: &Mat,
        roi: Rect,
        full: Rect,
    ) -> Result<MaskInstances, VisionError> {
        let mut timings_ms = Vec::new();
        let start = Instant::now();
        let found = match self.config.instances {
            // `instances_from_mask` has no image and passes the mask as one:
            // crossings are then paired by shape alone.
            InstanceMethod::Skeleton => skeleton::paths_from_mask(
                mask_roi,
                (image_roi.channels() == 3).then_some(image_roi),
                self.config.min_cable_length_px,
            )?,
            InstanceMethod::Superpixels => super::superpixels::paths_from_mask(
                image_roi,
                mask_roi,
                self.config.min_cable_length_px,
                self.config.superpixel_widths,
            )?,
        };
        let size_px = [f64::from(mask_roi.cols()), f64::from(mask_roi.rows())];
        // A skeleton ends about half a width short of where its cable
        // leaves the region.
        let margin_px = found.width_px + 2.0;
        let at_border = |p: &[f64; 2]| paths::near_border(*p, size_px, margin_px);
        let paths: Vec<_> = found
            .paths
            .iter()
            .filter(|path| {
                let ends = [path.points_px.first(), path.points_px.last()];
                path.length_px >= self.config.min_border_cable_length_px
                    || !ends.into_iter().flatten().any(at_border)
            })
            .collect();
        let border_dropped = found.paths.len() - paths.len();
        timings_ms.push(("instances", ms_since(start)));

        let start = Instant::now();
        let to_image = ToImage::new(roi, size_px);
        let mut fitted = Vec::new();
        let mut straight_dropped = 0;
        let mut plain_around = None;
        for path in paths {
            let n = spline::control_points_for_length(path.length_px);
            let Some(mut spline) = BSpline::fit(&path.points_px, n) else {
                continue;
            };
            let samples_px = spline.sample(self.config.samples_per_cable);
            if looks_like_edge(
                &samples_px,
                path.length_px,
                self.config.straight_edge_radius_px,
            ) && !straight_cable(
                image_roi,
                mask_roi,
                &samples_px,
                found.width_px,
                &mut plain_around,
            )? {
                straight_dropped += 1;
                continue;
            }
            // A B-spline's points move with its control points under an
            // affine map: the spline fitted in working pixels becomes the
            // image's by moving them.
            for c in &mut spline.control_points_px {
                *c = to_image.point(*c);
            }
            let samples_px: Vec<_> = samples_px.into_iter().map(|p| to_image.point(p)).collect();
            let grasp_px = spline.point(0.5);
            let direction_rad = spline.grasp_direction_rad();
            fitted.push((path, spline, samples_px, grasp_px, direction_rad));
        }
        timings_ms.push(("spline", ms_since(start)));

        let start = Instant::now();
        let thickness = (1.5 * found.width_px).ceil().max(1.0) as i32 + 2;
        let mut cables = Vec::with_capacity(fitted.len());
        for (path, spline, samples_px, grasp_px, direction_rad) in fitted {
            let mask = if self.config.cable_masks {
                let own = path_mask(mask_roi, &path.points_px, thickness)?;
                Some(mask_in_image(&own, roi, full)?)
            } else {
                None
            };
            cables.push(CableInstance {
                spline,
                samples_px,
                grasp_px,
                direction_rad,
                length_px: path.length_px * to_image.length_scale(),
                mask,
            });
        }
        if self.config.cable_masks {
            timings_ms.push(("instance_masks", ms_since(start)));
        }
        Ok(MaskInstances {
            cables,
            cable_width_px: found.width_px * to_image.length_scale(),
            straight_dropped,
            border_dropped,
            timings_ms,
        })
    }
}

/// Maps pixels of the image as worked on (the region of interest, perhaps
/// resized) to the full image's pixels, whose centres are at whole
/// coordinates in both.
struct ToImage {
    offset_px: [f64; 2],
    scale: [f64; 2],
}

impl ToImage {
    /// For a region `roi` of the image worked on at `size_px`.
    fn new(roi: Rect, size_px: [f64; 2]) -> Self {
        ToImage {
            offset_px: [f64::from(roi.x), f64::from(roi.y)],
            scale: [
                f64::from(roi.width) / size_px[0],
                f64::from(roi.height) / size_px[1],
            ],
        }
    }

    fn point(&self, p: [f64; 2]) -> [f64; 2] {
        [0, 1].map(|i| p[i] * self.scale[i] + (self.scale[i] - 1.0) / 2.0 + self.offset_px[i])
    }

    /// Image pixels per working pixel, for lengths.
    fn length_scale(&self) -> f64 {
        (self.scale[0] + self.scale[1]) / 2.0
    }
}

/// The most an image is enlarged to reach the working width: enough for a
/// camera 160 px wide, and a bound on the memory a thin strip of an image
/// would take.
pub const MAX_ENLARGEMENT: f64 = 4.0;

/// The image's size as worked on over its own, for an image `width_px`
/// wide: see [`VisionConfig::work_width_px`].
fn work_scale(width_px: i32, work_width_px: u32) -> f64 {
    if work_width_px == 0 || width_px <= 0 {
        return 1.0;
    }
    (f64::from(work_width_px) / f64::from(width_px)).min(MAX_ENLARGEMENT)
}

/// `image` resized by `scale`: shrunk by area averaging, as the network's
/// input is, or enlarged bilinearly; unchanged at 1.
fn to_work_size(image: Cow<'_, Mat>, scale: f64) -> Result<Cow<'_, Mat>, VisionError> {
    if scale == 1.0 {
        return Ok(image);
    }
    let size = |side: i32| ((f64::from(side) * scale).round() as i32).max(1);
    let interpolation = if scale < 1.0 {
        imgproc::INTER_AREA
    } else {
        imgproc::INTER_LINEAR
    };
    let mut resized = Mat::default();
    imgproc::resize(
        &*image,
        &mut resized,
        core::Size::new(size(image.cols()), size(image.rows())),
        0.0,
        0.0,
        interpolation,
    )
    .map_err(cv("resize to the working width"))?;
    Ok(Cow::Owned(resized))
}

/// A cable's working-size mask `own`, of region `roi` of an image of
/// extent `full`, in the full image: inside `roi`, what resizing the whole
/// of `own` to `roi`'s size and cutting it at half gives (its edges follow
/// the cable rather than the working pixels' steps); zero elsewhere. Only
/// a box around the cable is resized, so that the cost grows with the
/// cable rather than with the camera's resolution.
fn mask_in_image(own: &Mat, roi: Rect, full: Rect) -> Result<Mat, VisionError> {
    let mut out = mask::zeros_u8(full.height, full.width)?;
    let found = imgproc::bounding_rect(own).map_err(cv("cable mask extent"))?;
    if found.width <= 0 || found.height <= 0 {
        return Ok(out);
    }
    let (x, image_x) = resize_span(found.x, found.width, own.cols(), roi.width);
    let (y, image_y) = resize_span(found.y, found.height, own.rows(), roi.height);
    let part = Mat::roi(own, Rect::new(x.0, y.0, x.1 - x.0, y.1 - y.0))
        .and_then(|m| m.try_clone())
        .map_err(cv("box around a cable"))?;
    let size = core::Size::new(image_x.1 - image_x.0, image_y.1 - image_y.0);
    let resized = mask::resize_and_cut(&part, size, 127.0)?;
    let to = Rect::new(
        roi.x + image_x.0,
        roi.y + image_y.0,
        size.width,
        size.height,
    );
    let mut dst = Mat::roi_mut(&mut out, to).map_err(cv("box around a cable in the image"))?;
    resized
        .copy_to(&mut dst)
        .map_err(cv("place a cable's mask in the image"))?;
    Ok(out)
}

/// Along one axis, the working pixels `[start, start + len)` grown to a
/// span whose resize matches the whole row's: by a pixel each way (a
/// bilinear resize reads one pixel beyond the one it lands on, and pixels
/// next to the span are then zero in both), and out to working pixels
/// whose edges map onto image pixels' edges (`work_px` working pixels
/// span `image_px` image ones). Returns the span in working pixels and in
/// image pixels.
fn resize_span(start: i32, len: i32, work_px: i32, image_px: i32) -> ((i32, i32), (i32, i32)) {
    let step = work_px / gcd(work_px, image_px);
    let lo = (start - 1).max(0) / step * step;
    let hi = ((start + len + 1 + step - 1) / step * step).min(work_px);
    let to_image = |w: i32| (i64::from(w) * i64::from(image_px) / i64::from(work_px)) as i32;
    ((lo, hi), (to_image(lo), to_image(hi)))
}

fn gcd(a: i32, b: i32) -> i32 {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// How far from straight an edge's detection can be: mask noise and lens
/// distortion bend a paper edge's by up to 2 px in cables-dev; a cable that
/// departs more from its chord is visibly bent, however long.
const EDGE_MAX_SAGITTA_PX: f64 = 3.0;

/// Within this of straight, a detection's shape cannot tell it from an
/// edge, however short: mask noise alone bends edges' detections this much
/// (0.6 to 1.7 px in cables-dev; its wire pieces depart 2.2 px or more).
const EDGE_NOISE_SAGITTA_PX: f64 = 1.5;

/// Whether a detection (points along it, `length_px` long) is straight
/// enough to be an edge (never when `radius_px` is 0): within
/// [`EDGE_MAX_SAGITTA_PX`] of its chord and bending less than an arc of
/// `radius_px`, or within [`EDGE_NOISE_SAGITTA_PX`] of its chord.
fn looks_like_edge(points_px: &[[f64; 2]], length_px: f64, radius_px: f64) -> bool {
    let sagitta_px = spline::chord_sagitta_px(points_px);
    radius_px > 0.0
        && sagitta_px < EDGE_MAX_SAGITTA_PX
        && (sagitta_px < EDGE_NOISE_SAGITTA_PX
            || spline::arc_radius_px(length_px, sagitta_px) > radius_px)
}

/// On a background plain around each pixel, a straight detection is a
/// cable, not an edge, when the background's colours either side of it
/// differ by less than this share of the smaller difference between the
/// detection and either side. An edge's sides differ: the paper and table
/// edges taken for cables in cables-dev's photographs (on busy
/// backgrounds) score 1.0 and 1.25. A cable's do not: about as many
/// rendered straight detections are kept at any share from 0.3 to 1.5
/// (docs/vision.md, "Straight cables on a plain table").
const EDGE_SIDES_RATIO: f64 = 0.5;
/// Where each side's background is read, in cable widths from the
/// detection's centre line: clear of the cable and its shading.
const SIDE_OFFSETS_WIDTHS: [f64; 2] = [1.0, 1.5];

/// Whether a straight detection (points along it, cables `width_px`
/// wide) is a cable, not an edge: the BGR `image`'s background is alike
/// on the detection's two sides and plain around each pixel
/// ([`mask::plain_locally`], the dearer test, asked second and kept in
/// `plain_around` for the image once asked). Not when the image's colour
/// is unknown.
fn straight_cable(
    image: &Mat,
    mask: &Mat,
    points_px: &[[f64; 2]],
    width_px: f64,
    plain_around: &mut Option<bool>,
) -> Result<bool, VisionError> {
    if image.channels() != 3 {
        return Ok(false);
    }
    if !sides_alike(image, mask, points_px, width_px)? {
        return Ok(false);
    }
    match *plain_around {
        Some(plain) => Ok(plain),
        None => Ok(*plain_around.insert(mask::plain_locally(image)?)),
    }
}

/// Whether the BGR `image`'s background, off `mask`, is alike on the two
/// sides of a detection (points along it, cables `width_px` wide; see
/// [`EDGE_SIDES_RATIO`]). Not when a side is unknown.
fn sides_alike(
    image: &Mat,
    mask: &Mat,
    points_px: &[[f64; 2]],
    width_px: f64,
) -> Result<bool, VisionError> {
    let in_image = |p: &[f64; 2]| {
        (0.0..f64::from(image.cols())).contains(&p[0].round())
            && (0.0..f64::from(image.rows())).contains(&p[1].round())
    };
    let in_background = |p: [f64; 2]| {
        in_image(&p)
            && mask
                .at_2d::<u8>(p[1].round() as i32, p[0].round() as i32)
                .is_ok_and(|&v| v == 0)
    };
    let mut sides = [Vec::new(), Vec::new()];
    for w in points_px.windows(3) {
        let Some(along) = paths::unit(w[0], w[2]) else {
            continue;
        };
        let across = [-along[1], along[0]];
        for offset in SIDE_OFFSETS_WIDTHS.map(|k| k * width_px) {
            for (side, sign) in sides.iter_mut().zip([1.0, -1.0]) {
                let p = [
                    w[1][0] + sign * offset * across[0],
                    w[1][1] + sign * offset * across[1],
                ];
                if in_background(p) {
                    side.push(p);
                }
            }
        }
    }
    let on_image: Vec<[f64; 2]> = points_px.iter().copied().filter(in_image).collect();
    let [left, right] = &sides;
    let colours = (
        paths::median_colour_lab(image, left)?,
        paths::median_colour_lab(image, right)?,
        paths::median_colour_lab(image, &on_image)?,
    );
    let (Some(left), Some(right), Some(middle)) = colours else {
        return Ok(false);
    };
    let to_middle = paths::delta_e(middle, left).min(paths::delta_e(middle, right));
    Ok(paths::delta_e(left, right) < EDGE_SIDES_RATIO * to_middle)
}

/// The pixels of `mask` within `thickness` of the path.
fn path_mask(mask: &Mat, points_px: &[[f64; 2]], thickness: i32) -> Result<Mat, VisionError> {
    let drawn = draw_paths(mask.rows(), mask.cols(), &[points_px], thickness)?;
    let mut own = Mat::default();
    core::bitwise_and(&drawn, mask, &mut own, &core::no_array()).map_err(cv("instance mask"))?;
    Ok(own)
}

/// A `rows` × `cols` 0/255 mask of `paths` drawn `thickness` px wide
/// (points rounded to whole pixels).
pub(crate) fn draw_paths(
    rows: i32,
    cols: i32,
    paths: &[&[[f64; 2]]],
    thickness: i32,
) -> Result<Mat, VisionError> {
    let mut drawn = mask::zeros_u8(rows, cols)?;
    let curves: Vector<Vector<Point>> = paths
        .iter()
        .map(|path| {
            path.iter()
                .map(|p| Point::new(p[0].round() as i32, p[1].round() as i32))
                .collect()
        })
        .collect();
    imgproc::polylines(
        &mut drawn,
        &curves,
        false,
        Scalar::all(255.0),
        thickness,
        imgproc::LINE_8,
        0,
    )
    .map_err(cv("draw paths"))?;
    Ok(drawn)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::vision::test_curves::arc_px;

    #[test]
    fn a_cable_mask_resized_in_a_box_around_it_is_the_whole_resize() {
        // The box is resized alone, so its pixels must be those of the
        // whole working mask resized: at whole multiples, at ratios such as
        // 480 : 2048 whose box sides must fall on whole image pixels, at
        // none (640 : 641, the whole mask), shrunk, and inside a region of
        // interest; for cables reaching the working mask's edges and
        // corner, a lone pixel and no cable.
        let cables: [&[[f64; 2]]; 3] = [
            &[[0.0, 5.0], [200.0, 90.0], [350.0, 300.0]],
            &[[639.0, 479.0], [600.0, 440.0]],
            &[[410.0, 30.0], [410.0, 30.0]],
        ];
        let mut owns: Vec<Mat> = cables
            .iter()
            .map(|&c| draw_paths(480, 640, &[c], 7).unwrap())
            .collect();
        owns.push(draw_paths(480, 640, &[&[[77.0, 99.0]]], 1).unwrap());
        owns.push(mask::zeros_u8(480, 640).unwrap());
        for (cols, rows) in [
            (1920, 1440),
            (2448, 2048),
            (641, 481),
            (320, 240),
            (1000, 750),
        ] {
            for (roi, full) in [
                (Rect::new(0, 0, cols, rows), Rect::new(0, 0, cols, rows)),
                (
                    Rect::new(7, 3, cols, rows),
                    Rect::new(0, 0, cols + 20, rows + 9),
                ),
            ] {
                for own in &owns {
                    let whole = mask::resize_and_cut(own, roi.size(), 127.0).unwrap();
                    let mut expected = mask::zeros_u8(full.height, full.width).unwrap();
                    whole
                        .copy_to(&mut Mat::roi_mut(&mut expected, roi).unwrap())
                        .unwrap();
                    let boxed = mask_in_image(own, roi, full).unwrap();
                    let mut differ = Mat::default();
                    core::compare(&boxed, &expected, &mut differ, core::CMP_NE).unwrap();
                    assert_eq!(
                        core::count_non_zero(&differ).unwrap(),
                        0,
                        "{cols} x {rows} in {full:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn an_edge_bends_less_than_the_radius_or_no_more_than_mask_noise() {
        use std::f64::consts::FRAC_PI_2;
        // A piece of a circle, `length_px` long, as points.
        let piece = |length_px: f64, radius_px: f64| {
            let half_rad = length_px / radius_px / 2.0;
            let points = arc_px(
                [0.0, radius_px],
                radius_px,
                -FRAC_PI_2 - half_rad,
                -FRAC_PI_2 + half_rad,
            );
            (points, length_px)
        };
        let edge = |(points, length_px): (Vec<[f64; 2]>, f64), radius_px| {
            looks_like_edge(&points, length_px, radius_px)
        };
        // 300 px, 2.25 px from straight: a paper edge, unless kept.
        assert!(edge(piece(300.0, 5000.0), 1500.0));
        assert!(!edge(piece(300.0, 5000.0), 0.0));
        // 300 px, 11 px from straight: a cable.
        assert!(!edge(piece(300.0, 1000.0), 1500.0));
        // 70 px, 1.2 px from straight (a 500 px arc): too short for its bend
        // to tell it from an edge's noisy detection.
        assert!(edge(piece(70.0, 500.0), 1500.0));
        // 110 px, 2.5 px from straight: a piece of cable.
        assert!(!edge(piece(110.0, 600.0), 1500.0));
    }
}
