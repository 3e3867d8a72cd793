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
    use crate::perception::vision::eval::distance_to_polylines;
    use crate::sim::render::fixtures::{
        arc_px, demo_scene, draw_scene, matte_cable, midpoint_px, segment_px,
    };
    use crate::sim::render::{Background, CableSpec, RenderedScene};

    /// A matte cable 8 px across.
    fn cable(centerline_px: Vec<[f64; 2]>, bgr: [u8; 3]) -> CableSpec {
        matte_cable(centerline_px, 8.0, bgr)
    }

    /// `cables` on a plain light gray 640 × 480 table, without noise.
    fn on_gray_table(cables: Vec<CableSpec>) -> RenderedScene {
        draw_scene(
            480,
            640,
            Background::Plain { bgr: [210; 3] },
            0.0,
            cables,
            0,
        )
        .unwrap()
    }

    /// The defaults, but straight detections kept: most cables here are
    /// straight segments.
    fn keep_straight() -> VisionConfig {
        VisionConfig {
            straight_edge_radius_px: 0.0,
            ..VisionConfig::default()
        }
    }

    fn detect(image: &Mat, config: VisionConfig) -> VisionOutput {
        Pipeline::new(config).detect(image, None).expect("detect")
    }

    /// Each drawn cable is followed by its own instance: the instance whose
    /// samples lie nearest the curve, all within `tol_px` of it.
    fn assert_each_followed(out: &VisionOutput, curves: &[Vec<[f64; 2]>], tol_px: f64) {
        if let Err(why) = each_followed(out, curves, tol_px) {
            panic!("{why}");
        }
    }

    /// Whether each drawn cable is followed by its own instance (see
    /// [`assert_each_followed`]), or why not.
    fn each_followed(
        out: &VisionOutput,
        curves: &[Vec<[f64; 2]>],
        tol_px: f64,
    ) -> Result<(), String> {
        let ends: Vec<([f64; 2], [f64; 2])> = out
            .cables
            .iter()
            .map(|c| (c.spline.point(0.0), c.spline.point(1.0)))
            .collect();
        if out.cables.len() != curves.len() {
            return Err(format!(
                "{} instances for {} curves, from-to: {ends:.0?}",
                out.cables.len(),
                curves.len()
            ));
        }
        let mut used = vec![false; out.cables.len()];
        for curve in curves {
            let own = [curve.clone()];
            let (best, worst) = out
                .cables
                .iter()
                .enumerate()
                .map(|(i, c)| {
                    let worst = c
                        .samples_px
                        .iter()
                        .map(|&p| distance_to_polylines(p, &own))
                        .fold(0.0, f64::max);
                    (i, worst)
                })
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .expect("an instance");
            if worst >= tol_px {
                return Err(format!("curve followed only within {worst:.1} px"));
            }
            if used[best] {
                return Err("two curves matched one instance".into());
            }
            used[best] = true;
        }
        Ok(())
    }

    fn angle_diff_rad(a: f64, b: f64) -> f64 {
        let d = (a - b).rem_euclid(std::f64::consts::TAU);
        d.min(std::f64::consts::TAU - d)
    }

    #[test]
    fn one_cable_gives_its_midpoint_and_direction() {
        let curve = arc_px([320.0, 600.0], 400.0, -2.2, -0.9);
        let scene = draw_scene(
            480,
            640,
            Background::Plain { bgr: [220; 3] },
            0.0,
            vec![cable(curve.clone(), [30; 3])],
            1,
        )
        .unwrap();
        let out = detect(&scene.bgr, keep_straight());
        assert!(out.plain_background);
        assert_eq!(out.mask_used, MaskMethod::Classical);
        assert_each_followed(&out, std::slice::from_ref(&curve), 2.0);
        let c = &out.cables[0];
        let mid = midpoint_px(&curve).unwrap();
        let err = (c.grasp_px[0] - mid[0]).hypot(c.grasp_px[1] - mid[1]);
        assert!(err < 4.0, "grasp {:?} vs midpoint {mid:?}", c.grasp_px);
        // The arc's tangent at its middle (angle -1.55 rad on the circle),
        // going from the left end (s = 0) to the right.
        let expected = -1.55 + std::f64::consts::FRAC_PI_2;
        assert!(
            angle_diff_rad(c.direction_rad, expected) < 3f64.to_radians(),
            "direction {} vs {expected}",
            c.direction_rad
        );
        let names: Vec<&str> = out.timings_ms.iter().map(|t| t.0).collect();
        assert_eq!(
            names,
            ["prepare", "mask", "instances", "spline", "instance_masks"]
        );
    }

    #[test]
    fn two_crossing_cables_are_followed_through_the_crossing() {
        let a = segment_px([60.0, 100.0], [580.0, 380.0]);
        let b = arc_px([330.0, 560.0], 380.0, -2.4, -0.7);
        let scene = draw_scene(
            480,
            640,
            Background::Plain { bgr: [200; 3] },
            0.0,
            vec![
                cable(a.clone(), [40, 40, 160]),
                cable(b.clone(), [30, 30, 30]),
            ],
            2,
        )
        .unwrap();
        let out = detect(&scene.bgr, keep_straight());
        assert_each_followed(&out, &[a, b], 3.0);
        for c in &out.cables {
            let own = c.mask.as_ref().unwrap();
            assert_eq!(own.size().unwrap(), scene.bgr.size().unwrap());
            assert!(core::count_non_zero(own).unwrap() > 1000);
        }
        // Without the masks, the same grasp frames.
        let bare = detect(
            &scene.bgr,
            VisionConfig {
                cable_masks: false,
                ..keep_straight()
            },
        );
        assert!(bare.union_mask.is_none());
        assert!(
            bare.timings_ms
                .iter()
                .all(|(stage, _)| *stage != "instance_masks")
        );
        assert_eq!(bare.cables.len(), out.cables.len());
        for (b, c) in bare.cables.iter().zip(&out.cables) {
            assert!(b.mask.is_none());
            assert_eq!((b.grasp_px, b.direction_rad), (c.grasp_px, c.direction_rad));
        }
    }

    #[test]
    fn three_cables_with_three_crossings_on_a_noisy_table() {
        let scene = demo_scene(3).unwrap();
        let out = detect(&scene.bgr, keep_straight());
        assert!(out.plain_background, "{:?}", out.background);
        assert_each_followed(&out, &scene.centerlines_px, 3.0);
    }

    #[test]
    fn shallow_crossing_is_resolved() {
        let a = segment_px([40.0, 200.0], [600.0, 260.0]);
        let b = segment_px([40.0, 290.0], [600.0, 170.0]);
        let scene = draw_scene(
            480,
            640,
            Background::Plain { bgr: [230; 3] },
            0.0,
            vec![cable(a.clone(), [20; 3]), cable(b.clone(), [90, 30, 30])],
            4,
        )
        .unwrap();
        let out = detect(&scene.bgr, keep_straight());
        assert_each_followed(&out, &[a, b], 3.0);
    }

    /// Points a pixel apart along a curve through `through_px` with heading
    /// `heading_rad` there, turning by `turn_rad_per_px` per pixel,
    /// `half_length_px` either way.
    fn curve_through(
        through_px: [f64; 2],
        heading_rad: f64,
        turn_rad_per_px: f64,
        half_length_px: usize,
    ) -> Vec<[f64; 2]> {
        let walk = |sign: f64| {
            let (mut p, mut heading) = (through_px, heading_rad);
            let mut points = Vec::new();
            for _ in 0..half_length_px {
                p = [p[0] + sign * heading.cos(), p[1] + sign * heading.sin()];
                heading += sign * turn_rad_per_px;
                points.push(p);
            }
            points
        };
        let mut back = walk(-1.0);
        back.reverse();
        back.push(through_px);
        back.extend(walk(1.0));
        back
    }

    /// Two 10 px cables crossing at the image's centre: one heading
    /// `steep_rad` there and bending at `steep_radius_px`, the other
    /// `crossing_rad` from it and bending at `other_radius_px` (negative:
    /// the other way). Whether each is followed through the crossing.
    fn bending_crossing_followed(
        steep_rad: f64,
        steep_radius_px: f64,
        crossing_rad: f64,
        other_radius_px: f64,
    ) -> Result<(), String> {
        let centre = [320.0, 240.0];
        let steep = curve_through(centre, steep_rad, -1.0 / steep_radius_px, 140);
        let other = curve_through(
            centre,
            steep_rad + crossing_rad,
            -1.0 / other_radius_px,
            200,
        );
        let scene = draw_scene(
            480,
            640,
            Background::Plain { bgr: [220; 3] },
            0.0,
            vec![
                matte_cable(steep.clone(), 10.0, [20; 3]),
                matte_cable(other.clone(), 10.0, [150, 60, 40]),
            ],
            4,
        )
        .unwrap();
        let out = detect(&scene.bgr, VisionConfig::default());
        each_followed(&out, &[steep, other], 3.0).map_err(|why| {
            format!(
                "crossing {crossing_rad} rad, steep {steep_rad} rad at {steep_radius_px} px, other at {other_radius_px} px: {why}"
            )
        })
    }

    fn assert_bending_crossing_resolved(
        steep_rad: f64,
        steep_radius_px: f64,
        crossing_rad: f64,
        other_radius_px: f64,
    ) {
        if let Err(why) =
            bending_crossing_followed(steep_rad, steep_radius_px, crossing_rad, other_radius_px)
        {
            panic!("{why}");
        }
    }

    #[test]
    fn cables_bending_through_a_shallow_crossing_keep_to_themselves() {
        // Both bend the same way through the crossing, as cables lying
        // loose do. At 29°, radii 150 and 250 px: the skeleton between the
        // crossing's two junctions runs between the cables, far from the
        // sharper one's direction beyond. At 29°, radii 110 and 250 px:
        // the sharper cable's branch points, a width out, more towards the
        // other cable's far branch than its own, unless followed back
        // along its curve.
        assert_bending_crossing_resolved(-0.9, 150.0, 0.5, 250.0);
        assert_bending_crossing_resolved(-1.0, 110.0, 0.5, 250.0);
        // Bending opposite ways at 29° and 20°: the crossing's junctions lie
        // apart along the cables, and the branches are compared only once
        // each is followed along its curve to the crossing's centre.
        assert_bending_crossing_resolved(-0.9, 90.0, 0.5, -180.0);
        assert_bending_crossing_resolved(-1.3, 110.0, 0.35, -250.0);
        // At 29°, radii 110 and 250 px bending opposite ways, the junctions
        // lie 8.6 widths apart, and the steep cable's path, bridged between
        // them, was two pieces when the limit was 8 widths.
        assert_bending_crossing_resolved(-0.9, 110.0, 0.5, -250.0);
    }

    #[test]
    fn crossings_between_cables_bending_opposite_ways_are_mostly_resolved() {
        // 90 crossings, 20° to 63°, the steeper cable as below, the other
        // bending the other way at 180 or 250 px. 82 are resolved; by
        // bending alone, 81; before paths were bridged across crossings and
        // junctions up to 10 widths apart merged, 62. The others are
        // ambiguous to the eye too: the cables run over each other for
        // several widths, and the paths cross inside that stretch.
        let mut failures = Vec::new();
        for crossing_rad in [0.35, 0.5, 0.7, 0.9, 1.1] {
            for steep_rad in [-0.9, -1.1, -1.3] {
                for steep_radius_px in [90.0, 110.0, 150.0] {
                    for other_radius_px in [-180.0, -250.0] {
                        if let Err(why) = bending_crossing_followed(
                            steep_rad,
                            steep_radius_px,
                            crossing_rad,
                            other_radius_px,
                        ) {
                            failures.push(why);
                        }
                    }
                }
            }
        }
        assert!(failures.len() <= 8, "{:#?}", failures);
    }

    #[test]
    fn every_crossing_of_forty_degrees_or_more_between_bending_cables_is_resolved() {
        // 54 crossings: 40°, 52° and 63°; the steeper cable at three
        // headings and bending at radii of 90 to 150 px, the other bending
        // the same way at 180 or 250 px. At 20° and 29°, 19 of 36 such
        // crossings are resolved: the sharper cable curls along the other
        // for several widths.
        for crossing_rad in [0.7, 0.9, 1.1] {
            for steep_rad in [-0.9, -1.1, -1.3] {
                for steep_radius_px in [90.0, 110.0, 150.0] {
                    for other_radius_px in [180.0, 250.0] {
                        assert_bending_crossing_resolved(
                            steep_rad,
                            steep_radius_px,
                            crossing_rad,
                            other_radius_px,
                        );
                    }
                }
            }
        }
    }

    /// A cable that loops across itself, centred in a 640 × 480 image: it
    /// comes in straight heading `heading_rad`, turns left at `radius_px`
    /// through a full turn less `crossing_rad`, and leaves straight, its
    /// two straight stretches crossing at `crossing_rad`, `lead_px` before
    /// and after the crossing.
    fn lasso(heading_rad: f64, crossing_rad: f64, radius_px: f64, lead_px: f64) -> Vec<[f64; 2]> {
        let to_tangent_px = radius_px / (crossing_rad / 2.0).tan();
        let straight_px = (lead_px + to_tangent_px).round() as usize;
        let turn_rad = std::f64::consts::TAU - crossing_rad;
        let arc_px = (turn_rad * radius_px).round() as usize;
        let (mut p, mut heading) = ([0.0, 0.0], heading_rad);
        let mut points = vec![p];
        for i in 0..2 * straight_px + arc_px {
            if (straight_px..straight_px + arc_px).contains(&i) {
                heading -= turn_rad / arc_px as f64;
            }
            p = [p[0] + heading.cos(), p[1] + heading.sin()];
            points.push(p);
        }
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        for p in &points {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let shift = [320.0 - (lo[0] + hi[0]) / 2.0, 240.0 - (lo[1] + hi[1]) / 2.0];
        points
            .iter()
            .map(|p| [p[0] + shift[0], p[1] + shift[1]])
            .collect()
    }

    #[test]
    fn a_cable_looping_across_itself_is_one_cable() {
        // 10 px cables, each looping across itself once: the loop 4 to 8
        // widths in radius, its two strands crossing at 15° to 120°, in
        // four orientations; 55 such loops fit the image. Before a loop's
        // two ends were kept from being paired, 6 of them were found as the
        // loop and the rest of the cable, all where the strands cross at
        // 20° to 45° and thin into two junctions. (At 3 widths, 3 of 25 are
        // still not followed; before, 15.)
        let mut tried = 0;
        for crossing_deg in [15.0f64, 20.0, 30.0, 45.0, 60.0, 90.0, 120.0] {
            for radius_px in [40.0, 60.0, 80.0] {
                for heading_deg in [0.0f64, 30.0, -60.0, 160.0] {
                    let crossing_rad = crossing_deg.to_radians();
                    let curve = lasso(heading_deg.to_radians(), crossing_rad, radius_px, 120.0);
                    let inside = curve
                        .iter()
                        .all(|p| (15.0..625.0).contains(&p[0]) && (15.0..465.0).contains(&p[1]));
                    if !inside {
                        continue;
                    }
                    tried += 1;
                    let scene = draw_scene(
                        480,
                        640,
                        Background::Plain { bgr: [220; 3] },
                        0.0,
                        vec![matte_cable(curve.clone(), 10.0, [30; 3])],
                        4,
                    )
                    .unwrap();
                    let out = detect(&scene.bgr, keep_straight());
                    if let Err(why) = each_followed(&out, std::slice::from_ref(&curve), 3.0) {
                        panic!("{crossing_deg}° at {radius_px} px, heading {heading_deg}°: {why}");
                    }
                }
            }
        }
        assert_eq!(tried, 55);
    }

    #[test]
    fn cables_touching_side_by_side_keep_to_their_own_colour() {
        // Two 10 px cables come together, touch side by side for 60 or
        // 100 px, and part the way they came. Their shape alone reads as a
        // shallow crossing: bending least pairs each with the other's far
        // branch. Their colours tell them apart. Along the stretch they
        // share, one skeleton runs between them, 5 px from each.
        let polyline = |corners: &[[f64; 2]]| {
            let mut points = segment_px(corners[0], corners[1]);
            for w in corners[1..].windows(2) {
                points.extend(segment_px(w[0], w[1]).into_iter().skip(1));
            }
            points
        };
        for (run_px, part_px) in [(60.0, 100.0), (100.0, 60.0), (100.0, 100.0)] {
            let (x0, x1) = (320.0 - run_px / 2.0, 320.0 + run_px / 2.0);
            let upper = polyline(&[
                [40.0, 235.0 - part_px],
                [x0, 235.0],
                [x1, 235.0],
                [600.0, 235.0 - part_px],
            ]);
            let lower = polyline(&[
                [40.0, 245.0 + part_px],
                [x0, 245.0],
                [x1, 245.0],
                [600.0, 245.0 + part_px],
            ]);
            for (upper_bgr, lower_bgr) in [([20; 3], [150, 60, 40]), ([30, 30, 200], [40, 200, 40])]
            {
                let scene = on_gray_table(vec![
                    matte_cable(upper.clone(), 10.0, upper_bgr),
                    matte_cable(lower.clone(), 10.0, lower_bgr),
                ]);
                let out = detect(&scene.bgr, keep_straight());
                if let Err(why) = each_followed(&out, &[upper.clone(), lower.clone()], 10.0) {
                    panic!("touching for {run_px} px, {upper_bgr:?} over {lower_bgr:?}: {why}");
                }
            }
        }
    }

    #[test]
    fn no_cable_is_an_empty_result() {
        for (gray, noise_sigma) in [(128, 0.0), (180, 6.0)] {
            let background = Background::Plain { bgr: [gray; 3] };
            let scene = draw_scene(480, 640, background, noise_sigma, Vec::new(), 5).unwrap();
            let out = detect(&scene.bgr, keep_straight());
            assert!(
                out.cables.is_empty(),
                "gray {gray}, noise {noise_sigma}: {} cables",
                out.cables.len()
            );
        }
    }

    #[test]
    fn degenerate_images_do_not_panic() {
        let mut cases: Vec<(&str, Mat)> = Vec::new();
        for (name, rows, cols, typ, v) in [
            ("1x1", 1, 1, core::CV_8UC3, 0.0),
            ("1 row", 1, 640, core::CV_8UC3, 90.0),
            ("black", 480, 640, core::CV_8UC3, 0.0),
            ("white", 480, 640, core::CV_8UC3, 255.0),
            ("gray", 48, 64, core::CV_8UC1, 77.0),
            ("bgra", 48, 64, core::CV_8UC4, 77.0),
            ("16-bit", 48, 64, core::CV_16UC3, 30000.0),
            ("large", 2000, 3000, core::CV_8UC3, 200.0),
        ] {
            cases.push((
                name,
                Mat::new_rows_cols_with_default(rows, cols, typ, Scalar::all(v)).unwrap(),
            ));
        }
        let mut noise =
            Mat::new_rows_cols_with_default(120, 160, core::CV_8UC3, Scalar::all(0.0)).unwrap();
        core::randu(&mut noise, &Scalar::all(0.0), &Scalar::all(255.0)).unwrap();
        cases.push(("noise", noise));
        let mut stripes =
            Mat::new_rows_cols_with_default(100, 100, core::CV_8UC3, Scalar::all(0.0)).unwrap();
        for x in (0..100).step_by(2) {
            imgproc::line(
                &mut stripes,
                Point::new(x, 0),
                Point::new(x, 99),
                Scalar::all(255.0),
                1,
                imgproc::LINE_8,
                0,
            )
            .unwrap();
        }
        cases.push(("1-px stripes", stripes));
        for (name, image) in cases {
            for instances in [InstanceMethod::Skeleton, InstanceMethod::Superpixels] {
                let config = VisionConfig {
                    instances,
                    ..keep_straight()
                };
                let out = Pipeline::new(config).detect(&image, None);
                assert!(out.is_ok(), "{name}: {out:?}");
            }
        }
        let mut p = Pipeline::new(keep_straight());
        assert!(matches!(
            p.detect(&Mat::default(), None),
            Err(VisionError::EmptyImage { .. })
        ));
        let float =
            Mat::new_rows_cols_with_default(4, 4, core::CV_32FC3, Scalar::all(0.0)).unwrap();
        assert!(matches!(
            p.detect(&float, None),
            Err(VisionError::UnsupportedImage { .. })
        ));
    }

    #[test]
    fn region_of_interest_bounds_the_work_and_maps_back() {
        let inside = segment_px([300.0, 240.0], [560.0, 300.0]);
        let outside = segment_px([20.0, 40.0], [250.0, 60.0]);
        let scene = on_gray_table(vec![
            cable(inside.clone(), [20; 3]),
            cable(outside, [20; 3]),
        ]);
        let roi = Rect::new(280, 200, 320, 160);
        let out = detect(
            &scene.bgr,
            VisionConfig {
                roi_px: Some(roi),
                ..keep_straight()
            },
        );
        assert_each_followed(&out, std::slice::from_ref(&inside), 2.5);
        let mid = midpoint_px(&inside).unwrap();
        let g = out.cables[0].grasp_px;
        assert!(
            (g[0] - mid[0]).hypot(g[1] - mid[1]) < 4.0,
            "{g:?} vs {mid:?}"
        );
        let union_mask = out.union_mask.as_ref().unwrap();
        assert_eq!(union_mask.size().unwrap(), scene.bgr.size().unwrap());
        assert_eq!(*union_mask.at_2d::<u8>(50, 100).unwrap(), 0);
        let off = VisionConfig {
            roi_px: Some(Rect::new(700, 500, 10, 10)),
            ..keep_straight()
        };
        assert!(matches!(
            Pipeline::new(off).detect(&scene.bgr, None),
            Err(VisionError::RoiOutside { .. })
        ));
    }

    #[test]
    fn finer_and_coarser_cameras_are_worked_on_at_the_working_width_and_mapped_back() {
        // The crossing scene of 640 × 480, and the same drawn `k` times as
        // fine (3) or as coarse (0.5).
        let a = segment_px([60.0, 100.0], [580.0, 380.0]);
        let b = arc_px([330.0, 560.0], 380.0, -2.4, -0.7);
        let scene = |k: f64| {
            let cables = [(&a, [40, 40, 160]), (&b, [30, 30, 30])].map(|(c, bgr)| {
                matte_cable(c.iter().map(|&p| at_scale(p, k)).collect(), 8.0 * k, bgr)
            });
            let size = |side: f64| (side * k) as i32;
            draw_scene(
                size(480.0),
                size(640.0),
                Background::Plain { bgr: [200; 3] },
                0.0,
                cables.to_vec(),
                2,
            )
            .unwrap()
        };
        let working = scene(1.0);
        let at_640 = detect(&working.bgr, keep_straight());
        assert_eq!(at_640.work_scale, 1.0);
        let roi = Rect::new(280, 200, 320, 160);
        let bounded = |image: &Mat, roi: Rect| {
            let config = VisionConfig {
                roi_px: Some(roi),
                ..keep_straight()
            };
            detect(image, config)
        };
        let at_640_in_roi = bounded(&working.bgr, roi);
        assert!(!at_640_in_roi.cables.is_empty());

        for k in [3.0, 0.5] {
            let image = scene(k).bgr;
            let out = detect(&image, keep_straight());
            assert!(
                (out.work_scale - 1.0 / k).abs() < 1e-9,
                "{}",
                out.work_scale
            );
            let curves = [&a, &b].map(|c| c.iter().map(|&p| at_scale(p, k)).collect::<Vec<_>>());
            assert_each_followed(&out, &curves, 2.0 * k);
            assert_found_alike(&out, &at_640, k);
            assert!((out.cable_width_px / at_640.cable_width_px - k).abs() < 0.05 * k);
            for (found, working) in out.cables.iter().zip(&at_640.cables) {
                let (found, working) = (found.mask.as_ref(), working.mask.as_ref());
                let (found, working) = (found.unwrap(), working.unwrap());
                assert_eq!(found.size().unwrap(), image.size().unwrap());
                let area_ratio = f64::from(core::count_non_zero(found).unwrap())
                    / f64::from(core::count_non_zero(working).unwrap());
                assert!(
                    (area_ratio / (k * k) - 1.0).abs() < 0.12,
                    "mask area ratio {area_ratio} at {k}"
                );
            }
            // A region of interest is given in the image's pixels.
            let scaled = |v: i32| (f64::from(v) * k) as i32;
            let roi_k = Rect::new(
                scaled(roi.x),
                scaled(roi.y),
                scaled(roi.width),
                scaled(roi.height),
            );
            assert_found_alike(&bounded(&image, roi_k), &at_640_in_roi, k);
        }
    }

    /// Point `p` of a 640 px wide image in the same image drawn `k` times
    /// as fine: pixel centres lie at whole coordinates in both.
    fn at_scale(p: [f64; 2], k: f64) -> [f64; 2] {
        p.map(|v| k * v + (k - 1.0) / 2.0)
    }

    /// `found`, in an image `k` times as fine as 640 px wide, is what
    /// `working` found at 640 px wide, in that image's pixels.
    fn assert_found_alike(found: &VisionOutput, working: &VisionOutput, k: f64) {
        assert_eq!(found.cables.len(), working.cables.len());
        for (f, w) in found.cables.iter().zip(&working.cables) {
            let [x, y] = at_scale(w.grasp_px, k);
            let off_px = (f.grasp_px[0] - x).hypot(f.grasp_px[1] - y);
            // Within a fifth of a working pixel; a coarser image holds less
            // than the working one, within half its own pixel.
            let tolerance_px = if k > 1.0 { 0.2 * k } else { 0.5 };
            assert!(
                off_px < tolerance_px,
                "{:?} vs {:?} at {k}",
                f.grasp_px,
                [x, y]
            );
            assert!(angle_diff_rad(f.direction_rad, w.direction_rad) < 0.01);
            assert!((f.length_px / w.length_px / k - 1.0).abs() < 0.02);
        }
    }

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
    fn a_short_cable_running_out_of_view_is_dropped_a_short_loose_one_kept() {
        // Both 60 px long: one enters from the left border, one lies loose.
        let at_border = segment_px([0.0, 100.0], [60.0, 100.0]);
        let loose = segment_px([300.0, 300.0], [360.0, 300.0]);
        let scene = on_gray_table(vec![
            cable(at_border, [20; 3]),
            cable(loose.clone(), [20; 3]),
        ]);
        let keep_all = VisionConfig {
            min_border_cable_length_px: 0.0,
            ..keep_straight()
        };
        let all = detect(&scene.bgr, keep_all);
        assert_eq!(all.cables.len(), 2);
        assert!(all.notes.is_empty(), "{:?}", all.notes);
        let out = detect(
            &scene.bgr,
            VisionConfig {
                min_border_cable_length_px: 80.0,
                ..keep_straight()
            },
        );
        assert_each_followed(&out, std::slice::from_ref(&loose), 2.5);
        // And says so.
        assert_eq!(
            out.notes,
            [
                "dropped 1 cable(s) that run out of view shorter than 80 px: too little of them is in view to grasp (a minimum border length of 0 keeps them)"
            ]
        );
    }

    #[test]
    fn a_band_along_the_border_is_not_taken_for_cable() {
        // Two cables converge on the right border at about 20° and reach
        // it about 50 px apart; a dark band along the border (a shadow at
        // the frame's edge) continues one into the other. Each cable ends
        // where it leaves the view, without a hook along the band. (Each
        // turns onto the band by about 64°, so the corner cut parts them
        // as well as the border cut; the skeleton's unit tests check the
        // border cut alone.)
        let upper = curve_through([560.0, 170.0], 0.45, -1.0 / 1000.0, 150);
        let lower = curve_through([560.0, 290.0], -0.45, 1.0 / 1000.0, 150);
        let in_view = |curve: &[[f64; 2]]| -> Vec<[f64; 2]> {
            curve.iter().copied().take_while(|p| p[0] < 637.0).collect()
        };
        let (upper, lower) = (in_view(&upper), in_view(&lower));
        let (upper_end, lower_end) = (*upper.last().unwrap(), *lower.last().unwrap());
        assert!((30.0..60.0).contains(&(lower_end[1] - upper_end[1])));
        let mut joined = upper.clone();
        joined.extend(segment_px([637.0, upper_end[1]], [637.0, lower_end[1]]));
        joined.extend(lower.iter().rev());
        // Corners rounded, as the mask's are: a moving average over 21 px.
        let rounded: Vec<[f64; 2]> = (0..joined.len())
            .map(|i| {
                let near = &joined[i.saturating_sub(10)..(i + 11).min(joined.len())];
                let n = near.len() as f64;
                [
                    near.iter().map(|p| p[0]).sum::<f64>() / n,
                    near.iter().map(|p| p[1]).sum::<f64>() / n,
                ]
            })
            .collect();
        let scene = on_gray_table(vec![cable(rounded, [30; 3])]);
        let out = detect(&scene.bgr, VisionConfig::default());
        assert_each_followed(&out, &[upper, lower], 3.0);
    }

    #[test]
    fn two_cables_meeting_end_to_end_at_an_angle_are_two() {
        // One cable ends where the other begins, meeting at about 105°
        // (00042 of cables-dev: two wires leaving the view side by side,
        // their masks merged short of the border). The mask is one V.
        let left = curve_through([240.0, 190.0], 0.7, 1.0 / 400.0, 90);
        let apex = *left.last().unwrap();
        let right: Vec<[f64; 2]> = left
            .iter()
            .rev()
            .map(|p| [2.0 * apex[0] - p[0], p[1]])
            .collect();
        let scene = on_gray_table(vec![
            cable(left.clone(), [30; 3]),
            cable(right.clone(), [30; 3]),
        ]);
        let out = detect(&scene.bgr, VisionConfig::default());
        assert_each_followed(&out, &[left, right], 3.0);
    }

    #[test]
    fn a_straight_detection_is_dropped_as_an_edge_unless_its_sides_are_alike() {
        use std::f64::consts::FRAC_PI_2;
        // A ruler-straight 300 px line 30 px from the top; a 110 px piece
        // of cable bent like a 600 px arc (2.5 px from straight); a 420 px
        // cable bowed like a 3000 px arc (7 px from straight).
        let straight = segment_px([100.0, 30.0], [400.0, 30.0]);
        let short_bent = arc_px([450.0, 900.0], 600.0, -FRAC_PI_2 - 0.09, -FRAC_PI_2 + 0.09);
        let long_bowed = arc_px(
            [320.0, 3400.0],
            3000.0,
            -FRAC_PI_2 - 0.07,
            -FRAC_PI_2 + 0.07,
        );
        let lines = [straight, short_bent, long_bowed];

        // Drawn as a cable on an even table, the straight line is a taut
        // cable: the table is alike on its two sides.
        let drawn = on_gray_table(lines.iter().map(|c| cable(c.clone(), [20; 3])).collect());
        let out = detect(&drawn.bgr, VisionConfig::default());
        assert!(out.plain_background, "{:?}", out.background);
        assert_each_followed(&out, &lines, 2.5);
        assert!(out.notes.is_empty(), "{:?}", out.notes);

        // The edge of a white sheet along the straight line, which a
        // network took for a cable: the table differs on its two sides.
        let scene = on_gray_table(
            lines[1..]
                .iter()
                .map(|c| cable(c.clone(), [20; 3]))
                .collect(),
        );
        let mut sheet_edge = scene.bgr.clone();
        Mat::roi_mut(&mut sheet_edge, Rect::new(0, 0, 640, 30))
            .unwrap()
            .set_to_def(&Scalar::all(250.0))
            .unwrap();
        let mut known = scene.union_mask.clone();
        let band = draw_paths(480, 640, &[&lines[0]], 8).unwrap();
        core::bitwise_or_def(&scene.union_mask, &band, &mut known).unwrap();
        let by_network = |image: &Mat, config: VisionConfig| {
            let mut net = KnownMask(known.clone());
            let config = VisionConfig {
                mask: MaskMethod::Network,
                ..config
            };
            Pipeline::new(config).detect(image, Some(&mut net)).unwrap()
        };
        let dropped =
            |out: &VisionOutput| out.notes.iter().any(|n| n.contains("1 straight detection"));
        let out = by_network(&sheet_edge, VisionConfig::default());
        assert!(out.plain_background, "{:?}", out.background);
        assert_each_followed(&out, &lines[1..], 2.5);
        assert!(dropped(&out), "{:?}", out.notes);
        assert_each_followed(&by_network(&sheet_edge, keep_straight()), &lines, 2.5);

        // Under a light that falls off to the corners the table is no
        // longer plain as a whole, but it is around each pixel: the cable
        // is kept and the sheet's edge dropped as before.
        let out = by_network(&falling_off(&drawn.bgr), VisionConfig::default());
        assert!(!out.plain_background, "{:?}", out.background);
        assert_each_followed(&out, &lines, 2.5);
        assert!(!dropped(&out), "{:?}", out.notes);
        let out = by_network(&falling_off(&sheet_edge), VisionConfig::default());
        assert_each_followed(&out, &lines[1..], 2.5);
        assert!(dropped(&out), "{:?}", out.notes);
    }

    /// `image` under a light that falls off from its middle: the corners
    /// at half the brightness.
    fn falling_off(image: &Mat) -> Mat {
        let mut lit = image.clone();
        let (rows, cols) = (lit.rows(), lit.cols());
        for y in 0..rows {
            for x in 0..cols {
                let r = (f64::from(x) / f64::from(cols) - 0.5)
                    .hypot(f64::from(y) / f64::from(rows) - 0.5);
                let gain = 1.0 - r * r;
                let px = lit.at_2d_mut::<core::Vec3b>(y, x).unwrap();
                *px = core::Vec3b::from(px.0.map(|v| (f64::from(v) * gain) as u8));
            }
        }
        lit
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

    /// Stands in for the segmentation network: the mask of the drawn cables.
    struct KnownMask(Mat);

    impl MaskNetwork for KnownMask {
        fn mask(&mut self, _bgr: &Mat) -> Result<Mat, VisionError> {
            self.0.try_clone().map_err(cv("copy known mask"))
        }
    }

    #[test]
    fn a_busy_background_takes_the_network_or_says_it_fell_back() {
        let curve = arc_px([320.0, 560.0], 380.0, -2.3, -0.8);
        let scene = draw_scene(
            480,
            640,
            Background::Wood,
            0.0,
            vec![cable(curve.clone(), [40, 40, 220])],
            7,
        )
        .unwrap();

        let mut net = KnownMask(scene.union_mask.clone());
        let mut auto = Pipeline::new(keep_straight());
        let out = auto.detect(&scene.bgr, Some(&mut net)).unwrap();
        assert!(!out.plain_background, "{:?}", out.background);
        assert_eq!(out.mask_used, MaskMethod::Network);
        assert_each_followed(&out, &[curve], 2.0);

        let out = auto.detect(&scene.bgr, None).unwrap();
        assert_eq!(out.mask_used, MaskMethod::Classical);
        assert!(
            out.notes.iter().any(|n| n.contains("no network")),
            "{:?}",
            out.notes
        );
        // The classical mask is in doubt on wood, but the note that says
        // so is for plain tables.
        assert!(out.background.ambiguous_ratio > mask::MAX_AMBIGUOUS_RATIO);
        assert!(
            !out.notes.iter().any(|n| n.contains("plain background")),
            "{:?}",
            out.notes
        );

        let mut network_only = Pipeline::new(VisionConfig {
            mask: MaskMethod::Network,
            ..keep_straight()
        });
        assert!(matches!(
            network_only.detect(&scene.bgr, None),
            Err(VisionError::NoNetwork)
        ));
    }

    #[test]
    fn a_doubtful_classical_mask_on_a_plain_table_gives_way_to_the_network() {
        let curve = arc_px([320.0, 560.0], 380.0, -2.3, -0.8);
        let scene_with = |bgr: [u8; 3], gloss: f64, diameter_px: f64| {
            let spec = CableSpec {
                centerline_px: curve.clone(),
                diameter_px,
                bgr,
                gloss,
            };
            draw_scene(
                480,
                640,
                Background::Plain { bgr: [200; 3] },
                2.0,
                vec![spec],
                7,
            )
            .unwrap()
        };
        let mut auto = Pipeline::new(keep_straight());
        // A glossy cable a little darker than the table: its highlight is
        // the table's colour, and many pixels lie near the threshold. A
        // thick glossy white one: its shading passes through the table's
        // colour in a thin band, which leaves the mask hollow.
        for (scene, why) in [
            (scene_with([185, 175, 165], 1.0, 10.0), "ambiguous"),
            (scene_with([240; 3], 1.0, 16.0), "hollow"),
        ] {
            let mut net = KnownMask(scene.union_mask.clone());
            let out = auto.detect(&scene.bgr, Some(&mut net)).unwrap();
            assert!(out.plain_background, "{:?}", out.background);
            assert_eq!(out.mask_used, MaskMethod::Network, "{:?}", out.background);
            assert!(out.notes.iter().any(|n| n.contains(why)), "{:?}", out.notes);
            assert_each_followed(&out, std::slice::from_ref(&curve), 2.0);

            // Without a network the classical mask runs, says so, and
            // finds the cable's flanks as two or more cables.
            let out = auto.detect(&scene.bgr, None).unwrap();
            assert_eq!(out.mask_used, MaskMethod::Classical);
            assert!(
                out.notes
                    .iter()
                    .any(|n| n.contains(why) && n.contains("no network"))
            );
            assert!(out.cables.len() >= 2, "{} cables", out.cables.len());
        }

        // A dark matte cable on the same table is cut cleanly: the network
        // is skipped.
        let dark = scene_with([30; 3], 0.0, 10.0);
        let mut net = KnownMask(dark.union_mask.clone());
        let out = auto.detect(&dark.bgr, Some(&mut net)).unwrap();
        assert_eq!(out.mask_used, MaskMethod::Classical, "{:?}", out.notes);
        assert_each_followed(&out, &[curve], 2.0);
    }

    #[test]
    fn superpixel_walks_follow_crossing_cables() {
        let a = segment_px([80.0, 80.0], [560.0, 400.0]);
        let b = segment_px([100.0, 420.0], [540.0, 60.0]);
        // With the simulated camera's sensor noise: without any, the
        // shaded black tube over the red one leaves the walk of the red
        // one split at the crossing, one piece ending on a superpixel
        // centred off its line.
        let scene = draw_scene(
            480,
            640,
            Background::Plain { bgr: [200; 3] },
            2.0,
            vec![
                cable(a.clone(), [40, 40, 160]),
                cable(b.clone(), [30, 30, 30]),
            ],
            8,
        )
        .unwrap();
        let out = detect(
            &scene.bgr,
            VisionConfig {
                instances: InstanceMethod::Superpixels,
                ..keep_straight()
            },
        );
        // Each cable is walked through the crossing from superpixel to
        // superpixel; slivers of superpixels beside a cable are no nodes, so
        // the walk and its spline keep to the cable.
        assert_each_followed(&out, &[a.clone(), b.clone()], 4.0);
        for c in &out.cables {
            let mean = c
                .samples_px
                .iter()
                .map(|&p| distance_to_polylines(p, &[a.clone(), b.clone()]))
                .sum::<f64>()
                / c.samples_px.len() as f64;
            assert!(mean < 1.5, "mean distance {mean:.1} px");
        }
    }
}
