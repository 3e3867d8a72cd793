//! A run of the pipeline: the image prepared (converted, cropped to the
//! region of interest, resized to the working width), its mask chosen,
//! the mask's paths found, cut and filtered, splines fitted, and what
//! was found mapped back to the image's pixels, each stage timed.

use std::borrow::Cow;
use std::time::Instant;

use opencv::core::{self, Mat, Rect};
use opencv::imgproc;
use opencv::prelude::*;

use super::confidence::{self, Belief};
use super::config::{
    BUSY_MIN_LENGTH_FACTOR, InstanceMethod, MaskMethod, PAINTED_MIN_CONFIDENCE_FACTOR,
};
use super::draw::{cable_masks, mask_in_image, union_mask};
use super::mask_choice::{MaskChoice, MaskNetwork, choose_mask};
use super::output::{CableInstance, MaskInstances, VisionOutput, VisionSkip};
use super::straight_edge::{EDGE_NOISE_SAGITTA_PX, looks_like_edge, straight_cable};
use super::work_area::{NetworkView, ToImage, clip_roi, crop, to_work_size, work_scale};
use super::{Pipeline, ms_since};
use crate::perception::vision::error::{VisionError, cv};
use crate::perception::vision::spline::{self, BSpline};
use crate::perception::vision::{mask, paths, skeleton, superpixels};

/// What a mask may hold besides cables that looks like one.
#[derive(Clone, Copy)]
struct LookAlikes {
    /// Paint strokes as long and even as cables (see
    /// [`confidence::strokes_possible`]).
    strokes: bool,
    /// A busy background (paint, prints, mosaics): scraps and splashes of
    /// paint longer than scraps of mask (see
    /// [`VisionConfig::min_cable_length_px`]), and none of the paper and
    /// table edges as straight as a taut cable (see
    /// [`VisionConfig::straight_edge_radius_px`]).
    busy: bool,
    /// A painted background (busy and of many colours): more of what the
    /// network marks there is paint, so a detection must be more
    /// confident (see [`VisionConfig::min_confidence`]), and paint of a
    /// cable's colour cuts its mask for longer (see
    /// [`paths::PAINTED_JOIN_GAP_WIDTHS`]).
    painted: bool,
}

impl LookAlikes {
    /// Whether the mask holds nothing but cables: neither strokes nor a
    /// busy background's scraps.
    fn only_cables(self) -> bool {
        !self.strokes && !self.busy
    }

    /// The confidence below which a detection is dropped, given the
    /// configured floor.
    fn min_confidence(self, configured: f64) -> f64 {
        if self.painted {
            PAINTED_MIN_CONFIDENCE_FACTOR * configured
        } else {
            configured
        }
    }

    /// Across how many cable widths pieces that continue each other are
    /// joined.
    fn join_gap_widths(self) -> f64 {
        if self.painted {
            paths::PAINTED_JOIN_GAP_WIDTHS
        } else {
            paths::JOIN_GAP_WIDTHS
        }
    }
}

impl Pipeline {
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
        let roi = clip_roi(self.config.roi_px, full, &mut notes)?;
        let scale = work_scale(full.width, self.config.work_width_px);
        let view = if self.config.mask == MaskMethod::Classical {
            None
        } else {
            NetworkView::around(&image, roi, full, scale)?
        };
        let cropped = crop(image, roi, full)?;
        let work = to_work_size(cropped, scale)?;
        timings_ms.push(("prepare", ms_since(start)));

        let start = Instant::now();
        let MaskChoice {
            mask: mask_roi,
            used: mask_used,
            background,
            belief,
        } = choose_mask(
            &work,
            view.as_ref(),
            self.config.mask,
            network,
            self.config.min_blob_area_px,
            &mut notes,
        )?;
        timings_ms.push(("mask", ms_since(start)));

        let look_alikes = LookAlikes {
            strokes: confidence::strokes_possible(mask_used, &background),
            busy: background.busy(),
            painted: background.painted(),
        };
        let found = self.cables_in(&work, &mask_roi, look_alikes, belief.as_ref(), roi, full)?;
        timings_ms.extend(found.timings_ms);
        if found.straight_dropped > 0 {
            notes.push(format!(
                "dropped {} straight detection(s) as edges: they bend less than a {:.0} px arc, or lie within {EDGE_NOISE_SAGITTA_PX} px of straight (a straight-edge radius of 0 keeps them)",
                found.straight_dropped, self.config.straight_edge_radius_px
            ));
        }
        if found.unconfident_dropped > 0 {
            notes.push(format!(
                "dropped {} detection(s) less confident than {:.3}{} as probably not cables: short against their width, unevenly wide, unlike the other cables' width, or flat as paint",
                found.unconfident_dropped,
                look_alikes.min_confidence(self.config.min_confidence),
                if look_alikes.painted {
                    format!(" (the floor times {PAINTED_MIN_CONFIDENCE_FACTOR} on a painted background)")
                } else {
                    String::new()
                }
            ));
        }
        if found.border_dropped > 0 {
            notes.push(format!(
                "dropped {} cable(s) that run out of view shorter than {:.0} px: too little of them is in view to grasp (a minimum border length of 0 keeps them)",
                found.border_dropped, self.config.min_border_cable_length_px
            ));
        }
        let union_mask = if self.config.cable_masks {
            Some(union_mask(&found.cables, full)?)
        } else {
            None
        };
        let mut skipped = Vec::new();
        if self.config.mask == MaskMethod::Auto
            && mask_used == MaskMethod::Classical
            && background.plain
        {
            skipped.push(VisionSkip::Network {
                near_fraction: background.near_fraction,
            });
        }
        if found.junctions == Some(0) {
            skipped.push(VisionSkip::CrossingResolution);
        }
        if roi != full {
            let area = |r: Rect| f64::from(r.width) * f64::from(r.height);
            skipped.push(VisionSkip::ImageOutsideRoi {
                worked_fraction: area(roi) / area(full),
            });
        }
        if !self.config.cable_masks {
            skipped.push(VisionSkip::CableMasks);
        }
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
            skipped,
        })
    }

    /// The instance, spline and instance-mask stages on a given CV_8U mask
    /// (non-zero = cable) of the whole image, ignoring the region of
    /// interest and the working width: to test and time them on
    /// ground-truth masks, and to tell their errors from the mask's. The
    /// mask is taken as a classical one: only cables in it. With the
    /// `image` it is of (its size; gray, BGRA and 16-bit are converted),
    /// crossings are also paired by colour and straight cables told from
    /// edges by their sides, as [`Pipeline::detect`] does.
    pub fn instances_from_mask(
        &mut self,
        mask: &Mat,
        image: Option<&Mat>,
    ) -> Result<MaskInstances, VisionError> {
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
        // `cables_in` reads colours from its image only when it has three
        // channels: without an image, the mask stands in for it.
        let image = match image {
            Some(image) => {
                let bgr = mask::to_bgr8(image)?;
                if bgr.size().map_err(cv("the image's size"))?
                    != mask.size().map_err(cv("the mask's size"))?
                {
                    return Err(VisionError::MaskSize {
                        mask_cols: mask.cols(),
                        mask_rows: mask.rows(),
                        image_cols: bgr.cols(),
                        image_rows: bgr.rows(),
                    });
                }
                bgr
            }
            None => Cow::Borrowed(mask),
        };
        let look_alikes = LookAlikes {
            strokes: false,
            busy: false,
            painted: false,
        };
        self.cables_in(&image, mask, look_alikes, None, full, full)
    }

    /// Instances, splines and per-cable masks for `mask_roi`, the mask of
    /// `image_roi` (with the network's `belief` when it made the mask, and
    /// what else it may hold that looks like a cable),
    /// region `roi` of an image of extent `full`, perhaps resized (see
    /// [`VisionConfig::work_width_px`]): what is found is given in the
    /// image's pixels.
    fn cables_in(
        &self,
        image_roi: &Mat,
        mask_roi: &Mat,
        look_alikes: LookAlikes,
        belief: Option<&Belief>,
        roi: Rect,
        full: Rect,
    ) -> Result<MaskInstances, VisionError> {
        let mut timings_ms = Vec::new();
        let start = Instant::now();
        let min_length_px = if look_alikes.busy {
            BUSY_MIN_LENGTH_FACTOR * self.config.min_cable_length_px
        } else {
            self.config.min_cable_length_px
        };
        let found = match self.config.instances {
            // `instances_from_mask` without an image passes the mask as
            // one: crossings are then paired by shape alone.
            InstanceMethod::Skeleton => skeleton::paths_from_mask(
                mask_roi,
                (image_roi.channels() == 3).then_some(image_roi),
                look_alikes.painted,
                min_length_px,
                look_alikes.join_gap_widths(),
            )?,
            InstanceMethod::Superpixels => superpixels::paths_from_mask(
                image_roi,
                mask_roi,
                min_length_px,
                self.config.superpixel_widths,
                look_alikes.join_gap_widths(),
            )?,
        };
        let size_px = [f64::from(mask_roi.cols()), f64::from(mask_roi.rows())];
        // A skeleton ends about half a width short of where its cable
        // leaves the region.
        let margin_px = found.width_px + 2.0;
        let at_border = |p: &[f64; 2]| paths::near_border(*p, size_px, margin_px);
        // Where the mask holds nothing but cables, a path's length is its
        // cable's in view: the skeleton and the half width it stops short
        // of the cable's end at each end. Where paint may pass for cable,
        // that shortfall stays as a margin against scraps.
        let in_view_extra_px = if look_alikes.only_cables() {
            found.width_px
        } else {
            0.0
        };
        let cable_length_px = |path: &paths::CablePath| path.length_px + in_view_extra_px;
        let paths: Vec<_> = found
            .paths
            .iter()
            .filter(|path| {
                let ends = [path.points_px.first(), path.points_px.last()];
                cable_length_px(path) >= self.config.min_border_cable_length_px
                    || !ends.into_iter().flatten().any(at_border)
            })
            .collect();
        let border_dropped = found.paths.len() - paths.len();
        let junctions = found.junctions;
        timings_ms.push(("instances", ms_since(start)));

        let start = Instant::now();
        let to_image = ToImage::new(roi, size_px);
        let mut fitted = Vec::new();
        let mut straight_dropped = 0;
        let mut unconfident_dropped = 0;
        let min_confidence = look_alikes.min_confidence(self.config.min_confidence);
        let mut plain_around = None;
        let half_widths = mask::half_widths(mask_roi)?;
        // Paint dries flat; where it may pass for cable, how shaded each
        // detection is counts (see `confidence::lightness_spread`).
        let gray = if look_alikes.strokes {
            let mut gray = Mat::default();
            imgproc::cvt_color_def(image_roi, &mut gray, imgproc::COLOR_BGR2GRAY)
                .map_err(cv("the image's lightness"))?;
            Some(gray)
        } else {
            None
        };
        for path in paths {
            let lightness_spread = gray
                .as_ref()
                .and_then(|gray| confidence::lightness_spread(gray, &half_widths, &path.points_px));
            let confidence = confidence::confidence(
                &half_widths,
                belief,
                &path.points_px,
                cable_length_px(path),
                look_alikes.strokes.then_some(found.width_px),
                lightness_spread,
            );
            if confidence < min_confidence {
                unconfident_dropped += 1;
                continue;
            }
            let n = spline::control_points_for_length(path.length_px);
            let Some(mut spline) = BSpline::fit(&path.points_px, n) else {
                continue;
            };
            let samples_px = spline.sample(self.config.samples_per_cable);
            // Paper and table edges lie on tables; on paint, prints and
            // mosaics a straight detection is a cable.
            if !look_alikes.busy
                && looks_like_edge(
                    &samples_px,
                    path.length_px,
                    self.config.straight_edge_radius_px,
                )
                && !straight_cable(
                    image_roi,
                    mask_roi,
                    &samples_px,
                    found.width_px,
                    &mut plain_around,
                )?
            {
                straight_dropped += 1;
                continue;
            }
            // A B-spline's points move with its control points under an
            // affine map: the spline fitted in working pixels becomes the
            // image's by moving them.
            for c in &mut spline.control_points {
                *c = to_image.point(*c);
            }
            let samples_px: Vec<_> = samples_px.into_iter().map(|p| to_image.point(p)).collect();
            let grasp_px = spline.point(0.5);
            let direction_rad = spline.grasp_direction_rad();
            fitted.push((
                path,
                spline,
                samples_px,
                grasp_px,
                direction_rad,
                confidence,
            ));
        }
        timings_ms.push(("spline", ms_since(start)));

        let start = Instant::now();
        let band_px = (1.5 * found.width_px).ceil().max(1.0) as i32 + 2;
        let owns = if self.config.cable_masks {
            let paths: Vec<&[[f64; 2]]> = fitted.iter().map(|f| f.0.points_px.as_slice()).collect();
            cable_masks(mask_roi, &half_widths, &paths, band_px)?
                .iter()
                .map(|own| mask_in_image(own, roi, full).map(Some))
                .collect::<Result<Vec<_>, _>>()?
        } else {
            vec![None; fitted.len()]
        };
        let mut cables = Vec::with_capacity(fitted.len());
        for ((path, spline, samples_px, grasp_px, direction_rad, confidence), mask) in
            fitted.into_iter().zip(owns)
        {
            cables.push(CableInstance {
                spline,
                samples_px,
                grasp_px,
                direction_rad,
                length_px: path.length_px * to_image.length_scale(),
                confidence,
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
            unconfident_dropped,
            timings_ms,
            junctions,
        })
    }
}
