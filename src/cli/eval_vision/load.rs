//! Reading a labelled folder: its images and their ground truth, once for
//! every setting.

use cablecell::hw::camera::read_image;
use cablecell::perception::vision::eval::{GroundTruth, labelled_images};

use super::{EvalVisionArgs, Sample};

/// The selected images of the folder and their truth, or what is wrong:
/// with every image that cannot be read or whose truth is malformed, so
/// that one run lists all there is to mend.
pub(super) fn load_samples(args: &EvalVisionArgs) -> Result<Vec<Sample>, Vec<String>> {
    let dir = &args.dir;
    let stems = labelled_images(dir).map_err(|error| {
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
