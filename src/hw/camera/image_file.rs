//! Reading one image file, for `detect`, `eval-vision` and a camera that
//! plays back a folder, with an error that names the file.

use std::path::{Path, PathBuf};

use opencv::core::Mat;
use opencv::imgcodecs;
use opencv::prelude::*;

use super::jpeg::{JpegFault, check};

/// Why an image file could not be read; every message starts with the
/// file's path.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImageError {
    /// The path names a folder. Fix: name an image file in it.
    #[error("{path}: is a folder, not an image file")]
    Folder { path: PathBuf },
    /// No file at the path (`source`: the I/O error). Fix: check the
    /// path.
    #[error("{path}: no such image file")]
    NotFound {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file is there but could not be read (`source`: the I/O error,
    /// e.g. no permission). Fix: check its permissions and the disk.
    #[error("{path}: cannot read the file: {source}")]
    Unreadable {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file is a JPEG cut short (a copy or a capture that stopped):
    /// libjpeg would decode the part before the cut and grey the rest.
    /// Fix: copy or capture the image again.
    #[error("{path}: the JPEG data stops before its end-of-image marker: the file is truncated")]
    TruncatedJpeg { path: PathBuf },
    /// The file is a JPEG whose data is damaged (`reason`: what libjpeg
    /// would warn of): libjpeg would decode it anyway, garbled. Fix: copy
    /// or capture the image again.
    #[error("{path}: the JPEG data is corrupt ({reason})")]
    CorruptJpeg { path: PathBuf, reason: String },
    /// OpenCV failed reading the image (`source`: its error). Fix: check
    /// that the file is an image OpenCV can decode (PNG, JPEG, ...).
    #[error("{path}: cannot read the image: {source}")]
    Decode {
        path: PathBuf,
        #[source]
        source: opencv::Error,
    },
    /// OpenCV read the file but found no image in it: not an image format
    /// it decodes. Fix: convert it to PNG or JPEG.
    #[error("{path}: not an image OpenCV can decode")]
    NotAnImage { path: PathBuf },
}

impl ImageError {
    /// The image file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            ImageError::Folder { path }
            | ImageError::NotFound { path, .. }
            | ImageError::Unreadable { path, .. }
            | ImageError::TruncatedJpeg { path }
            | ImageError::CorruptJpeg { path, .. }
            | ImageError::Decode { path, .. }
            | ImageError::NotAnImage { path } => path,
        }
    }
}

/// Reads a colour image (8-bit BGR), or says which file could not be read
/// and why.
pub fn read_image(path: &Path) -> Result<Mat, ImageError> {
    let path_buf = || path.to_path_buf();
    if path.is_dir() {
        return Err(ImageError::Folder { path: path_buf() });
    }
    let bytes = std::fs::read(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => ImageError::NotFound {
            path: path_buf(),
            source,
        },
        _ => ImageError::Unreadable {
            path: path_buf(),
            source,
        },
    })?;
    // libjpeg would decode a cut or damaged JPEG, grey or garble what it
    // could not read and warn on stderr without the file's name.
    match check(&bytes) {
        Ok(()) => {}
        Err(JpegFault::Truncated) => return Err(ImageError::TruncatedJpeg { path: path_buf() }),
        Err(JpegFault::Corrupt(reason)) => {
            return Err(ImageError::CorruptJpeg {
                path: path_buf(),
                reason,
            });
        }
    }
    let name = path.display().to_string();
    let image =
        imgcodecs::imread(&name, imgcodecs::IMREAD_COLOR).map_err(|source| ImageError::Decode {
            path: path_buf(),
            source,
        })?;
    if image.empty() {
        return Err(ImageError::NotAnImage { path: path_buf() });
    }
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hw::camera::jpeg::tests::{jpeg_bytes, scan_data_start};

    #[test]
    fn a_truncated_jpeg_file_is_an_error_that_names_it() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("cut.jpg");
        let bytes = jpeg_bytes(&[]);
        std::fs::write(&path, &bytes[..bytes.len() / 2]).expect("write");
        let error = read_image(&path).expect_err("truncated");
        assert!(
            matches!(error, ImageError::TruncatedJpeg { .. }),
            "{error:?}"
        );
        assert_eq!(error.path(), path);
        assert!(
            error.to_string().contains("cut.jpg: the JPEG data stops"),
            "{error}"
        );
        std::fs::write(&path, &bytes).expect("write");
        let image = read_image(&path).expect("whole");
        assert_eq!((image.cols(), image.rows()), (32, 24));
    }

    #[test]
    fn a_corrupt_jpeg_file_is_an_error_that_names_it() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("corrupt.jpg");
        let mut bytes = jpeg_bytes(&[]);
        // An end-of-image marker halfway through the scan, the file's
        // length kept: libjpeg would decode it, greying the rest.
        let middle = (scan_data_start(&bytes) + bytes.len()) / 2;
        bytes[middle..middle + 2].copy_from_slice(&[0xFF, 0xD9]);
        std::fs::write(&path, &bytes).expect("write");
        let error = read_image(&path).expect_err("corrupt");
        assert_eq!(error.path(), path);
        assert!(
            error
                .to_string()
                .contains("corrupt.jpg: the JPEG data is corrupt (premature end of data segment)"),
            "{error}"
        );
    }
}
