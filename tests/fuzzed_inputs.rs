//! Inputs the fuzz targets (`fuzz/`, see docs/testing.md) found to crash
//! cablecell or to break a property, kept as tests. The condition
//! language's (a stack overflow) is tested beside it, in
//! `orchestrator/breakpoint/condition.rs`.

use cablecell::recording::Recording;

/// `recording`: a record claiming 2^64 - 1 bytes overflowed inside the
/// mcap crate, a panic of `cablecell replay`. The recording now ends there,
/// cut, like a file whose run was killed.
#[test]
fn a_record_longer_than_the_file_ends_the_recording_there() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("corrupt.mcap");
    let mut bytes = b"\x89MCAP0\r\n".to_vec();
    // The header record: an empty profile and library name.
    bytes.push(0x01);
    bytes.extend(8_u64.to_le_bytes());
    bytes.extend([0; 8]);
    // A record of an unknown kind, as long as a length can say.
    bytes.push(0xFF);
    bytes.extend(u64::MAX.to_le_bytes());
    std::fs::write(&path, &bytes).expect("write the file");
    let recording = Recording::read(&path).expect("read as cut, not refused");
    assert!(recording.messages.is_empty());
    let why = recording
        .truncated
        .expect("the file is cut at the long record");
    assert!(why.contains("exceeds limit"), "{why}");
}
