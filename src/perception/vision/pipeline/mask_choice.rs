//! Which mask a run takes: the classical threshold where the background
//! is plain and its mask not in doubt, else the segmentation network, or,
//! with no network, the classical mask with a note that says what to
//! expect of it.

use opencv::core::Mat;
use opencv::prelude::*;

use super::confidence::Belief;
use super::config::MaskMethod;
use super::work_area::NetworkView;
use crate::perception::vision::background::{self, BackgroundStats};
use crate::perception::vision::error::{VisionError, cv};
use crate::perception::vision::mask;

/// A segmentation network that gives the cables' mask; implemented by the
/// ONNX network so that the pipeline does not depend on its runtime.
pub trait MaskNetwork {
    /// The cables' mask for a BGR 8-bit image: one channel, the image's size
    /// (or any size: it is resized), 8-bit 0/255 (or 0/1) or 32-bit float
    /// probabilities. Probabilities also tell each detection's confidence
    /// how sure the network was of it. `background`: the image's
    /// background, where a network may look closer
    /// ([`BackgroundStats::closer_look`]) or hand a painted scene to a
    /// network of its own ([`BackgroundStats::painted`]).
    fn mask(&mut self, bgr: &Mat, background: &BackgroundStats) -> Result<Mat, VisionError>;

    /// The probability above which a pixel is cable, for a network that
    /// gives probabilities, on `background` (a network may cut a painted
    /// scene's elsewhere).
    fn threshold(&self, _background: &BackgroundStats) -> f64 {
        0.5
    }
}

/// The mask a run takes, the method that made it (`Classical` or
/// `Network`), the background statistics behind the choice, and the
/// network's probabilities when it gave them.
pub(super) struct MaskChoice {
    pub mask: Mat,
    pub used: MaskMethod,
    pub background: BackgroundStats,
    pub belief: Option<Belief>,
}

/// The mask-choice policy, on the image as worked on (`work`, BGR):
/// - `Network`: the network's mask; without a network,
///   [`VisionError::NoNetwork`].
/// - `Auto`: the network's mask on a background that is not plain; on a
///   plain one, the classical mask unless it is in doubt
///   ([`mask::classical_doubt`]), then the network's. Without a network,
///   the classical mask, with a note in `notes` when it was not the
///   policy's choice.
/// - `Classical`: the classical mask.
///
/// The network sees `view` when given (the region of interest with the
/// image around it), else `work`. Masks are cleaned of blobs smaller than
/// `min_blob_area_px`.
pub(super) fn choose_mask(
    work: &Mat,
    view: Option<&NetworkView>,
    method: MaskMethod,
    network: Option<&mut dyn MaskNetwork>,
    min_blob_area_px: f64,
    notes: &mut Vec<String>,
) -> Result<MaskChoice, VisionError> {
    let background = background::background_stats(work)?;
    let network_mask =
        |net: &mut dyn MaskNetwork| network_mask(net, work, view, &background, min_blob_area_px);
    let (found, used, background) = match (method, network) {
        (MaskMethod::Network, None) => return Err(VisionError::NoNetwork),
        (MaskMethod::Network, Some(net)) => (network_mask(net)?, MaskMethod::Network, background),
        (MaskMethod::Auto, Some(net)) if !background.plain => {
            (network_mask(net)?, MaskMethod::Network, background)
        }
        (method, network) => {
            let auto = method == MaskMethod::Auto;
            if auto && !background.plain {
                notes.push(format!(
                    "background not plain ({:.0}% of pixels near its colour, plain needs {:.0}%) and no network given: used the classical mask, expect clutter in it",
                    100.0 * background.near_fraction,
                    100.0 * background::PLAIN_MIN_FRACTION
                ));
            }
            let (m, stats) = mask::classical_mask(work, &background, min_blob_area_px)?;
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
                    ((m, None), MaskMethod::Classical, stats)
                }
            }
        }
    };
    let (mask, belief) = found;
    Ok(MaskChoice {
        mask,
        used,
        background,
        belief,
    })
}

/// The network's mask of `work` (seen within `view` when given; of
/// `background`), binarized to its size
/// and cleaned of blobs smaller than `min_blob_area_px`, with its
/// probabilities if it gave them.
fn network_mask(
    net: &mut dyn MaskNetwork,
    work: &Mat,
    view: Option<&NetworkView>,
    background: &BackgroundStats,
    min_blob_area_px: f64,
) -> Result<(Mat, Option<Belief>), VisionError> {
    let raw = match view {
        None => net.mask(work, background)?,
        Some(view) => {
            let size = view.image.size().map_err(cv("image size"))?;
            let seen = mask::at_size(net.mask(&view.image, background)?, size)?;
            Mat::roi(&seen, view.region)
                .and_then(|region| region.try_clone())
                .map_err(cv("cut the region of interest from the network's view"))?
        }
    };
    let size = work.size().map_err(cv("image size"))?;
    let threshold = net.threshold(background);
    let binary = mask::binarize_network_mask(&raw, size, threshold)?;
    let belief = Belief::of(raw, size, threshold)?;
    Ok((mask::clean_mask(&binary, min_blob_area_px)?, belief))
}
