//! A campaign's journal, read as `--resume` and the summary read it: every
//! entry read back writes back as a line that reads back equal, and what
//! follows the last newline is reported as the cut tail.

#![no_main]

use cablecell::campaign::journal;
use cablecell::campaign::trial::TrialEntry;
use cablecell_fuzz::with_file;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(recovered) = with_file("trials.jsonl", data, journal::read::<TrialEntry>) else {
        return;
    };
    let tail = data.len() - data.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    assert_eq!(recovered.truncated_tail_bytes, tail);
    for entry in &recovered.entries {
        let line = serde_json::to_string(entry).expect("an entry read is written");
        let again: TrialEntry = serde_json::from_str(&line).expect("an entry written is read");
        assert_eq!(&again, entry, "{line}");
    }
});
