//! Files that appear whole or not at all: written to `NAME.part`, renamed to `NAME` on
//! [`PartFile::commit`]. A run that is killed leaves `NAME.part` holding every line
//! written so far; a run that fails removes it with [`PartFile::discard`].

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// A buffered file written under a temporary name.
pub struct PartFile {
    part: PathBuf,
    target: PathBuf,
    writer: BufWriter<File>,
}

impl PartFile {
    /// Creates `dir/name.part` (truncating any left-over one).
    pub fn create(dir: &Path, name: &str) -> io::Result<PartFile> {
        let target = dir.join(name);
        let part = dir.join(format!("{name}.part"));
        let writer = BufWriter::with_capacity(1 << 16, File::create(&part)?);
        Ok(PartFile { part, target, writer })
    }
    pub fn writer(&mut self) -> &mut BufWriter<File> {
        &mut self.writer
    }
    /// Flushes to the operating system (the file stays under its temporary name).
    pub fn flush(&mut self) -> io::Result<()> {
        self.writer.flush()
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

/// Writes `bytes` to `dir/name` atomically.
pub fn write_whole(dir: &Path, name: &str, bytes: &[u8]) -> io::Result<PathBuf> {
    let mut f = PartFile::create(dir, name)?;
    f.writer().write_all(bytes)?;
    f.commit()
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
}
