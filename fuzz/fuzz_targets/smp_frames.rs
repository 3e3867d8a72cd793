//! The PG70's SMP frames: the decoder on any bytes, arriving in pieces of
//! any size, each frame understood as a reply; then the driver itself
//! reading those bytes as the module's answers.

#![no_main]

use std::time::Duration;

use cablecell::hw::gripper::smp::{Decoder, Reply};
use cablecell::hw::gripper::{Gripper, Pg70};
use cablecell_fuzz::ScriptedLink;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&piece, bytes)) = data.split_first() else {
        return;
    };
    let mut decoder = Decoder::default();
    let mut frames = Vec::new();
    for chunk in bytes.chunks(usize::from(piece).max(1)) {
        decoder.push(chunk);
        while let Some(frame) = decoder.next_frame() {
            frames.push(frame);
        }
    }
    // Every byte is in a frame, thrown away, or held for a frame to come.
    let framed: usize = frames.iter().map(|f| f.encode().len()).sum();
    assert_eq!(
        framed + decoder.discarded_bytes + decoder.pending_bytes(),
        bytes.len()
    );
    for frame in frames {
        // A frame read off the wire is written back byte for byte.
        let mut again = Decoder::default();
        again.push(&frame.encode());
        assert_eq!(again.next_frame().as_ref(), Some(&frame));
        let _ = Reply::parse(frame);
    }

    let link = ScriptedLink::from_input(data);
    // Deadlines that only a driver looping without reading would meet.
    let mut pg70 =
        Pg70::new(link, "fuzz", 1).with_timeouts(Duration::from_secs(1), Duration::from_secs(1));
    let _ = pg70.state();
    let _ = pg70.acknowledge();
    let _ = pg70.reference();
    let _ = pg70.move_to(30.0);
    let _ = pg70.grip(1.5);
    let _ = pg70.stop();
});
