//! Where the pipeline works and at what size: the region of interest
//! clipped to the image, the image cropped to it and resized to the
//! working width, and the map from working pixels back to the image's.

use std::borrow::Cow;

use opencv::core::{self, Mat, Rect};
use opencv::imgproc;
use opencv::prelude::*;

use crate::perception::vision::error::{VisionError, cv};

/// The region worked on: `roi_px` clipped to the image of extent `full`
/// (noting a clip in `notes`), or the whole image without one. A region
/// that misses the image is [`VisionError::RoiOutside`].
pub(super) fn clip_roi(
    roi_px: Option<Rect>,
    full: Rect,
    notes: &mut Vec<String>,
) -> Result<Rect, VisionError> {
    let Some(r) = roi_px else {
        return Ok(full);
    };
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
    Ok(clipped)
}

/// Region `roi` of `image` (of extent `full`): the image itself when the
/// region is all of it, else a copy of the region.
pub(super) fn crop(
    image: Cow<'_, Mat>,
    roi: Rect,
    full: Rect,
) -> Result<Cow<'_, Mat>, VisionError> {
    if roi == full {
        return Ok(image);
    }
    Ok(Cow::Owned(
        Mat::roi(&*image, roi)
            .and_then(|m| m.try_clone())
            .map_err(cv("crop to region of interest"))?,
    ))
}

/// Around a region of interest, how much more of the image (in working
/// pixels, each way) the network sees: a convolutional network marks
/// things near its input's border less reliably (on the simulated cell's
/// 360 × 110 px region, wood grain along the region's top edge), and the
/// image around the region is the context it lacks there.
pub(super) const NETWORK_CONTEXT_PX: f64 = 48.0;

/// What the network sees for a region of interest: the region with
/// [`NETWORK_CONTEXT_PX`] of the image around it (as much as the image
/// has), at the working size, and where the region lies in it.
pub(super) struct NetworkView {
    pub image: Mat,
    pub region: Rect,
}

impl NetworkView {
    /// The view for region `roi` of `image` (of extent `full`), worked on
    /// at `scale`; `None` when the region is the whole image.
    pub(super) fn around(
        image: &Mat,
        roi: Rect,
        full: Rect,
        scale: f64,
    ) -> Result<Option<NetworkView>, VisionError> {
        if roi == full {
            return Ok(None);
        }
        let margin = (NETWORK_CONTEXT_PX / scale).ceil() as i32;
        let context = Rect::new(
            roi.x - margin,
            roi.y - margin,
            roi.width + 2 * margin,
            roi.height + 2 * margin,
        ) & full;
        let seen = to_work_size(crop(Cow::Borrowed(image), context, full)?, scale)?;
        let at = |offset: i32, side: i32, room: i32| {
            let start = ((f64::from(offset) * scale).round() as i32).clamp(0, room - 1);
            let len = ((f64::from(side) * scale).round() as i32).clamp(1, room - start);
            (start, len)
        };
        let (x, width) = at(roi.x - context.x, roi.width, seen.cols());
        let (y, height) = at(roi.y - context.y, roi.height, seen.rows());
        Ok(Some(NetworkView {
            image: seen.into_owned(),
            region: Rect::new(x, y, width, height),
        }))
    }
}

/// Maps pixels of the image as worked on (the region of interest, perhaps
/// resized) to the full image's pixels, whose centres are at whole
/// coordinates in both.
pub(super) struct ToImage {
    offset_px: [f64; 2],
    scale: [f64; 2],
}

impl ToImage {
    /// For a region `roi` of the image worked on at `size_px`.
    pub(super) fn new(roi: Rect, size_px: [f64; 2]) -> Self {
        ToImage {
            offset_px: [f64::from(roi.x), f64::from(roi.y)],
            scale: [
                f64::from(roi.width) / size_px[0],
                f64::from(roi.height) / size_px[1],
            ],
        }
    }

    pub(super) fn point(&self, p: [f64; 2]) -> [f64; 2] {
        [0, 1].map(|i| p[i] * self.scale[i] + (self.scale[i] - 1.0) / 2.0 + self.offset_px[i])
    }

    /// Image pixels per working pixel, for lengths.
    pub(super) fn length_scale(&self) -> f64 {
        (self.scale[0] + self.scale[1]) / 2.0
    }
}

/// The most an image is enlarged to reach the working width: enough for a
/// camera 160 px wide, and a bound on the memory a thin strip of an image
/// would take.
pub const MAX_ENLARGEMENT: f64 = 4.0;

/// The image's size as worked on over its own, for an image `width_px`
/// wide: see [`VisionConfig::work_width_px`](super::VisionConfig::work_width_px).
pub(super) fn work_scale(width_px: i32, work_width_px: u32) -> f64 {
    if work_width_px == 0 || width_px <= 0 {
        return 1.0;
    }
    (f64::from(work_width_px) / f64::from(width_px)).min(MAX_ENLARGEMENT)
}

/// `image` resized by `scale`: shrunk by area averaging, as the network's
/// input is, or enlarged bilinearly; unchanged at 1.
pub(super) fn to_work_size(image: Cow<'_, Mat>, scale: f64) -> Result<Cow<'_, Mat>, VisionError> {
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

/// Along one axis, the working pixels `[start, start + len)` grown to a
/// span whose resize matches the whole row's: by a pixel each way (a
/// bilinear resize reads one pixel beyond the one it lands on, and pixels
/// next to the span are then zero in both), and out to working pixels
/// whose edges map onto image pixels' edges (`work_px` working pixels
/// span `image_px` image ones). Returns the span in working pixels and in
/// image pixels.
pub(super) fn resize_span(
    start: i32,
    len: i32,
    work_px: i32,
    image_px: i32,
) -> ((i32, i32), (i32, i32)) {
    let step = work_px / gcd(work_px, image_px);
    let lo = (start - 1).max(0) / step * step;
    let hi = ((start + len + 1 + step - 1) / step * step).min(work_px);
    let to_image = |w: i32| (i64::from(w) * i64::from(image_px) / i64::from(work_px)) as i32;
    ((lo, hi), (to_image(lo), to_image(hi)))
}

fn gcd(a: i32, b: i32) -> i32 {
    if b == 0 { a } else { gcd(b, a % b) }
}
