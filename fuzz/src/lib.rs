//! What the fuzz targets share: a serial link whose far end sends the fuzz
//! input, and a file holding it for loaders that read a path.

use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};

use cablecell::hw::tactile::SerialLink;

/// A serial link whose far end sends `bytes` whatever is asked: a few
/// bytes a read, some reads finding nothing yet (a port's read timeout),
/// then the port closes. Every idle read is followed by one that hands
/// bytes over, so a driver reading it ends without waiting for its
/// deadline.
pub struct ScriptedLink {
    bytes: Vec<u8>,
    at: usize,
    /// Bytes a read hands over at most.
    piece: usize,
    /// Whether every other read finds nothing.
    stutter: bool,
    idle_next: bool,
    /// The bytes handed over since the last request was written.
    answer: Arc<Mutex<Vec<u8>>>,
}

impl ScriptedLink {
    /// A link from fuzz input: its first byte says how the bytes arrive
    /// (low 6 bits: how many a read at most, less one; top bit: every
    /// other read finds nothing), the rest are what the far end sends.
    pub fn from_input(data: &[u8]) -> Self {
        let (how, bytes) = data.split_first().map_or((0, &[][..]), |(&b, r)| (b, r));
        Self {
            bytes: bytes.to_vec(),
            at: 0,
            piece: usize::from(how & 0x3F) + 1,
            stutter: how & 0x80 != 0,
            idle_next: false,
            answer: Arc::default(),
        }
    }

    /// The bytes handed over since the last request was written, seen
    /// from outside the driver that owns the link.
    pub fn answer(&self) -> Arc<Mutex<Vec<u8>>> {
        Arc::clone(&self.answer)
    }

    /// Whether every byte has been handed over.
    fn drained(&self) -> bool {
        self.at == self.bytes.len()
    }
}

impl Read for ScriptedLink {
    fn read(&mut self, buffer: &mut [u8]) -> io::Result<usize> {
        if self.drained() {
            return Ok(0);
        }
        if self.stutter {
            self.idle_next = !self.idle_next;
            if self.idle_next {
                return Err(io::ErrorKind::TimedOut.into());
            }
        }
        let n = buffer.len().min(self.piece).min(self.bytes.len() - self.at);
        buffer[..n].copy_from_slice(&self.bytes[self.at..self.at + n]);
        lock(&self.answer).extend_from_slice(&self.bytes[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

impl Write for ScriptedLink {
    fn write(&mut self, request: &[u8]) -> io::Result<usize> {
        lock(&self.answer).clear();
        Ok(request.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// The bytes behind `answer`; a panic elsewhere cannot leave them half
/// written.
pub fn lock(answer: &Mutex<Vec<u8>>) -> std::sync::MutexGuard<'_, Vec<u8>> {
    answer.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The far end's bytes arrive after the request, so there is nothing
/// stale to throw away.
impl SerialLink for ScriptedLink {
    fn discard_input(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// Runs `read` on a file holding `bytes`, named `name` in the temporary
/// folder (one a process), and removes it after.
pub fn with_file<T>(name: &str, bytes: &[u8], read: impl FnOnce(&Path) -> T) -> T {
    let path: PathBuf =
        std::env::temp_dir().join(format!("cablecell-fuzz-{}-{name}", std::process::id()));
    std::fs::write(&path, bytes).expect("the temporary folder is writable");
    let result = read(&path);
    // Best effort: a file left behind is harmless, and rewritten next time.
    let _ = std::fs::remove_file(&path);
    result
}
