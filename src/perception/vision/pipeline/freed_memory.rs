//! Keeping the memory a run frees for the next run.
//!
//! A run allocates about a dozen image-sized buffers (the network's
//! probabilities, masks, labels, distances) and frees them at its end.
//! glibc's malloc gives freed memory at the top of its heap back to the
//! system once it exceeds a trim threshold, which starts at 128 KiB and
//! rises to twice the largest mmapped block freed so far (`mallopt(3)`,
//! M_MMAP_THRESHOLD and M_TRIM_THRESHOLD). With the pipeline's buffers
//! alone it stays below what a run frees, so every run gave its buffers
//! back and faulted them in again, page by page (docs/vision-record.md,
//! "End to end", has the count and the cost). Freeing one larger block once
//! raises both thresholds for the process; other allocators are not
//! harmed by it.

use std::sync::Once;

/// The block allocated and freed once: larger than what a 640 × 480 run
/// has in flight, and at most glibc's ceiling for the dynamic thresholds
/// (32 MiB on 64-bit systems), above which freeing it would change nothing.
const BLOCK_BYTES: usize = 16 << 20;

/// Raises glibc's trim threshold for the process, once: see the module's
/// doc.
pub(super) fn keep_freed_memory() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Zeroed, so the system maps it without the pages being touched;
        // `black_box` keeps the allocation from being optimized away.
        drop(std::hint::black_box(vec![0u8; BLOCK_BYTES]));
    });
}
