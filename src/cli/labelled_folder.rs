//! Reading a labelled folder (the cables-dev layout): its images and their
//! ground truth, for `eval-vision` to score and for `render-dataset` to
//! take cables from.

use std::path::{Path, PathBuf};

use cablecell::hw::camera::read_image;
use cablecell::perception::vision::eval::{GroundTruth, labelled_images};
use opencv::core::Mat;

/// An image with its ground truth, read once for all settings.
pub struct LabelledImage {
    pub stem: String,
    pub path: PathBuf,
    pub image: Mat,
    pub truth: GroundTruth,
}

/// The images of `dir` whose names sort from `from` to `to` (each
/// inclusive, either open), with their truth, or what is wrong: with every
/// image that cannot be read or whose truth is malformed, so that one run
/// lists all there is to mend.
pub fn load_labelled(
    dir: &Path,
    from: Option<&str>,
    to: Option<&str>,
) -> Result<Vec<LabelledImage>, Vec<String>> {
    let stems = labelled_images(dir).map_err(|error| {
        vec![format!(
            "{}: cannot list the folder: {error}",
            dir.display()
        )]
    })?;
    let selected: Vec<_> = stems
        .into_iter()
        .filter(|(stem, _)| from.is_none_or(|from| stem.as_str() >= from))
        .filter(|(stem, _)| to.is_none_or(|to| stem.as_str() <= to))
        .collect();
    if selected.is_empty() {
        return Err(vec![format!(
            "{}: no NNNNN.jpg images with NNNNN_mask_all.png beside them{}",
            dir.display(),
            match (from, to) {
                (None, None) => String::new(),
                (from, to) => format!(
                    " between {} and {}",
                    from.unwrap_or("the first"),
                    to.unwrap_or("the last")
                ),
            }
        )]);
    }
    let mut samples = Vec::new();
    let mut errors = Vec::new();
    for (stem, path) in selected {
        let image = read_image(&path);
        let truth = GroundTruth::load(dir, &stem).and_then(|truth| match &image {
            Ok(image) => truth.check_fits(image, &path, dir, &stem).map(|()| truth),
            Err(_) => Ok(truth),
        });
        let truth = truth.map_err(|error| format!("{}: {stem}: {error}", dir.display()));
        match (image, truth) {
            (Ok(image), Ok(truth)) => samples.push(LabelledImage {
                stem,
                path,
                image,
                truth,
            }),
            (image, truth) => errors.extend(
                image
                    .err()
                    .map(|error| error.to_string())
                    .into_iter()
                    .chain(truth.err()),
            ),
        }
    }
    if errors.is_empty() {
        Ok(samples)
    } else {
        Err(errors)
    }
}
