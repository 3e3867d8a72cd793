//! The REMODEL microcontroller's answers: the driver asks for its id, its
//! count and samples over a link whose far end sends the fuzz input, and
//! every sample it returns is the 12-bit decoding of the bytes it was sent,
//! in the layout's order. The samples then go through bias removal and
//! both estimators, as a run's would.

#![no_main]

use std::time::Duration;

use cablecell::hw::DeviceError;
use cablecell::hw::clock::MonotonicClock;
use cablecell::hw::tactile::{RemodelTactile, TactileSensor};
use cablecell::perception::tactile::{
    ADC_MAX, BiasEstimator, Estimator, FitConfig, RawFrame, TAXEL_COUNT,
};
use cablecell_fuzz::{ScriptedLink, lock};
use libfuzzer_sys::fuzz_target;

/// Taxel k on ADC channel 24 - k: any order but the identity shows a
/// sample read through the wrong end of the layout.
const LAYOUT: [usize; TAXEL_COUNT] = {
    let mut layout = [0; TAXEL_COUNT];
    let mut k = 0;
    while k < TAXEL_COUNT {
        layout[k] = TAXEL_COUNT - 1 - k;
        k += 1;
    }
    layout
};

fuzz_target!(|data: &[u8]| {
    let link = ScriptedLink::from_input(data);
    let answer = link.answer();
    // A deadline only a driver looping without reading would meet.
    let mut pad = RemodelTactile::new(link, "fuzz", LAYOUT, Box::new(MonotonicClock::new()))
        .with_deadline(Duration::from_secs(1));
    let mut frames: Vec<RawFrame> = Vec::new();
    // Each request reads at least one byte or ends the input.
    for request in 0..=data.len() {
        let result = match request % 4 {
            0 => pad.id().map(|_| ()),
            1 => pad.count().map(|_| ()),
            _ => pad.read().map(|frame| {
                let bytes = lock(&answer);
                for (taxel, &value) in frame.raw.iter().enumerate() {
                    let channel = LAYOUT[taxel];
                    let (low, high) = (bytes[2 * channel], bytes[2 * channel + 1]);
                    assert_eq!(high & 0xF0, 0, "a sample kept a byte that is not 12-bit");
                    assert_eq!(value, u16::from(low) | u16::from(high) << 8);
                    assert!(value <= ADC_MAX);
                }
                frames.push(frame.raw);
            }),
        };
        if let Err(DeviceError::Disconnected { .. }) = result {
            break;
        }
    }
    let mut bias = BiasEstimator::new(1);
    let config = FitConfig::default();
    for frame in &frames {
        let Some(bias) = bias.push(frame) else {
            continue;
        };
        let map = bias.remove(frame);
        for estimator in [Estimator::Centroids, Estimator::Ridge] {
            let _ = estimator.estimate(&map, &config, None);
        }
    }
});
