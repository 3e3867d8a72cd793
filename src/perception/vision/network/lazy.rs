//! The network as the pipeline runs it: loaded when a scene first needs
//! it, with a second network for painted scenes.

use std::path::{Path, PathBuf};

use opencv::core::Mat;

use super::{DEFAULT_BUSY_THRESHOLD, DEFAULT_THRESHOLD, InputScales, SegmentationNet};
use crate::perception::vision::{BackgroundStats, MaskNetwork, VisionError};

/// The network, loaded the first time a scene needs it: a plain
/// background never pays for it. Given a second network for busy scenes
/// ([`LazyNetwork::with_busy_model`]), that one sees the scenes whose
/// background is painted (busy and of many colours: paint, prints,
/// mosaics), the first all others.
pub struct LazyNetwork {
    model: PathBuf,
    busy_model: Option<PathBuf>,
    runtime_library: PathBuf,
    threshold: f32,
    busy_threshold: f32,
    input_scales: InputScales,
    loaded: Option<SegmentationNet>,
    loaded_busy: Option<SegmentationNet>,
}

impl LazyNetwork {
    /// The network at its default threshold and input scales.
    pub fn new(model: PathBuf, runtime_library: PathBuf) -> Self {
        Self {
            model,
            busy_model: None,
            runtime_library,
            threshold: DEFAULT_THRESHOLD,
            busy_threshold: DEFAULT_BUSY_THRESHOLD,
            input_scales: InputScales::default(),
            loaded: None,
            loaded_busy: None,
        }
    }

    /// The same with another probability threshold and input scales.
    pub fn tuned(self, threshold: f32, input_scales: InputScales) -> Self {
        Self {
            threshold,
            input_scales,
            ..self
        }
    }

    /// The same with `busy_model`, when given, for the scenes whose
    /// background is painted ([`BackgroundStats::painted`]): a network trained
    /// more on them (`models/history.md`, "The network for busy scenes"),
    /// whose probabilities are cut at `busy_threshold`, at the input scales'
    /// `busy` scale.
    pub fn with_busy_model(self, busy_model: Option<PathBuf>, busy_threshold: f32) -> Self {
        Self {
            busy_model,
            busy_threshold,
            ..self
        }
    }

    /// The network, and the busy scenes' one when given, loaded now if
    /// they were not yet: a command that will need them calls this first,
    /// so that a model that is no network or a missing runtime is found
    /// before any image, whatever the images.
    pub fn load(&mut self) -> Result<(), VisionError> {
        if let Some(busy_model) = &self.busy_model {
            loaded(
                &mut self.loaded_busy,
                busy_model,
                &self.runtime_library,
                self.busy_threshold,
            )?;
        }
        loaded(
            &mut self.loaded,
            &self.model,
            &self.runtime_library,
            self.threshold,
        )?;
        Ok(())
    }
}

/// The network in `slot`, loaded from `model` first if the slot is empty.
fn loaded<'a>(
    slot: &'a mut Option<SegmentationNet>,
    model: &Path,
    runtime_library: &Path,
    threshold: f32,
) -> Result<&'a mut SegmentationNet, VisionError> {
    let net = match slot.take() {
        Some(net) => net,
        None => {
            let mut net = SegmentationNet::load(model, runtime_library)
                .map_err(|source| VisionError::Network { source })?;
            net.threshold = threshold;
            net
        }
    };
    Ok(slot.insert(net))
}

impl MaskNetwork for LazyNetwork {
    fn mask(&mut self, bgr: &Mat, background: &BackgroundStats) -> Result<Mat, VisionError> {
        let (slot, model, threshold, input_scale) = match &self.busy_model {
            Some(busy_model) if background.painted() => (
                &mut self.loaded_busy,
                busy_model,
                self.busy_threshold,
                self.input_scales.busy,
            ),
            _ => (
                &mut self.loaded,
                &self.model,
                self.threshold,
                if background.closer_look() {
                    self.input_scales.close
                } else {
                    self.input_scales.normal
                },
            ),
        };
        let net = loaded(slot, model, &self.runtime_library, threshold)?;
        net.input_scale = input_scale;
        MaskNetwork::mask(net, bgr, background)
    }

    fn threshold(&self, background: &BackgroundStats) -> f64 {
        if self.busy_model.is_some() && background.painted() {
            f64::from(self.busy_threshold)
        } else {
            f64::from(self.threshold)
        }
    }
}
