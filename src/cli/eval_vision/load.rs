//! Reading a labelled folder: its images and their ground truth, once for
//! every setting.

use std::path::{Path, PathBuf};

use cablecell::hw::camera::read_image;
use cablecell::perception::vision::eval::GroundTruth;

use super::{EvalVisionArgs, Sample};

/// The selected images of the folder and their truth, or what is wrong:
/// with every image that cannot be read or whose truth is malformed, so
/// that one run lists all there is to mend.
pub(super) fn load_samples(args: &EvalVisionArgs) -> Result<Vec<Sample>, Vec<String>> {
    let dir = &args.dir;
    let stems = image_stems(dir).map_err(|error| {
        vec![format!(
            "{}: cannot list the folder: {error}",
            dir.display()
        )]
    })?;
    let selected: Vec<_> = stems
        .into_iter()
        .filter(|(stem, _)| args.from.as_ref().is_none_or(|from| stem >= from))
        .filter(|(stem, _)| args.to.as_ref().is_none_or(|to| stem <= to))
        .collect();
    if selected.is_empty() {
        return Err(vec![format!(
            "{}: no NNNNN.jpg images with NNNNN_mask_all.png beside them{}",
            dir.display(),
            match (&args.from, &args.to) {
                (None, None) => String::new(),
                (from, to) => format!(
                    " between {} and {}",
                    from.as_deref().unwrap_or("the first"),
                    to.as_deref().unwrap_or("the last")
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
            (Ok(image), Ok(truth)) => samples.push(Sample {
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

/// (stem, image path) of every image with a union mask beside it, sorted.
fn image_stems(dir: &Path) -> std::io::Result<Vec<(String, PathBuf)>> {
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
