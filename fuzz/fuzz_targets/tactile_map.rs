//! The tactile map text `cablecell tactile-fit` reads: a parsed map,
//! written back as 25 numbers, parses to the same map; then both
//! estimators fit it, as the command and a replay would.

#![no_main]

use cablecell::perception::tactile::{Estimator, FitConfig, TactileMap};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(map) = TactileMap::parse(text) else {
        return;
    };
    let written: Vec<String> = map.dv_v.iter().flatten().map(f64::to_string).collect();
    assert_eq!(TactileMap::parse(&written.join(" ")), Ok(map));
    let config = FitConfig::default();
    for estimator in [Estimator::Centroids, Estimator::Ridge] {
        if let Ok(estimate) = estimator.estimate(&map, &config, None) {
            let line = estimate.line();
            assert!(
                line.n_mm.is_finite() && line.alpha_rad.is_finite(),
                "{line:?}"
            );
        }
    }
});
