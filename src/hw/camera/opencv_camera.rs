//! A real camera through OpenCV: a capture device, a video file, or a
//! folder of images (a recorded scene played back, one image per capture).
//! The source is opened at the first capture, so that a cell can be built
//! and checked without it.

use std::path::{Path, PathBuf};

use opencv::core::Mat;
use opencv::prelude::*;
use opencv::videoio::{self, VideoCapture};

use super::{Camera, read_image};
use crate::hw::camera::config::CameraSource;
use crate::hw::{DeviceError, DeviceKind};
use crate::perception::vision::calibration::CameraModel;

pub struct OpencvCamera {
    source: CameraSource,
    intrinsics: CameraModel,
    opened: Option<Opened>,
}

enum Opened {
    Capture(VideoCapture),
    /// The folder's images in name order, and the next one to read.
    Folder {
        images: Vec<PathBuf>,
        next: usize,
    },
}

/// The image files OpenCV reads, by extension.
const IMAGE_EXTENSIONS: [&str; 6] = ["png", "jpg", "jpeg", "bmp", "tif", "tiff"];

impl OpencvCamera {
    pub fn new(source: CameraSource, intrinsics: CameraModel) -> Self {
        Self {
            source,
            intrinsics,
            opened: None,
        }
    }

    fn describe(&self) -> String {
        match &self.source {
            CameraSource::Device(index) => format!("capture device {index}"),
            CameraSource::Video(path) => format!("video {}", path.display()),
            CameraSource::Folder(path) => format!("image folder {}", path.display()),
        }
    }

    fn unusable(&self, reason: impl std::fmt::Display) -> DeviceError {
        DeviceError::Unusable {
            device: DeviceKind::Camera,
            reason: format!("{}: {reason}", self.describe()),
        }
    }

    fn open(&self) -> Result<Opened, DeviceError> {
        let capture = |capture: opencv::Result<VideoCapture>| {
            let capture = capture.map_err(|e| self.unusable(e))?;
            match capture.is_opened() {
                Ok(true) => Ok(Opened::Capture(capture)),
                _ => Err(self.unusable("cannot be opened")),
            }
        };
        match &self.source {
            CameraSource::Device(index) => capture(VideoCapture::new(*index, videoio::CAP_ANY)),
            CameraSource::Video(path) => capture(VideoCapture::from_file(path, videoio::CAP_ANY)),
            CameraSource::Folder(dir) => {
                let images = list_images(dir).map_err(|e| self.unusable(e))?;
                if images.is_empty() {
                    return Err(self.unusable("holds no images"));
                }
                Ok(Opened::Folder { images, next: 0 })
            }
        }
    }

    fn next_image(&mut self) -> Result<Mat, DeviceError> {
        let mut opened = match self.opened.take() {
            Some(opened) => opened,
            None => self.open()?,
        };
        let image = self.read(&mut opened);
        self.opened = Some(opened);
        image
    }

    fn read(&self, opened: &mut Opened) -> Result<Mat, DeviceError> {
        match opened {
            Opened::Capture(capture) => {
                let mut image = Mat::default();
                let read = capture.read(&mut image).unwrap_or(false);
                if !read || image.empty() {
                    let reason = match self.source {
                        CameraSource::Device(_) => "gave no image (unplugged?)",
                        _ => "has no more frames",
                    };
                    return Err(self.unusable(reason));
                }
                Ok(image)
            }
            Opened::Folder { images, next } => {
                let Some(path) = images.get(*next).cloned() else {
                    let count = images.len();
                    return Err(self.unusable(format!("all {count} images have been read")));
                };
                *next += 1;
                read_image(&path).map_err(|source| DeviceError::Image {
                    device: DeviceKind::Camera,
                    source: source.into(),
                })
            }
        }
    }
}

impl Camera for OpencvCamera {
    fn capture(&mut self) -> Result<Mat, DeviceError> {
        let image = self.next_image()?;
        let (width, height) = (image.cols(), image.rows());
        if (width, height) != (self.intrinsics.width_px, self.intrinsics.height_px) {
            return Err(self.unusable(format!(
                "gave a {width}×{height} image; the cell file's intrinsics are for {}×{}",
                self.intrinsics.width_px, self.intrinsics.height_px
            )));
        }
        Ok(image)
    }
}

/// The image files in `dir`, in name order.
fn list_images(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut images: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|path| {
            path.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| IMAGE_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
        })
        .collect();
    images.sort();
    Ok(images)
}
