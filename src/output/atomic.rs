//! Files that appear whole or not at all: written to `NAME.part`, renamed to `NAME` on
//! [`PartFile::commit`]; a set of files written at once ([`write_files`]) is renamed into
//! place only when every file of it is written. A run that is killed leaves `NAME.part` holding every line
//! flushed so far (writers hand the operating system whole lines only); a run that fails
//! removes it with [`PartFile::discard`]; `stickslip resume` reopens it with
//! [`PartFile::reopen`], cut back to the length its checkpoint recorded.

use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// Capacity of a part file's buffer: the largest write the operating system receives at once.
const BUFFER: usize = 1 << 16;

/// A buffered file written under a temporary name.
pub struct PartFile {
    part: PathBuf,
    target: PathBuf,
    writer: BufWriter<File>,
}

/// Why a part file cannot be reopened at a checkpointed length.
#[derive(Debug, thiserror::Error)]
pub enum ReopenError {
    #[error("{path} is missing")]
    Missing { path: PathBuf },
    #[error("{path} holds {len} bytes, fewer than the {expected} the checkpoint recorded")]
    Short { path: PathBuf, len: u64, expected: u64 },
    #[error("{path} does not hold at byte {at} what the checkpoint recorded (written by another run?)")]
    Mismatch { path: PathBuf, at: u64 },
    #[error("cannot reopen {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
}

impl PartFile {
    /// Creates `dir/name.part` (truncating any left-over one).
    pub fn create(dir: &Path, name: &str) -> io::Result<PartFile> {
        let (part, target) = Self::names(dir, name);
        // Readable too: a checkpoint reads back the last bytes written.
        let file = OpenOptions::new().read(true).write(true).create(true).truncate(true).open(&part)?;
        Ok(PartFile { part, target, writer: BufWriter::with_capacity(BUFFER, file) })
    }

    fn names(dir: &Path, name: &str) -> (PathBuf, PathBuf) {
        (dir.join(format!("{name}.part")), dir.join(name))
    }

    /// Checks, without changing anything, that `dir/name.part` can be reopened at length
    /// `len`: it exists (or, if a run was killed while renaming its outputs into place,
    /// `dir/name` does), is at least `len` bytes long and holds `tail` just before `len`.
    /// Returns the path that will be reopened.
    pub fn check_reopen(dir: &Path, name: &str, len: u64, tail: &[u8]) -> Result<PathBuf, ReopenError> {
        let (part, target) = Self::names(dir, name);
        let path = if part.exists() {
            part
        } else if target.exists() {
            target
        } else {
            return Err(ReopenError::Missing { path: part });
        };
        let io = |source| ReopenError::Io { path: path.clone(), source };
        let f = File::open(&path).map_err(io)?;
        let have = f.metadata().map_err(io)?.len();
        if have < len {
            return Err(ReopenError::Short { path, len: have, expected: len });
        }
        if tail.len() as u64 > len {
            return Err(ReopenError::Mismatch { path, at: 0 });
        }
        let at = len - tail.len() as u64;
        let mut buf = vec![0; tail.len()];
        f.read_exact_at(&mut buf, at).map_err(io)?;
        if buf != tail {
            return Err(ReopenError::Mismatch { path, at });
        }
        Ok(path)
    }

    /// Reopens `dir/name.part` for appending after cutting it to `len` bytes (call
    /// [`PartFile::check_reopen`] first). A `dir/name` left by a run killed while renaming
    /// its outputs is moved back to `dir/name.part` first.
    pub fn reopen(dir: &Path, name: &str, len: u64) -> io::Result<PartFile> {
        let (part, target) = Self::names(dir, name);
        if !part.exists() && target.exists() {
            std::fs::rename(&target, &part)?;
        }
        let mut f = OpenOptions::new().read(true).write(true).open(&part)?;
        f.set_len(len)?;
        f.seek(SeekFrom::End(0))?;
        Ok(PartFile { part, target, writer: BufWriter::with_capacity(BUFFER, f) })
    }

    pub fn writer(&mut self) -> &mut BufWriter<File> {
        &mut self.writer
    }
    /// Flushes to the operating system (the file stays under its temporary name).
    pub fn flush(&mut self) -> io::Result<()> {
        self.writer.flush()
    }
    /// Flushes and waits until the data is on disk.
    pub fn sync(&mut self) -> io::Result<()> {
        self.writer.flush()?;
        self.writer.get_ref().sync_data()
    }
    /// Reads `buf.len()` bytes of what has been flushed, at offset `at`.
    pub fn read_at(&self, buf: &mut [u8], at: u64) -> io::Result<()> {
        self.writer.get_ref().read_exact_at(buf, at)
    }
    /// Flushes, syncs and renames to the final name.
    pub fn commit(mut self) -> io::Result<PathBuf> {
        self.writer.flush()?;
        self.writer.get_ref().sync_all()?;
        std::fs::rename(&self.part, &self.target)?;
        Ok(self.target)
    }
    /// Removes the temporary file.
    pub fn discard(self) {
        let _ = std::fs::remove_file(&self.part);
    }
}

/// Writes `bytes` to `dir/name` atomically: on failure `dir/name` is unchanged and no
/// `dir/name.part` is left.
pub fn write_whole(dir: &Path, name: &str, bytes: &[u8]) -> io::Result<PathBuf> {
    let (part, target) = write_part(dir, name, bytes)?;
    if let Err(e) = std::fs::rename(&part, &target) {
        let _ = std::fs::remove_file(&part);
        return Err(e);
    }
    Ok(target)
}

/// Writes `bytes` to `dir/name.part` and syncs it, returning `(part, target)` for the
/// rename; on failure removes it. Refuses a target that is a directory (a rename cannot
/// replace it), before writing anything.
fn write_part(dir: &Path, name: &str, bytes: &[u8]) -> io::Result<(PathBuf, PathBuf)> {
    let (part, target) = PartFile::names(dir, name);
    if std::fs::symlink_metadata(&target).is_ok_and(|m| m.is_dir()) {
        return Err(io::Error::from_raw_os_error(libc::EISDIR));
    }
    let mut f = PartFile::create(dir, name)?;
    let written =
        f.writer.write_all(bytes).and_then(|()| f.writer.flush()).and_then(|()| f.writer.get_ref().sync_all());
    match written {
        Ok(()) => Ok((part, target)),
        Err(e) => {
            f.discard();
            Err(e)
        }
    }
}

/// Removes the part files of `(part, target)` pairs, ignoring failures (best effort on a
/// path that already failed).
fn remove_parts(parts: &[(PathBuf, PathBuf)]) {
    for (part, _) in parts {
        let _ = std::fs::remove_file(part);
    }
}

/// A file of a study's or run's outputs could not be written.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {source}")]
pub struct WriteFileError {
    pub path: String,
    #[source]
    pub source: io::Error,
}

/// Writes each `(name, text)` to `dir/name` as one set: every file is written to its
/// `.part` first, and only when all are written are they renamed into place, in order. A
/// failed write removes every `.part` and leaves the old files untouched; a failed rename
/// (a target turned into a directory meanwhile) removes the `.part` files not yet renamed.
/// The error names the failing path. Used for the whole-file outputs (figures, tables,
/// reports).
pub fn write_files<S: AsRef<str>>(dir: &Path, files: &[(&str, S)]) -> Result<(), WriteFileError> {
    let fail = |path: &Path, source| WriteFileError { path: path.display().to_string(), source };
    let mut parts = Vec::with_capacity(files.len());
    for (name, text) in files {
        match write_part(dir, name, text.as_ref().as_bytes()) {
            Ok(pair) => parts.push(pair),
            Err(source) => {
                remove_parts(&parts);
                return Err(fail(&dir.join(name), source));
            }
        }
    }
    for (k, (part, target)) in parts.iter().enumerate() {
        if let Err(source) = std::fs::rename(part, target) {
            remove_parts(&parts[k..]);
            return Err(fail(target, source));
        }
    }
    Ok(())
}

/// Syncs a directory, so that a rename inside it survives a crash of the machine.
pub fn sync_dir(dir: &Path) -> io::Result<()> {
    File::open(dir)?.sync_all()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commit_renames_and_discard_removes() {
        let dir = tempfile::tempdir().unwrap();
        let mut f = PartFile::create(dir.path(), "a.csv").unwrap();
        writeln!(f.writer(), "x").unwrap();
        assert!(dir.path().join("a.csv.part").exists());
        f.commit().unwrap();
        assert_eq!(std::fs::read_to_string(dir.path().join("a.csv")).unwrap(), "x\n");
        assert!(!dir.path().join("a.csv.part").exists());
        let g = PartFile::create(dir.path(), "b.csv").unwrap();
        g.discard();
        assert!(!dir.path().join("b.csv.part").exists() && !dir.path().join("b.csv").exists());
    }

    #[test]
    fn reopen_cuts_back_and_appends() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let mut f = PartFile::create(d, "a.csv").unwrap();
        write!(f.writer(), "h\n1\n2\n3\n4").unwrap(); // "4" is a line cut short by a kill
        f.flush().unwrap();
        drop(f);
        // The checkpoint recorded 6 bytes ("h\n1\n2\n"), ending in "2\n".
        assert!(matches!(PartFile::check_reopen(d, "a.csv", 6, b"1\n3\n"), Err(ReopenError::Mismatch { at: 2, .. })));
        assert!(matches!(PartFile::check_reopen(d, "a.csv", 64, b""), Err(ReopenError::Short { len: 9, .. })));
        assert!(matches!(PartFile::check_reopen(d, "b.csv", 0, b""), Err(ReopenError::Missing { .. })));
        // Checks change nothing.
        assert_eq!(std::fs::read(d.join("a.csv.part")).unwrap(), b"h\n1\n2\n3\n4");
        PartFile::check_reopen(d, "a.csv", 6, b"1\n2\n").unwrap();
        let mut f = PartFile::reopen(d, "a.csv", 6).unwrap();
        writeln!(f.writer(), "x").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read(d.join("a.csv")).unwrap(), b"h\n1\n2\nx\n");
    }

    #[test]
    fn reopen_takes_back_a_file_already_renamed_into_place() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("a.csv"), b"h\n1\n2\n").unwrap();
        assert_eq!(PartFile::check_reopen(d, "a.csv", 4, b"1\n").unwrap(), d.join("a.csv"));
        let f = PartFile::reopen(d, "a.csv", 4).unwrap();
        assert!(!d.join("a.csv").exists());
        f.commit().unwrap();
        assert_eq!(std::fs::read(d.join("a.csv")).unwrap(), b"h\n1\n");
    }

    /// The names in `dir`, sorted.
    fn listing(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        names.sort();
        names
    }

    #[test]
    fn a_set_with_a_target_that_is_a_directory_replaces_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        write_files(d, &[("a.csv", "old a"), ("c.json", "old c")]).unwrap();
        std::fs::create_dir(d.join("b.inp")).unwrap();
        let err = write_files(d, &[("a.csv", "new a"), ("b.inp", "new b"), ("c.json", "new c")]).unwrap_err();
        assert_eq!(err.path, d.join("b.inp").display().to_string());
        assert_eq!(std::fs::read_to_string(d.join("a.csv")).unwrap(), "old a");
        assert_eq!(std::fs::read_to_string(d.join("c.json")).unwrap(), "old c");
        assert!(d.join("b.inp").is_dir());
        assert_eq!(listing(d), ["a.csv", "b.inp", "c.json"], "no .part left");
        // A single file likewise.
        assert!(write_whole(d, "b.inp", b"new b").is_err());
        assert_eq!(listing(d), ["a.csv", "b.inp", "c.json"], "no .part left");
    }

    #[test]
    fn a_set_whose_write_fails_removes_the_parts_already_written() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        write_files(d, &[("a.csv", "old a")]).unwrap();
        // A directory where b.inp's part file would go: creating it fails.
        std::fs::create_dir(d.join("b.inp.part")).unwrap();
        let err = write_files(d, &[("a.csv", "new a"), ("b.inp", "new b")]).unwrap_err();
        assert_eq!(err.path, d.join("b.inp").display().to_string());
        assert_eq!(std::fs::read_to_string(d.join("a.csv")).unwrap(), "old a");
        assert_eq!(listing(d), ["a.csv", "b.inp.part"], "a.csv.part removed");
    }
}
