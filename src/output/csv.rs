//! The CSV writers: `trace.csv` (a row per output sample) and `events.csv` (a row per
//! junction event). Numbers are written in the shortest form that reads back to the same
//! `f64` (ryu), so a trace is byte-identical for the same scene and seed.

use std::fmt::Write as _;
use std::io::{self, Write};
use std::path::Path;

use super::atomic::PartFile;
use crate::observe::{JunctionEvent, Observer, Sample};

/// Appends the shortest round-trip representation of `v`.
#[inline]
pub fn push_f64(line: &mut String, v: f64) {
    // -0.0 is written as 0.0.
    let v = if v == 0.0 { 0.0 } else { v };
    let mut buf = ryu::Buffer::new();
    line.push_str(buf.format(v));
}

/// A CSV file fed by an observer; the first I/O error is kept and reported by `finish`.
pub struct CsvFile {
    file: PartFile,
    line: String,
    error: Option<io::Error>,
    rows: u64,
}

impl CsvFile {
    pub fn create(dir: &Path, name: &str, header: &str) -> io::Result<CsvFile> {
        let mut file = PartFile::create(dir, name)?;
        writeln!(file.writer(), "{header}")?;
        Ok(CsvFile { file, line: String::with_capacity(160), error: None, rows: 0 })
    }
    #[inline]
    fn write_line(&mut self) {
        if self.error.is_none() {
            self.line.push('\n');
            if let Err(e) = self.file.writer().write_all(self.line.as_bytes()) {
                self.error = Some(e);
            }
            self.rows += 1;
        }
        self.line.clear();
    }
    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }
    /// Flushes to the operating system without renaming.
    pub fn flush(&mut self) -> io::Result<()> {
        match self.error.take() {
            Some(e) => Err(e),
            None => self.file.flush(),
        }
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
    pub fn create(dir: &Path) -> io::Result<Self> {
        CsvFile::create(dir, "trace.csv", Self::HEADER).map(TraceWriter)
    }
}

impl Observer for TraceWriter {
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
    pub fn create(dir: &Path) -> io::Result<Self> {
        CsvFile::create(dir, "events.csv", Self::HEADER).map(EventWriter)
    }
}

impl Observer for EventWriter {
    const EVENTS: bool = true;
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
