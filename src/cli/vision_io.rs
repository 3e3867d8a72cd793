//! What `detect` and `eval-vision` share: the pipeline's configuration
//! from the command line, the network loaded only when a scene needs it,
//! and reading images.

use std::path::{Path, PathBuf};

use cablecell::perception::vision::network::{LazyNetwork, runtime_library};
use cablecell::perception::vision::{InstanceMethod, MaskMethod, Pipeline, VisionConfig};
use clap::Args;
use opencv::core::Mat;
use opencv::imgcodecs;
use opencv::prelude::*;

#[derive(Args, Debug, Clone)]
pub struct VisionArgs {
    /// How to find the cables' pixels: `auto` uses the classical mask on a
    /// plain background and the network otherwise.
    #[arg(long, value_enum, default_value = "auto")]
    pub mask: MaskArg,
    /// How to split the mask into cables.
    #[arg(long, value_enum, default_value = "skeleton")]
    pub instances: InstancesArg,
    /// The segmentation network.
    #[arg(long, default_value = "models/cable_segmentation.onnx")]
    pub model: PathBuf,
    /// The ONNX Runtime library (default: $ORT_DYLIB_PATH, else .setup/onnxruntime/).
    #[arg(long)]
    pub onnxruntime: Option<PathBuf>,
}

#[derive(clap::ValueEnum, Debug, Clone, Copy)]
pub enum MaskArg {
    Auto,
    Classical,
    Network,
}

#[derive(clap::ValueEnum, Debug, Clone, Copy)]
pub enum InstancesArg {
    Skeleton,
    Superpixels,
}

impl VisionArgs {
    pub fn pipeline(&self) -> Pipeline {
        let config = VisionConfig {
            mask: match self.mask {
                MaskArg::Auto => MaskMethod::Auto,
                MaskArg::Classical => MaskMethod::Classical,
                MaskArg::Network => MaskMethod::Network,
            },
            instances: match self.instances {
                InstancesArg::Skeleton => InstanceMethod::Skeleton,
                InstancesArg::Superpixels => InstanceMethod::Superpixels,
            },
            ..VisionConfig::default()
        };
        Pipeline::new(config)
    }

    pub fn network(&self) -> LazyNetwork {
        LazyNetwork::new(
            self.model.clone(),
            runtime_library(self.onnxruntime.as_deref()),
        )
    }
}

/// Reads a colour image, or says which file could not be read.
pub fn read_image(path: &Path) -> Result<Mat, String> {
    let name = path.display().to_string();
    if !path.is_file() {
        return Err(format!("{name}: no such image file"));
    }
    let image = imgcodecs::imread(&name, imgcodecs::IMREAD_COLOR)
        .map_err(|e| format!("{name}: cannot read the image: {e}"))?;
    if image.empty() {
        return Err(format!("{name}: not an image OpenCV can decode"));
    }
    Ok(image)
}
