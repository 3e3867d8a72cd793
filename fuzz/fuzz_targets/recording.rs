//! MCAP recordings: any bytes read back as `cablecell replay` reads a
//! file (whole or cut short), its messages decoded and its grasps fitted
//! again with both estimators.

#![no_main]

use cablecell::perception::tactile::Estimator;
use cablecell::recording::Recording;
use cablecell::recording::replay::Replay;
use cablecell_fuzz::with_file;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(recording) = with_file("recording.mcap", data, Recording::read) else {
        return;
    };
    let Ok(replay) = Replay::of(&recording) else {
        return;
    };
    for estimator in [Estimator::Centroids, Estimator::Ridge] {
        for refit in replay.refit(estimator) {
            let _ = (refit.error(), refit.recorded_error());
        }
    }
});
