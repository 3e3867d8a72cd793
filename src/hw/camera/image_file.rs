//! Reading one image file, for `detect`, `eval-vision` and a camera that
//! plays back a folder, with an error that names the file.

use std::path::{Path, PathBuf};

use opencv::core::Mat;
use opencv::imgcodecs;
use opencv::prelude::*;

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
    if !jpeg_is_whole(&bytes) {
        // libjpeg would decode the part before the cut, grey the rest and
        // warn on stderr without the file's name.
        return Err(ImageError::TruncatedJpeg { path: path_buf() });
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

/// Whether JPEG data runs to its end-of-image marker. Walks the markers,
/// skipping each segment by its length (so an EXIF thumbnail's own end
/// marker does not count) and the entropy-coded data byte by byte (in
/// which 0xFF is always followed by 0x00, a restart marker or fill).
/// Anything that does not start like a JPEG is not judged here.
fn jpeg_is_whole(bytes: &[u8]) -> bool {
    const SOI: [u8; 2] = [0xFF, 0xD8];
    const EOI: u8 = 0xD9;
    if !bytes.starts_with(&SOI) {
        return true;
    }
    let mut at = SOI.len();
    while at + 1 < bytes.len() {
        if bytes[at] != 0xFF {
            at += 1;
            continue;
        }
        match bytes[at + 1] {
            EOI => return true,
            // Fill byte before a marker.
            0xFF => at += 1,
            // A stuffed data byte, TEM, restart markers, SOI: no length.
            0x00 | 0x01 | 0xD0..=0xD8 => at += 2,
            _ => {
                let Some(length) = bytes.get(at + 2..at + 4) else {
                    return false;
                };
                at += 2 + usize::from(u16::from_be_bytes([length[0], length[1]]));
            }
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use opencv::core::{CV_8UC3, Scalar, Vector};

    /// A small noisy JPEG as OpenCV writes it.
    fn jpeg_bytes() -> Vec<u8> {
        let mut image =
            Mat::new_rows_cols_with_default(48, 64, CV_8UC3, Scalar::all(0.0)).expect("image");
        opencv::core::randu(&mut image, &Scalar::all(0.0), &Scalar::all(255.0)).expect("noise");
        let mut bytes = Vector::<u8>::new();
        assert!(imgcodecs::imencode_def(".jpg", &image, &mut bytes).expect("encode"));
        bytes.to_vec()
    }

    #[test]
    fn a_whole_jpeg_is_whole_and_every_cut_of_it_is_not() {
        let bytes = jpeg_bytes();
        assert!(jpeg_is_whole(&bytes));
        for cut in 2..bytes.len() {
            assert!(
                !jpeg_is_whole(&bytes[..cut]),
                "cut at {cut} of {}",
                bytes.len()
            );
        }
    }

    #[test]
    fn data_after_the_end_marker_and_a_thumbnail_s_end_marker_are_told_apart() {
        let bytes = jpeg_bytes();
        let mut trailing = bytes.clone();
        trailing.extend_from_slice(b"camera maker's trailer");
        assert!(jpeg_is_whole(&trailing));

        // An APP1 segment holding a whole JPEG (as an EXIF thumbnail does),
        // in front of a truncated main image.
        let thumbnail = jpeg_bytes();
        let length = u16::try_from(thumbnail.len() + 2).expect("fits");
        let mut with_thumbnail = vec![0xFF, 0xD8, 0xFF, 0xE1];
        with_thumbnail.extend_from_slice(&length.to_be_bytes());
        with_thumbnail.extend_from_slice(&thumbnail);
        with_thumbnail.extend_from_slice(&bytes[2..]);
        assert!(jpeg_is_whole(&with_thumbnail));
        with_thumbnail.truncate(with_thumbnail.len() - 100);
        assert!(!jpeg_is_whole(&with_thumbnail));
    }

    #[test]
    fn a_truncated_jpeg_file_is_an_error_that_names_it() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("cut.jpg");
        let bytes = jpeg_bytes();
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
        assert_eq!((image.cols(), image.rows()), (64, 48));
    }
}
