//! The campaign's trial record: one JSON object per finished trial, one per
//! line (JSON Lines), made durable before the next trial starts.
//!
//! A campaign may be killed at any moment. Every entry whose `append`
//! returned is on disk; the only damage a kill can do is a last line cut
//! short. Reading reports such a tail and drops it (its trial never
//! finished being recorded, so a resumed campaign runs it again), and
//! [`Journal::resume`] cuts it off before appending, so the file stays valid
//! JSON Lines. A *complete* line that does not parse is not kill damage but
//! a real fault, and is refused rather than silently dropped.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use serde::Serialize;
use serde::de::DeserializeOwned;

/// Errors of reading and writing a journal.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum JournalError {
    /// The file or its folder could not be created, read, written or
    /// synced: check the path, its permissions and the free space.
    #[error("{}: journal I/O failed: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A complete line is not a valid entry. A kill can only cut the last
    /// line short, so this is a hand edit, a different program's file or a
    /// changed entry format; the journal is refused rather than resumed
    /// without that trial. Fix or remove the line, or start a new journal.
    #[error(
        "{}:{line}: not a valid journal entry: {message}; fix or remove the line, or use another output folder",
        path.display()
    )]
    Corrupt {
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        message: String,
    },
    /// `create` found a journal with entries already at this path: resume
    /// it, or write the new campaign to another output folder.
    #[error(
        "{}: a journal already exists here ({len_bytes} bytes): resume it, or choose another output folder",
        path.display()
    )]
    AlreadyExists { path: PathBuf, len_bytes: u64 },
    /// The path names something other than a regular file (a folder, a
    /// device, a link to one): a journal is a file of JSON lines. Remove it
    /// or choose another output folder.
    #[error("{}: not a regular file, so not a journal: remove it, or choose another output folder", path.display())]
    NotAFile { path: PathBuf },
    /// The file is larger than any campaign's journal: the campaign file
    /// allows 10 000 trials per policy, of a few kB each. It is not read.
    #[error(
        "{}: {len_bytes} bytes, more than a journal holds ({max} bytes at most): not a campaign's journal",
        path.display(),
        max = MAX_JOURNAL_BYTES
    )]
    TooLarge { path: PathBuf, len_bytes: u64 },
    /// Another open journal (in this or another process) holds the file's
    /// lock: two campaigns writing one journal would interleave their
    /// trials. Stop the other campaign or choose another output folder.
    #[error("{}: the journal is in use by another campaign", path.display())]
    Locked { path: PathBuf },
    /// The entry cannot be written as one JSON line that reads back as the
    /// same type, e.g. a NaN float (which JSON writes as `null`) or a map
    /// with non-string keys. Nothing was written.
    #[error("{}: entry cannot be recorded as JSON: {source}", path.display())]
    Encode {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    /// An earlier append failed, so the file may end in a partial line or an
    /// unsynced one. Resume the journal to continue from a clean state.
    #[error("{}: an earlier append failed; resume the journal to continue", path.display())]
    Poisoned { path: PathBuf },
}

/// The most bytes a journal may hold: far more than the largest campaign
/// writes, and a bound on what a resume reads.
pub const MAX_JOURNAL_BYTES: u64 = 1 << 30;

/// What was read back from a journal.
#[derive(Debug, Clone, PartialEq)]
pub struct Recovered<T> {
    /// Every entry of a complete line, in file order.
    pub entries: Vec<T>,
    /// The 1-based line of each entry.
    pub lines: Vec<usize>,
    /// Bytes of a final line cut short by a kill, dropped. 0 if none.
    pub truncated_tail_bytes: usize,
    /// 1-based line number of that dropped tail, `None` if there is none.
    pub truncated_tail_line: Option<usize>,
}

/// A journal open for appending. It holds an exclusive lock on the file
/// until dropped, and needs no explicit close: every `append` that returned
/// is already durable.
#[derive(Debug)]
pub struct Journal {
    path: PathBuf,
    file: File,
    /// Set when a write or sync failed, so that no further line is glued
    /// onto a possibly partial one.
    poisoned: bool,
}

impl Journal {
    /// Creates the journal at `path`, creating its parent folders.
    ///
    /// An existing empty file is taken over; an existing non-empty one is
    /// refused with [`JournalError::AlreadyExists`] rather than truncated, so
    /// that a repeated command cannot wipe a finished campaign.
    pub fn create(path: &Path) -> Result<Journal, JournalError> {
        let file = open_locked(path)?;
        let len_bytes = file.metadata().map_err(io_error(path))?.len();
        if len_bytes > 0 {
            return Err(JournalError::AlreadyExists {
                path: path.to_path_buf(),
                len_bytes,
            });
        }
        sync_parent_dir(path).map_err(io_error(path))?;
        Ok(Journal {
            path: path.to_path_buf(),
            file,
            poisoned: false,
        })
    }

    /// Opens an existing journal to continue it: reads every complete
    /// entry, cuts off a truncated tail, and positions for appending. A
    /// missing file is the same as an empty one (it is created, with its
    /// parent folders). A corrupt complete line is an error, and then the
    /// file is left untouched.
    pub fn resume<T: DeserializeOwned>(
        path: &Path,
    ) -> Result<(Journal, Recovered<T>), JournalError> {
        let mut file = open_locked(path)?;
        let bytes = read_bounded(&mut file, path)?;
        let (recovered, complete_len) = parse(&bytes, path)?;
        if recovered.truncated_tail_bytes > 0 {
            file.set_len(complete_len as u64)
                .and_then(|()| file.sync_data())
                .map_err(io_error(path))?;
        }
        sync_parent_dir(path).map_err(io_error(path))?;
        let journal = Journal {
            path: path.to_path_buf(),
            file,
            poisoned: false,
        };
        Ok((journal, recovered))
    }

    /// Appends one entry as a single line and makes it durable before
    /// returning.
    ///
    /// The line is written with one `write_all` straight to the file (there
    /// is no user-space buffer to flush) and then `sync_data`ed. The entry
    /// is first checked to read back as `T`, so that a resume can never
    /// trip over a line this journal wrote; if it does not, nothing is
    /// written and the journal stays usable. After an I/O failure the
    /// journal refuses further appends ([`JournalError::Poisoned`]).
    pub fn append<T: Serialize + DeserializeOwned>(
        &mut self,
        entry: &T,
    ) -> Result<(), JournalError> {
        if self.poisoned {
            return Err(JournalError::Poisoned {
                path: self.path.clone(),
            });
        }
        let encode_error = |source| JournalError::Encode {
            path: self.path.clone(),
            source,
        };
        let mut line = serde_json::to_vec(entry).map_err(encode_error)?;
        serde_json::from_slice::<T>(&line).map_err(encode_error)?;
        line.push(b'\n');
        let written = self
            .file
            .write_all(&line)
            .and_then(|()| self.file.sync_data());
        if let Err(source) = written {
            self.poisoned = true;
            return Err(JournalError::Io {
                path: self.path.clone(),
                source,
            });
        }
        Ok(())
    }

    /// The journal's file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// Reads a journal without changing it, for reports. Unlike
/// [`Journal::resume`], a missing file is an error, and a running campaign
/// may hold the file meanwhile: its line being written shows as a
/// truncated tail.
pub fn read<T: DeserializeOwned>(path: &Path) -> Result<Recovered<T>, JournalError> {
    refuse_non_file(path)?;
    let mut file = File::open(path).map_err(io_error(path))?;
    let bytes = read_bounded(&mut file, path)?;
    let (recovered, _complete_len) = parse(&bytes, path)?;
    Ok(recovered)
}

/// Parses the complete lines of `bytes` and measures the tail after the last
/// newline. Returns what was recovered and the length of the complete part.
/// Lines holding only whitespace are skipped (a hand-edited file may end in
/// a blank line); line numbers still count them.
fn parse<T: DeserializeOwned>(
    bytes: &[u8],
    path: &Path,
) -> Result<(Recovered<T>, usize), JournalError> {
    let complete_len = bytes
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |last_newline| last_newline + 1);
    let (complete, tail) = bytes.split_at(complete_len);
    let mut entries = Vec::new();
    let mut lines = Vec::new();
    let mut complete_lines = 0;
    for line in complete.split_inclusive(|&b| b == b'\n') {
        complete_lines += 1;
        if line.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        let entry = serde_json::from_slice(line).map_err(|e| JournalError::Corrupt {
            path: path.to_path_buf(),
            line: complete_lines,
            message: e.to_string(),
        })?;
        entries.push(entry);
        lines.push(complete_lines);
    }
    let recovered = Recovered {
        entries,
        lines,
        truncated_tail_bytes: tail.len(),
        truncated_tail_line: (!tail.is_empty()).then_some(complete_lines + 1),
    };
    Ok((recovered, complete_len))
}

/// The whole file, unless it holds more than [`MAX_JOURNAL_BYTES`] (read
/// through a bound, so that no file, whatever its metadata says, is read
/// without end).
fn read_bounded(file: &mut File, path: &Path) -> Result<Vec<u8>, JournalError> {
    let mut bytes = Vec::new();
    file.take(MAX_JOURNAL_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io_error(path))?;
    if bytes.len() as u64 > MAX_JOURNAL_BYTES {
        let len_bytes = file.metadata().map_or(bytes.len() as u64, |m| m.len());
        return Err(JournalError::TooLarge {
            path: path.to_path_buf(),
            len_bytes,
        });
    }
    Ok(bytes)
}

/// Refuses a path that is there but no regular file (after links): a
/// folder, or a device such as `/dev/zero` that would be read without end.
fn refuse_non_file(path: &Path) -> Result<(), JournalError> {
    match std::fs::metadata(path) {
        Ok(meta) if !meta.is_file() => Err(JournalError::NotAFile {
            path: path.to_path_buf(),
        }),
        _ => Ok(()),
    }
}

/// Opens (creating if missing, with its folders) `path` for reading and
/// appending, and takes its exclusive lock. Only a regular file is opened.
fn open_locked(path: &Path) -> Result<File, JournalError> {
    refuse_non_file(path)?;
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(io_error(path))?;
    }
    let file = OpenOptions::new()
        .read(true)
        .append(true)
        .create(true)
        .open(path)
        .map_err(io_error(path))?;
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(TryLockError::WouldBlock) => Err(JournalError::Locked {
            path: path.to_path_buf(),
        }),
        Err(TryLockError::Error(source)) => Err(io_error(path)(source)),
    }
}

/// Syncs the folder holding `path`, so that a newly created journal's
/// directory entry survives a power loss along with its synced contents.
#[cfg(unix)]
fn sync_parent_dir(path: &Path) -> std::io::Result<()> {
    let parent = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    File::open(parent)?.sync_all()
}

/// Folders cannot be opened and synced this way off Unix; the file's own
/// syncs are all there is.
#[cfg(not(unix))]
fn sync_parent_dir(_path: &Path) -> std::io::Result<()> {
    Ok(())
}

fn io_error(path: &Path) -> impl Fn(std::io::Error) -> JournalError + '_ {
    move |source| JournalError::Io {
        path: path.to_path_buf(),
        source,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    struct Entry {
        trial: u32,
        n_mm: f64,
    }

    fn entry(trial: u32) -> Entry {
        Entry {
            trial,
            n_mm: 0.25 * f64::from(trial),
        }
    }

    fn journal_path(dir: &tempfile::TempDir) -> PathBuf {
        dir.path().join("out").join("trials.jsonl")
    }

    fn append_raw(path: &Path, bytes: &[u8]) {
        let mut file = OpenOptions::new().append(true).open(path).unwrap();
        file.write_all(bytes).unwrap();
    }

    #[test]
    fn append_then_read_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = journal_path(&dir);
        let mut journal = Journal::create(&path).unwrap();
        assert_eq!(journal.path(), path);
        for trial in 0..3 {
            journal.append(&entry(trial)).unwrap();
        }
        let recovered: Recovered<Entry> = read(&path).unwrap();
        assert_eq!(recovered.entries, vec![entry(0), entry(1), entry(2)]);
        assert_eq!(recovered.truncated_tail_bytes, 0);
        assert_eq!(recovered.truncated_tail_line, None);
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 3);
        assert!(text.ends_with('\n'));
    }

    #[test]
    fn entries_survive_drop_and_resume_continues() {
        let dir = tempfile::tempdir().unwrap();
        let path = journal_path(&dir);
        {
            let mut journal = Journal::create(&path).unwrap();
            journal.append(&entry(0)).unwrap();
            journal.append(&entry(1)).unwrap();
        }
        let (mut journal, recovered) = Journal::resume::<Entry>(&path).unwrap();
        assert_eq!(recovered.entries, vec![entry(0), entry(1)]);
        journal.append(&entry(2)).unwrap();
        drop(journal);
        let recovered: Recovered<Entry> = read(&path).unwrap();
        assert_eq!(recovered.entries, vec![entry(0), entry(1), entry(2)]);
    }

    #[test]
    fn truncated_tail_is_reported_dropped_and_cut_on_resume() {
        let dir = tempfile::tempdir().unwrap();
        let path = journal_path(&dir);
        let mut journal = Journal::create(&path).unwrap();
        journal.append(&entry(0)).unwrap();
        journal.append(&entry(1)).unwrap();
        drop(journal);
        let clean_two = std::fs::read(&path).unwrap();
        // A kill halfway through writing the third line.
        let full = serde_json::to_vec(&entry(2)).unwrap();
        let half = &full[..full.len() / 2];
        append_raw(&path, half);

        let recovered: Recovered<Entry> = read(&path).unwrap();
        assert_eq!(recovered.entries, vec![entry(0), entry(1)]);
        assert_eq!(recovered.truncated_tail_bytes, half.len());
        assert_eq!(recovered.truncated_tail_line, Some(3));
        // Reading changed nothing.
        assert_eq!(
            std::fs::read(&path).unwrap().len(),
            clean_two.len() + half.len()
        );

        let (mut journal, recovered) = Journal::resume::<Entry>(&path).unwrap();
        assert_eq!(recovered.entries, vec![entry(0), entry(1)]);
        assert_eq!(recovered.truncated_tail_bytes, half.len());
        assert_eq!(std::fs::read(&path).unwrap(), clean_two);
        journal.append(&entry(2)).unwrap();
        drop(journal);

        let recovered: Recovered<Entry> = read(&path).unwrap();
        assert_eq!(recovered.entries, vec![entry(0), entry(1), entry(2)]);
        assert_eq!(recovered.truncated_tail_bytes, 0);
    }

    #[test]
    fn complete_line_without_newline_counts_as_truncated() {
        // A kill after the JSON but before its newline: `append` had not
        // returned, so the trial is run again rather than half-trusted.
        let dir = tempfile::tempdir().unwrap();
        let path = journal_path(&dir);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, br#"{"trial":0,"n_mm":0.0}"#).unwrap();
        let recovered: Recovered<Entry> = read(&path).unwrap();
        assert!(recovered.entries.is_empty());
        assert_eq!(recovered.truncated_tail_line, Some(1));
    }

    #[test]
    fn corrupt_complete_line_is_an_error_naming_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = journal_path(&dir);
        let mut journal = Journal::create(&path).unwrap();
        journal.append(&entry(0)).unwrap();
        drop(journal);
        // A blank line 2 (skipped), a corrupt line 3, a valid line 4.
        append_raw(&path, b"\n{\"trial\": oops}\n");
        append_raw(&path, &serde_json::to_vec(&entry(3)).unwrap());
        append_raw(&path, b"\n");
        let before = std::fs::read(&path).unwrap();

        let err = read::<Entry>(&path).unwrap_err();
        assert!(
            matches!(&err, JournalError::Corrupt { line: 3, path: p, .. } if p == &path),
            "{err:?}"
        );
        assert!(err.to_string().contains("trials.jsonl:3:"), "{err}");
        let err = Journal::resume::<Entry>(&path).unwrap_err();
        assert!(
            matches!(err, JournalError::Corrupt { line: 3, .. }),
            "{err:?}"
        );
        assert_eq!(std::fs::read(&path).unwrap(), before);
    }

    #[test]
    fn resume_of_missing_file_is_empty_and_creates_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = journal_path(&dir);
        let (mut journal, recovered) = Journal::resume::<Entry>(&path).unwrap();
        assert!(recovered.entries.is_empty());
        assert_eq!(recovered.truncated_tail_bytes, 0);
        journal.append(&entry(0)).unwrap();
        drop(journal);
        assert_eq!(read::<Entry>(&path).unwrap().entries, vec![entry(0)]);
    }

    #[test]
    fn read_of_missing_file_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let err = read::<Entry>(&journal_path(&dir)).unwrap_err();
        assert!(matches!(err, JournalError::Io { .. }), "{err:?}");
    }

    #[test]
    fn create_refuses_non_empty_file_but_takes_an_empty_one() {
        let dir = tempfile::tempdir().unwrap();
        let path = journal_path(&dir);
        let mut journal = Journal::create(&path).unwrap();
        journal.append(&entry(0)).unwrap();
        drop(journal);
        let err = Journal::create(&path).unwrap_err();
        assert!(matches!(err, JournalError::AlreadyExists { .. }), "{err:?}");
        assert!(err.to_string().contains("resume"), "{err}");
        assert_eq!(read::<Entry>(&path).unwrap().entries, vec![entry(0)]);

        let empty = dir.path().join("empty.jsonl");
        std::fs::write(&empty, b"").unwrap();
        Journal::create(&empty).unwrap();
    }

    #[test]
    fn second_writer_is_locked_out() {
        let dir = tempfile::tempdir().unwrap();
        let path = journal_path(&dir);
        let _journal = Journal::create(&path).unwrap();
        let err = Journal::resume::<Entry>(&path).unwrap_err();
        assert!(matches!(err, JournalError::Locked { .. }), "{err:?}");
        // Reading for a report is still allowed.
        read::<Entry>(&path).unwrap();
    }

    #[test]
    fn entry_that_would_not_read_back_is_refused_and_nothing_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = journal_path(&dir);
        let mut journal = Journal::create(&path).unwrap();
        let nan = Entry {
            trial: 0,
            n_mm: f64::NAN,
        };
        let err = journal.append(&nan).unwrap_err();
        assert!(matches!(err, JournalError::Encode { .. }), "{err:?}");
        assert_eq!(std::fs::read(&path).unwrap().len(), 0);
        journal.append(&entry(1)).unwrap();
        assert_eq!(read::<Entry>(&path).unwrap().entries, vec![entry(1)]);
    }
}
