//! Reading a data set's ground truth: per image, one mask per cable,
//! their union and each cable's polyline, checked against each other's
//! and the image's size.

use std::path::{Path, PathBuf};

use opencv::core::{self, Mat, Size};
use opencv::imgcodecs;
use opencv::prelude::*;

use super::measure::size_of;
use crate::perception::vision::error::{VisionError, cv};

/// One image's ground truth.
#[derive(Debug)]
pub struct GroundTruth {
    /// One CV_8U 0/255 mask per cable, the image's size.
    pub masks: Vec<Mat>,
    /// The union of the cables' masks.
    pub union_mask: Mat,
    /// Each cable's centreline, in pixels (x right, y down).
    pub polylines_px: Vec<Vec<[f64; 2]>>,
}

/// Reads a ground-truth mask, binarized at half: 0/255.
fn read_mask(path: &Path) -> Result<Mat, VisionError> {
    let bytes = std::fs::read(path).map_err(|source| VisionError::ReadTruth {
        path: path.to_path_buf(),
        source,
    })?;
    let undecodable = |source| VisionError::DecodeTruth {
        path: path.to_path_buf(),
        source,
    };
    let m = imgcodecs::imdecode(
        &core::Vector::from_slice(&bytes),
        imgcodecs::IMREAD_GRAYSCALE,
    )
    .map_err(|e| undecodable(Some(e)))?;
    if m.empty() {
        return Err(undecodable(None));
    }
    let mut binary = Mat::default();
    opencv::imgproc::threshold(
        &m,
        &mut binary,
        127.0,
        255.0,
        opencv::imgproc::THRESH_BINARY,
    )
    .map_err(cv("binarize truth mask"))?;
    Ok(binary)
}

/// Parses one annotation line: `N x0 y0 ... x(N-1) y(N-1)`.
fn parse_polyline(path: &Path, line_no: usize, line: &str) -> Result<Vec<[f64; 2]>, VisionError> {
    let bad = |reason: String| VisionError::BadAnnotation {
        path: path.to_path_buf(),
        line: line_no,
        reason,
    };
    let mut numbers = Vec::new();
    for word in line.split_whitespace() {
        let v: f64 = word
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| bad(format!("`{word}` is not a number")))?;
        numbers.push(v);
    }
    let Some((&count, coords)) = numbers.split_first() else {
        return Err(bad("empty line".into()));
    };
    if count < 0.0 || count.fract() != 0.0 || coords.len() != 2 * count as usize {
        return Err(bad(format!(
            "says {count} points but holds {} coordinates",
            coords.len()
        )));
    }
    Ok(coords.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
}

/// Checks that a centre line read from line `line_no` of `path` lies near
/// the image of size `extent`: it may run out of view, but no farther
/// than the image is wide or tall. Points far outside are a labelling
/// error, and a line millions of pixels long would take the scoring, which
/// walks centre lines pixel by pixel, that long.
fn near_image(
    path: &Path,
    line_no: usize,
    points: Vec<[f64; 2]>,
    extent: Size,
) -> Result<Vec<[f64; 2]>, VisionError> {
    let (w, h) = (f64::from(extent.width), f64::from(extent.height));
    match points
        .iter()
        .find(|[x, y]| !(-w..=2.0 * w).contains(x) || !(-h..=2.0 * h).contains(y))
    {
        None => Ok(points),
        Some([x, y]) => Err(VisionError::BadAnnotation {
            path: path.to_path_buf(),
            line: line_no,
            reason: format!(
                "the point ({x:?}, {y:?}) lies farther outside the {}x{} px image than the image is wide or tall (x from {} to {}, y from {} to {})",
                extent.width,
                extent.height,
                -w,
                2.0 * w,
                -h,
                2.0 * h
            ),
        }),
    }
}

/// Checks that the mask read from `path` is `expected` in size, which
/// `expected_from` names.
fn check_mask_size(
    mask: &Mat,
    path: &Path,
    expected: Size,
    expected_from: impl FnOnce() -> String,
) -> Result<(), VisionError> {
    if mask.cols() == expected.width && mask.rows() == expected.height {
        return Ok(());
    }
    Err(VisionError::TruthMaskSize {
        path: path.to_path_buf(),
        cols: mask.cols(),
        rows: mask.rows(),
        expected_cols: expected.width,
        expected_rows: expected.height,
        expected_from: expected_from(),
    })
}

impl GroundTruth {
    /// Reads `STEM_mask_K.png` (K = 0, 1, ... while they exist),
    /// `STEM_mask_all.png` (or the masks' union when it is absent) and
    /// `STEM.txt` from `dir`. All masks must have the first one's size.
    pub fn load(dir: &Path, stem: &str) -> Result<GroundTruth, VisionError> {
        let first_path = dir.join(format!("{stem}_mask_0.png"));
        let like_first = || format!("the size of {}", first_path.display());
        let mut masks: Vec<Mat> = Vec::new();
        loop {
            let path = dir.join(format!("{stem}_mask_{}.png", masks.len()));
            if !path.exists() {
                break;
            }
            let mask = read_mask(&path)?;
            if let Some(first) = masks.first() {
                check_mask_size(&mask, &path, size_of(first), like_first)?;
            }
            masks.push(mask);
        }
        let Some(first) = masks.first() else {
            return Err(VisionError::NoTruthMasks {
                dir: dir.to_path_buf(),
                stem: stem.to_string(),
            });
        };
        let all_path = dir.join(format!("{stem}_mask_all.png"));
        let union_mask = if all_path.exists() {
            let union = read_mask(&all_path)?;
            check_mask_size(&union, &all_path, size_of(first), like_first)?;
            union
        } else {
            let mut union = masks[0].try_clone().map_err(cv("copy truth mask"))?;
            for m in &masks[1..] {
                let mut next = Mat::default();
                core::bitwise_or(&union, m, &mut next, &core::no_array())
                    .map_err(cv("union of truth masks"))?;
                union = next;
            }
            union
        };
        let txt: PathBuf = dir.join(format!("{stem}.txt"));
        let text = std::fs::read_to_string(&txt).map_err(|source| VisionError::ReadTruth {
            path: txt.clone(),
            source,
        })?;
        let extent = size_of(first);
        let polylines_px = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty())
            .map(|(i, l)| {
                parse_polyline(&txt, i + 1, l)
                    .and_then(|points| near_image(&txt, i + 1, points, extent))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(GroundTruth {
            masks,
            union_mask,
            polylines_px,
        })
    }

    /// Checks that the masks are `image`'s size (`image_path` names it),
    /// so that they can be compared with what the pipeline finds in it.
    pub fn check_fits(
        &self,
        image: &Mat,
        image_path: &Path,
        dir: &Path,
        stem: &str,
    ) -> Result<(), VisionError> {
        check_mask_size(
            &self.union_mask,
            &dir.join(format!("{stem}_mask_0.png")),
            size_of(image),
            || format!("the size of the image {}", image_path.display()),
        )
    }
}

/// (stem, image path) of every image with a union mask beside it, sorted.
pub fn labelled_images(dir: &Path) -> std::io::Result<Vec<(String, PathBuf)>> {
    let mut stems = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        let is_image = path.extension().is_some_and(|e| e == "jpg" || e == "png");
        let Some(stem) = path.file_stem().map(|s| s.to_string_lossy().into_owned()) else {
            continue;
        };
        if is_image
            && !stem.contains("_mask_")
            && dir.join(format!("{stem}_mask_all.png")).is_file()
        {
            stems.push((stem, path));
        }
    }
    stems.sort();
    Ok(stems)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polyline_lines_parse_and_bad_ones_say_where() {
        let p = Path::new("x.txt");
        assert_eq!(
            parse_polyline(p, 1, "2 1 2 3 4").unwrap(),
            vec![[1.0, 2.0], [3.0, 4.0]]
        );
        let err = parse_polyline(p, 7, "3 1 2 3 4").unwrap_err();
        assert!(
            matches!(err, VisionError::BadAnnotation { line: 7, .. }),
            "{err}"
        );
        assert!(parse_polyline(p, 1, "2 a 2 3 4").is_err());
        let err = parse_polyline(p, 2, "2 1 2 inf 4").unwrap_err();
        assert!(err.to_string().contains("`inf` is not a number"), "{err}");
        assert!(parse_polyline(p, 1, "2 1 NaN 3 4").is_err());
    }

    #[test]
    fn centre_lines_far_outside_the_image_are_refused_with_their_line() {
        let p = Path::new("x.txt");
        let extent = Size::new(64, 48);
        let near = vec![[-10.0, 0.0], [70.0, 47.0], [127.0, 95.0]];
        assert_eq!(near_image(p, 1, near.clone(), extent).unwrap(), near);
        let err = near_image(p, 3, vec![[1.0, 2.0], [1e9, 4.0]], extent).unwrap_err();
        assert!(
            matches!(err, VisionError::BadAnnotation { line: 3, .. }),
            "{err}"
        );
        assert!(
            err.to_string().contains("(1000000000.0, 4.0)")
                && err.to_string().contains("x from -64 to 128"),
            "{err}"
        );
        assert!(near_image(p, 1, vec![[0.0, -49.0]], extent).is_err());
    }

    #[test]
    fn masks_of_another_size_are_refused_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str, rows: i32, cols: i32| {
            let mask = Mat::zeros(rows, cols, core::CV_8UC1)
                .unwrap()
                .to_mat()
                .unwrap();
            let path = dir.path().join(name);
            imgcodecs::imwrite(path.to_str().unwrap(), &mask, &core::Vector::new()).unwrap();
        };
        write("a_mask_0.png", 48, 64);
        write("a_mask_1.png", 24, 32);
        std::fs::write(dir.path().join("a.txt"), "1 1 1\n1 2 2\n").unwrap();
        let err = GroundTruth::load(dir.path(), "a").unwrap_err();
        assert!(
            matches!(&err, VisionError::TruthMaskSize { path, cols: 32, rows: 24, .. }
                if path.ends_with("a_mask_1.png")),
            "{err}"
        );

        write("a_mask_1.png", 48, 64);
        let truth = GroundTruth::load(dir.path(), "a").unwrap();
        let image = Mat::zeros(96, 128, core::CV_8UC3)
            .unwrap()
            .to_mat()
            .unwrap();
        let err = truth
            .check_fits(&image, Path::new("a.jpg"), dir.path(), "a")
            .unwrap_err();
        assert!(
            err.to_string()
                .contains("is 64x48 px, expected 128x96 px (the size of the image a.jpg)"),
            "{err}"
        );
        let image = Mat::zeros(48, 64, core::CV_8UC3).unwrap().to_mat().unwrap();
        assert!(
            truth
                .check_fits(&image, Path::new("a.jpg"), dir.path(), "a")
                .is_ok()
        );
    }
}
