//! Inputs the fuzz targets (`fuzz/`, see docs/testing.md) found to crash
//! cablecell or to break a property, kept as tests. The condition
//! language's (a stack overflow) is tested beside it, in
//! `orchestrator/breakpoint/condition.rs`.

use cablecell::campaign::journal::{Journal, read};
use cablecell::recording::Recording;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// An MCAP file's magic and header record (an empty profile and library
/// name), for the records after it.
fn mcap_start() -> Vec<u8> {
    let mut bytes = b"\x89MCAP0\r\n".to_vec();
    bytes.push(0x01);
    bytes.extend(8_u64.to_le_bytes());
    bytes.extend([0; 8]);
    bytes
}

/// `bytes` written to a file and read back as a recording, which must
/// succeed (a corrupt file reads as cut).
fn read_as_cut(bytes: &[u8]) -> Recording {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("corrupt.mcap");
    std::fs::write(&path, bytes).expect("write the file");
    Recording::read(&path).expect("read as cut, not refused")
}

/// `recording`: a record claiming 2^64 - 1 bytes overflowed inside the
/// mcap crate, a panic of `cablecell replay`. The recording now ends there,
/// cut, like a file whose run was killed.
#[test]
fn a_record_longer_than_the_file_ends_the_recording_there() {
    let mut bytes = mcap_start();
    // A record of an unknown kind, as long as a length can say.
    bytes.push(0xFF);
    bytes.extend(u64::MAX.to_le_bytes());
    let recording = read_as_cut(&bytes);
    assert!(recording.messages.is_empty());
    let why = recording
        .truncated
        .expect("the file is cut at the long record");
    assert!(why.contains("exceeds limit"), "{why}");
}

/// `recording`: an uncompressed chunk whose record runs past the chunk's
/// end made the mcap crate (0.26) subtract past zero in the chunk's
/// remaining length: a panic where overflow checks are on (debug builds,
/// the fuzz targets), a wrapped length and a file read as cut where they
/// are off (release builds). Its overflow checks are now off in every
/// profile (Cargo.toml), so the file reads as cut everywhere. The input as
/// the fuzz target found it.
#[test]
fn a_chunk_whose_record_runs_past_its_end_ends_the_recording() {
    let bytes: &[u8] = b"\x89\x4d\x43\x41\x50\x30\x0d\x0a\x06\x01\x17\x00\x00\x00\x00\x00\x00\x00\x00\xff\xff\xff\xe9\x00\x00\x00\x00\x4d\x43\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x02\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x4a\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00";
    let recording = read_as_cut(bytes);
    assert!(recording.messages.is_empty());
    assert!(
        recording.truncated.is_some(),
        "the file is cut in the chunk"
    );
}

/// `recording`: an attachment record too short for its own length field
/// made the mcap crate (0.26) cut its body from byte 32 to byte 28: a
/// panic in every build, found by the fuzz target. A recording holds no
/// attachments, and the reader now passes them over unparsed.
#[test]
fn an_attachment_shorter_than_its_header_is_passed_over() {
    let mut bytes = mcap_start();
    // An attachment: two times, an empty name and media type, a data
    // length of 0, and no data or CRC after them.
    bytes.push(0x09);
    bytes.extend(32_u64.to_le_bytes());
    bytes.extend([0; 32]);
    let recording = read_as_cut(&bytes);
    assert!(recording.messages.is_empty());
    assert!(
        recording.truncated.is_some(),
        "the file ends without its summary"
    );
}

/// `journal`: serde_json read some floats one unit in the last place off
/// (0.21937721680296174, an angle's error as a trial entry holds it), so
/// a resumed campaign's entries were not the ones it had written. Every
/// finite float now reads back bit for bit (10 000 more drawn with seed 1,
/// half of them any bit pattern, half of them of a run's scale).
#[test]
fn a_journal_reads_back_every_float_as_written() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut values = vec![0.21937721680296174];
    for _ in 0..5_000 {
        values.push(f64::from_bits(rng.random()));
        values.push(rng.random_range(-10.0..10.0));
    }
    values.retain(|v: &f64| v.is_finite());
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("trials.jsonl");
    Journal::create(&path)
        .and_then(|mut journal| journal.append(&values))
        .expect("append");
    let recovered = read::<Vec<f64>>(&path).expect("read back");
    let bits = |values: &[f64]| values.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(recovered.entries.len(), 1);
    assert_eq!(bits(&recovered.entries[0]), bits(&values));
}
