//! The CSV writers: `trace.csv` (a row per output sample) and `events.csv` (a row per
//! junction event). Numbers are written in the shortest form that reads back to the same
//! `f64` (ryu), so a trace is byte-identical for the same scene and seed.
//!
//! Rows are streamed to `NAME.part` (see [`super::atomic`]): the buffer only ever holds whole
//! lines, so the operating system receives whole lines only, and [`CsvFile::position`]
//! records how far the file is written for a checkpoint.

use std::fmt::Write as _;
use std::io::{self, Write};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::atomic::{PartFile, ReopenError};
use crate::observe::{JunctionEvent, Observer, Sample};

/// Appends the shortest round-trip representation of `v`.
#[inline]
pub fn push_f64(line: &mut String, v: f64) {
    // -0.0 is written as 0.0.
    let v = if v == 0.0 { 0.0 } else { v };
    let mut buf = ryu::Buffer::new();
    line.push_str(buf.format(v));
}

/// How far a streamed file is written: what a checkpoint records, and what a resume cuts
/// the file back to.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FilePos {
    /// Bytes written (header included); always the end of a line.
    pub bytes: u64,
    /// Rows written (header excluded).
    pub rows: u64,
    /// The last bytes before `bytes` (at most [`FilePos::TAIL`]), by which a resume
    /// recognises the file.
    pub tail: Vec<u8>,
}

impl FilePos {
    pub const TAIL: usize = 256;
}

/// A CSV file fed by an observer; the first I/O error is kept and reported by `finish`.
pub struct CsvFile {
    file: PartFile,
    line: String,
    error: Option<io::Error>,
    rows: u64,
    bytes: u64,
}

impl CsvFile {
    pub fn create(dir: &Path, name: &str, header: &str) -> io::Result<CsvFile> {
        let mut file = PartFile::create(dir, name)?;
        writeln!(file.writer(), "{header}")?;
        let bytes = header.len() as u64 + 1;
        Ok(CsvFile { file, line: String::with_capacity(160), error: None, rows: 0, bytes })
    }
    /// Checks that `dir/name.part` can be continued from `pos` (changes nothing).
    pub fn check_resume(dir: &Path, name: &str, pos: &FilePos) -> Result<(), ReopenError> {
        PartFile::check_reopen(dir, name, pos.bytes, &pos.tail).map(|_| ())
    }
    /// Continues `dir/name.part` from `pos`: the file is cut back to `pos.bytes` (dropping
    /// whatever was written after the checkpoint) and rows are appended after it.
    pub fn resume(dir: &Path, name: &str, pos: &FilePos) -> io::Result<CsvFile> {
        let file = PartFile::reopen(dir, name, pos.bytes)?;
        Ok(CsvFile { file, line: String::with_capacity(160), error: None, rows: pos.rows, bytes: pos.bytes })
    }
    #[inline]
    fn write_line(&mut self) {
        if self.error.is_none() {
            self.line.push('\n');
            if let Err(e) = self.file.writer().write_all(self.line.as_bytes()) {
                self.error = Some(e);
            }
            self.rows += 1;
            self.bytes += self.line.len() as u64;
        }
        self.line.clear();
    }
    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }
    /// Bytes written so far (header included).
    pub fn bytes(&self) -> u64 {
        self.bytes
    }
    /// Flushes to the operating system without renaming.
    pub fn flush(&mut self) -> io::Result<()> {
        match self.error.take() {
            Some(e) => Err(e),
            None => self.file.flush(),
        }
    }
    /// Flushes, syncs to disk and returns how far the file is written.
    pub fn position(&mut self) -> io::Result<FilePos> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.file.sync()?;
        let n = (FilePos::TAIL as u64).min(self.bytes);
        let mut tail = vec![0; n as usize];
        self.file.read_at(&mut tail, self.bytes - n)?;
        Ok(FilePos { bytes: self.bytes, rows: self.rows, tail })
    }
    /// Renames the file into place, or reports the first write error.
    pub fn finish(self) -> io::Result<()> {
        match self.error {
            Some(e) => {
                self.file.discard();
                Err(e)
            }
            None => self.file.commit().map(|_| ()),
        }
    }
    pub fn discard(self) {
        self.file.discard()
    }
}

/// `trace.csv`: `t,x,v,friction,bond_force,attached_fraction`.
pub struct TraceWriter(pub CsvFile);

impl TraceWriter {
    pub const HEADER: &'static str = "t,x,v,friction,bond_force,attached_fraction";
    pub const NAME: &'static str = "trace.csv";
    pub fn create(dir: &Path) -> io::Result<Self> {
        CsvFile::create(dir, Self::NAME, Self::HEADER).map(TraceWriter)
    }
}

impl Observer for TraceWriter {
    const STRETCHES: bool = true;
    #[inline]
    fn integrals_after(&self) -> f64 {
        f64::INFINITY
    }
    fn sample(&mut self, s: &Sample) {
        let l = &mut self.0.line;
        for (i, v) in [s.t, s.x, s.v, s.friction, s.bond_force, s.attached_fraction()].into_iter().enumerate() {
            if i > 0 {
                l.push(',');
            }
            push_f64(l, v);
        }
        self.0.write_line();
    }
}

/// `events.csv`: `t,junction,kind,extension,tension`.
pub struct EventWriter(pub CsvFile);

impl EventWriter {
    pub const HEADER: &'static str = "t,junction,kind,extension,tension";
    pub const NAME: &'static str = "events.csv";
    pub fn create(dir: &Path) -> io::Result<Self> {
        CsvFile::create(dir, Self::NAME, Self::HEADER).map(EventWriter)
    }
}

impl Observer for EventWriter {
    const EVENTS: bool = true;
    const STRETCHES: bool = true;
    #[inline]
    fn integrals_after(&self) -> f64 {
        f64::INFINITY
    }
    #[inline]
    fn event(&mut self, e: &JunctionEvent) {
        let l = &mut self.0.line;
        push_f64(l, e.t);
        l.push(',');
        let _ = write!(l, "{}", e.junction);
        l.push(',');
        l.push_str(e.kind.as_str());
        l.push(',');
        push_f64(l, e.extension);
        l.push(',');
        push_f64(l, e.tension);
        self.0.write_line();
    }
}
