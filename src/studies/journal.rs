//! The journal of a study (`sweep`, `compare`): `journal.jsonl` in its output directory,
//! one line of JSON per finished run, so that a study killed at any moment keeps every run
//! it finished and can be continued (`stickslip resume DIR`, the same command again, or
//! `stickslip.sweep(..., out=DIR)` in Python).
//!
//! Line 1 is the [`Header`]: the study's kind, its arguments as one line, a fingerprint of
//! its resolved scene (overrides applied), its number of runs, the program version, and the
//! command line that started it. Every further line is an [`Entry`]: a run's index in the
//! study's order of runs, its seed and what it gave. A line is appended with a single
//! `write` of the whole line, newline included, then synced, and only while holding an
//! exclusive lock on the file; so a kill leaves whole lines and at most one cut-short last
//! line (no newline), which opening drops. Any other line that does not parse is damage
//! and an error. After a failed write the file is cut back to its last whole line and no
//! more lines are appended.

use std::fs::{File, OpenOptions};
use std::io::{self, Read, Write};
use std::os::fd::AsRawFd;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::output::atomic::sync_dir;
use crate::output::checkpoint::Checksum;
use crate::scene::Scene;

/// The journal's file name in a study's output directory.
pub const FILE: &str = "journal.jsonl";
/// The first field of every journal's header.
const MAGIC: &str = "stickslip study journal";
/// The format written and read.
pub const FORMAT: u32 = 1;

/// Which study wrote a journal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StudyKind {
    Sweep,
    Compare,
    /// A calibration (`stickslip fit`): a "run" is one evaluation of the misfit.
    Fit,
}

impl StudyKind {
    pub fn as_str(self) -> &'static str {
        match self {
            StudyKind::Sweep => "sweep",
            StudyKind::Compare => "compare",
            StudyKind::Fit => "fit",
        }
    }
}

/// How a study was started from the command line: what `stickslip resume` runs again.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Invocation {
    /// The arguments, program name first.
    pub argv: Vec<String>,
    /// The working directory they are relative to.
    pub cwd: PathBuf,
}

/// The first line of a journal: which study it belongs to.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Header {
    /// Always `stickslip study journal`.
    pub journal: String,
    /// Always [`FORMAT`].
    pub format: u32,
    /// The stickslip version that wrote it.
    pub version: String,
    pub study: StudyKind,
    /// Everything besides the scene that decides the study's runs and files, as one line
    /// (e.g. `--param plate.v --values 0.1,1 --replicas 2`).
    pub arguments: String,
    /// The scene's name.
    pub scene: String,
    /// [`scene_fingerprint`] of the resolved scene (every `--set` applied).
    pub fingerprint: String,
    /// Runs in the study.
    pub runs: usize,
    /// The command line that started it (`None` from Python).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub command: Option<Invocation>,
}

impl Header {
    /// The header of a study of `runs` runs of `scene` with `arguments`.
    pub fn new(study: StudyKind, arguments: String, scene: &Scene, runs: usize, command: Option<Invocation>) -> Self {
        Header {
            journal: MAGIC.to_string(),
            format: FORMAT,
            version: env!("CARGO_PKG_VERSION").to_string(),
            study,
            arguments,
            scene: scene.name.clone(),
            fingerprint: scene_fingerprint(scene),
            runs,
            command,
        }
    }
}

/// 16 hex digits that change with any parameter of the resolved scene (a checksum of its
/// complete TOML text, every field explicit).
pub fn scene_fingerprint(scene: &Scene) -> String {
    let text = toml::to_string(&scene.to_file()).expect("a scene always serializes");
    format!("{:016x}", Checksum::of(text.as_bytes()))
}

/// One finished run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Entry<T> {
    /// Its index in the study's order of runs.
    pub run: usize,
    pub seed: u64,
    pub result: T,
}

/// Why a journal cannot be opened or appended to. Every message is one line naming the file.
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    #[error("cannot {what} {path}: {source}")]
    Io {
        what: &'static str,
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    #[error("{path} is in use by another process (a study is running into {dir})", dir = .path.parent().unwrap_or(Path::new(".")).display())]
    Locked { path: PathBuf },
    #[error("{path} is not a stickslip study journal (line 1: {why})")]
    NotAJournal { path: PathBuf, why: String },
    #[error("{path} has journal format {found}; this stickslip reads format {FORMAT}")]
    Format { path: PathBuf, found: u32 },
    #[error("{path} was written by stickslip {found}; this is stickslip {expected}")]
    Version { path: PathBuf, found: String, expected: String },
    #[error(
        "{path} belongs to another study ({found}); this one is {expected}: nothing was changed (choose another --out, or remove the journal to start afresh)"
    )]
    OtherStudy { path: PathBuf, found: String, expected: String },
    #[error(
        "{path} was written for another scene ({found_name}, fingerprint {found}); this scene is {name}, fingerprint {expected}: nothing was changed (choose another --out, or remove the journal to start afresh)"
    )]
    OtherScene { path: PathBuf, found_name: String, found: String, name: String, expected: String },
    #[error("{path} is damaged at line {line}: {why}")]
    Damaged { path: PathBuf, line: usize, why: String },
    #[error(
        "{path} line {line}: run {run} has seed {found} where this study's seed rule gives {expected}: the journal was written with other seeds (by another version of stickslip, or edited) and cannot be continued; run the study again into a new --out"
    )]
    OtherSeeds { path: PathBuf, line: usize, run: usize, found: u64, expected: u64 },
    #[error("run {run} (seed {seed}) cannot be journaled: its result does not read back from JSON as it was")]
    NotJson { run: usize, seed: u64 },
    #[error("{path} is closed after an earlier write failed")]
    Closed { path: PathBuf },
}

/// An open journal, locked for this process, appending.
#[derive(Debug)]
pub struct Journal {
    path: PathBuf,
    state: Mutex<Appender>,
}

#[derive(Debug)]
struct Appender {
    file: File,
    /// Bytes of whole lines in the file.
    len: u64,
    /// A write failed: the file was cut back and takes no more lines.
    closed: bool,
}

/// A journal opened for a study, with the runs it already holds.
#[derive(Debug)]
pub struct Opened<T> {
    pub journal: Journal,
    /// `done[i]`: run `i`'s result, if the journal holds it.
    pub done: Vec<Option<T>>,
    /// Whether a cut-short last line was dropped.
    pub dropped_tail: bool,
}

impl<T> Opened<T> {
    /// How many runs the journal already holds.
    pub fn count(&self) -> usize {
        self.done.iter().filter(|d| d.is_some()).count()
    }
}

/// The path of the journal in `dir`.
pub fn path_in(dir: &Path) -> PathBuf {
    dir.join(FILE)
}

/// `Ok` if `f` is a regular file: a journal that is a link to a device (such as /dev/zero)
/// would be read without end.
fn regular(f: &File) -> io::Result<()> {
    if f.metadata()?.is_file() { Ok(()) } else { Err(io::Error::other("not a regular file")) }
}

/// Reads the header of the journal in `dir` (for `stickslip resume`). `Ok(None)` if there is
/// no journal, or only a header cut short while it was being created.
pub fn read_header(dir: &Path) -> Result<Option<Header>, JournalError> {
    let path = path_in(dir);
    let mut text = Vec::new();
    match File::open(&path) {
        Ok(mut f) => {
            regular(&f).map_err(io_error("read", &path))?;
            f.read_to_end(&mut text).map_err(io_error("read", &path))?
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io_error("open", &path)(e)),
    };
    match text.iter().position(|&b| b == b'\n') {
        Some(end) => parse_header(&path, &text[..end]).map(Some),
        None => Ok(None),
    }
}

fn io_error(what: &'static str, path: &Path) -> impl FnOnce(io::Error) -> JournalError {
    let path = path.to_path_buf();
    move |source| JournalError::Io { what, path, source }
}

fn parse_header(path: &Path, line: &[u8]) -> Result<Header, JournalError> {
    let not = |why: String| JournalError::NotAJournal { path: path.to_path_buf(), why };
    let value: serde_json::Value = serde_json::from_slice(line).map_err(|e| not(e.to_string()))?;
    if value.get("journal").and_then(|j| j.as_str()) != Some(MAGIC) {
        return Err(not(format!("no \"journal\": \"{MAGIC}\"")));
    }
    if let Some(found) = value.get("format").and_then(|f| f.as_u64()).filter(|&f| f != u64::from(FORMAT)) {
        return Err(JournalError::Format { path: path.to_path_buf(), found: found.min(u64::from(u32::MAX)) as u32 });
    }
    serde_json::from_value(value).map_err(|e| not(e.to_string()))
}

/// Takes an exclusive lock on `file`, without waiting.
fn lock(file: &File, path: &Path) -> Result<(), JournalError> {
    // SAFETY: `flock` on a descriptor this process owns; it touches no memory.
    if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } == 0 {
        return Ok(());
    }
    let e = io::Error::last_os_error();
    if e.kind() == io::ErrorKind::WouldBlock {
        Err(JournalError::Locked { path: path.to_path_buf() })
    } else {
        Err(io_error("lock", path)(e))
    }
}

/// Checks that `found` is the journal of the study `expected` describes.
fn check_same_study(path: &Path, found: &Header, expected: &Header) -> Result<(), JournalError> {
    let path = path.to_path_buf();
    if found.version != expected.version {
        return Err(JournalError::Version { path, found: found.version.clone(), expected: expected.version.clone() });
    }
    let describe = |h: &Header| format!("{} {}, {} runs", h.study.as_str(), h.arguments, h.runs);
    if (found.study, &found.arguments, found.runs) != (expected.study, &expected.arguments, expected.runs) {
        return Err(JournalError::OtherStudy { path, found: describe(found), expected: describe(expected) });
    }
    if (&found.scene, &found.fingerprint) != (&expected.scene, &expected.fingerprint) {
        return Err(JournalError::OtherScene {
            path,
            found_name: found.scene.clone(),
            found: found.fingerprint.clone(),
            name: expected.scene.clone(),
            expected: expected.fingerprint.clone(),
        });
    }
    Ok(())
}

impl Journal {
    /// Opens the journal in `dir` for the study `header` describes, whose run `i` has seed
    /// `seeds[i]`, and locks it. Without a journal (or with one holding no whole line) a new
    /// one is written. An existing journal must be the same study (kind, arguments, runs,
    /// scene fingerprint, version) and every whole line must be a run of it with its seed;
    /// a cut-short last line is dropped. On any error nothing is changed.
    pub fn open<T: DeserializeOwned>(dir: &Path, header: &Header, seeds: &[u64]) -> Result<Opened<T>, JournalError> {
        assert_eq!(header.runs, seeds.len(), "one seed per run");
        let path = path_in(dir);
        // Appending: every write lands at the end, also after a cut-short line is cut off.
        let mut file = OpenOptions::new()
            .read(true)
            .append(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(io_error("open", &path))?;
        regular(&file).map_err(io_error("read", &path))?;
        lock(&file, &path)?;
        let mut text = Vec::new();
        file.read_to_end(&mut text).map_err(io_error("read", &path))?;
        let whole = text.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let mut done: Vec<Option<T>> = (0..seeds.len()).map(|_| None).collect();
        if whole == 0 {
            // New, or cut short while its header was written: start it (again).
            let mut line = serde_json::to_vec(header).expect("a header always serializes");
            line.push(b'\n');
            file.set_len(0).map_err(io_error("write", &path))?;
            let mut appender = Appender { file, len: 0, closed: false };
            appender.append(&line).map_err(io_error("write", &path))?;
            sync_dir(dir).map_err(io_error("sync the directory of", &path))?;
            let journal = Journal { path, state: Mutex::new(appender) };
            return Ok(Opened { journal, done, dropped_tail: false });
        }
        let mut lines = text[..whole].split(|&b| b == b'\n');
        let found = parse_header(&path, lines.next().unwrap_or_default())?;
        check_same_study(&path, &found, header)?;
        for (k, line) in lines.enumerate().filter(|(_, l)| !l.is_empty()) {
            let damaged = |why: String| JournalError::Damaged { path: path.clone(), line: k + 2, why };
            let entry: Entry<T> = serde_json::from_slice(line).map_err(|e| damaged(e.to_string()))?;
            let Some(&seed) = seeds.get(entry.run) else {
                return Err(damaged(format!("run {} of a study of {} runs", entry.run, seeds.len())));
            };
            if entry.seed != seed {
                let (run, found) = (entry.run, entry.seed);
                return Err(JournalError::OtherSeeds { path: path.clone(), line: k + 2, run, found, expected: seed });
            }
            if done[entry.run].replace(entry.result).is_some() {
                return Err(damaged(format!("run {} is there twice", entry.run)));
            }
        }
        let dropped_tail = whole < text.len();
        if dropped_tail {
            file.set_len(whole as u64).map_err(io_error("cut the last line of", &path))?;
        }
        let journal = Journal { path, state: Mutex::new(Appender { file, len: whole as u64, closed: false }) };
        Ok(Opened { journal, done, dropped_tail })
    }

    /// The journal's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Appends run `run` (seed `seed`) with its result, as one line, and syncs it. The
    /// result must read back from JSON as it is. After a failed write the file is cut back
    /// to its whole lines and refuses further lines.
    pub fn append<T: Serialize + DeserializeOwned + PartialEq>(
        &self,
        run: usize,
        seed: u64,
        result: &T,
    ) -> Result<(), JournalError> {
        let entry = Entry { run, seed, result };
        let mut line = serde_json::to_vec(&entry).map_err(|_| JournalError::NotJson { run, seed })?;
        if serde_json::from_slice::<Entry<T>>(&line).ok().as_ref().map(|e| &e.result) != Some(result) {
            return Err(JournalError::NotJson { run, seed });
        }
        line.push(b'\n');
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        if state.closed {
            return Err(JournalError::Closed { path: self.path.clone() });
        }
        state.append(&line).map_err(io_error("write", &self.path))
    }
}

impl Appender {
    /// One write of `line`, then a sync; on failure, cuts the file back and closes.
    fn append(&mut self, line: &[u8]) -> io::Result<()> {
        let written = (&self.file).write_all(line).and_then(|()| self.file.sync_data());
        match written {
            Ok(()) => {
                self.len += line.len() as u64;
                Ok(())
            }
            Err(e) => {
                self.closed = true;
                let _ = self.file.set_len(self.len);
                let _ = self.file.sync_data();
                Err(e)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(arguments: &str) -> Header {
        Header::new(StudyKind::Sweep, arguments.into(), &crate::test_scenes::fig1(), 3, None)
    }

    fn open(dir: &Path, h: &Header) -> Result<Opened<String>, JournalError> {
        Journal::open(dir, h, &[10, 11, 12])
    }

    /// A journal that is a link to a device (read without end) is refused when read and
    /// when opened, in one error.
    #[test]
    fn a_journal_that_is_not_a_file_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::os::unix::fs::symlink("/dev/zero", path_in(dir.path())).unwrap();
        let e = read_header(dir.path()).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        let Err(e) = open(dir.path(), &header("a")) else { panic!("a device as the journal was opened") };
        let e = e.to_string();
        assert!(e.contains("not a regular file"), "{e}");
    }

    #[test]
    fn runs_survive_reopening_and_a_cut_last_line_is_dropped() {
        let d = tempfile::tempdir().unwrap();
        let h = header("--replicas 3");
        let o = open(d.path(), &h).unwrap();
        assert_eq!(o.count(), 0);
        o.journal.append(2, 12, &"c".to_string()).unwrap();
        o.journal.append(0, 10, &"a".to_string()).unwrap();
        drop(o);
        let path = path_in(d.path());
        let whole = std::fs::read(&path).unwrap();
        std::fs::OpenOptions::new().append(true).open(&path).unwrap().write_all(b"{\"run\":1,\"se").unwrap();
        let o = open(d.path(), &h).unwrap();
        assert!(o.dropped_tail);
        assert_eq!(o.done, vec![Some("a".to_string()), None, Some("c".to_string())]);
        assert_eq!(std::fs::read(&path).unwrap(), whole, "the cut line is gone");
        o.journal.append(1, 11, &"b".to_string()).unwrap();
        drop(o);
        assert_eq!(open(d.path(), &h).unwrap().count(), 3);
        assert_eq!(read_header(d.path()).unwrap(), Some(h));
    }

    #[test]
    fn another_study_scene_or_damage_is_refused_and_nothing_changes() {
        let d = tempfile::tempdir().unwrap();
        let h = header("--replicas 3");
        open(d.path(), &h).unwrap().journal.append(1, 11, &"b".to_string()).unwrap();
        let path = path_in(d.path());
        let before = std::fs::read(&path).unwrap();
        let mut other_scene = h.clone();
        other_scene.fingerprint = "0123456789abcdef".into();
        let mut other_version = h.clone();
        other_version.version = "0.0.0".into();
        for (other, what) in [
            (header("--replicas 4"), "another study"),
            (other_scene, "another scene"),
            (other_version, "stickslip 0.0.0"),
        ] {
            let e = open(d.path(), &other).unwrap_err().to_string();
            assert!(e.contains(what) && !e.contains('\n'), "{e}");
        }
        assert!(matches!(
            Journal::open::<String>(d.path(), &h, &[10, 99, 12]),
            Err(JournalError::OtherSeeds { line: 2, run: 1, found: 11, expected: 99, .. })
        ));
        // A damaged line that is not the last.
        let text = String::from_utf8(before.clone()).unwrap();
        std::fs::write(&path, text.replace("\"b\"", "\"b") + "{\"run\":0,\"seed\":10,\"result\":\"a\"}\n").unwrap();
        assert!(matches!(open(d.path(), &h), Err(JournalError::Damaged { line: 2, .. })));
        std::fs::write(&path, [&before[..], b"{\"run\":1,\"seed\":11,\"result\":\"b\"}\n"].concat()).unwrap();
        assert!(matches!(open(d.path(), &h), Err(JournalError::Damaged { line: 3, .. })), "a run twice");
        std::fs::write(&path, b"{\"a\": 1}\n").unwrap();
        assert!(matches!(open(d.path(), &h), Err(JournalError::NotAJournal { .. })));
        std::fs::write(&path, &before).unwrap();
        // Locked while open.
        let o = open(d.path(), &h).unwrap();
        assert!(matches!(open(d.path(), &h), Err(JournalError::Locked { .. })));
        drop(o);
        assert_eq!(std::fs::read(&path).unwrap(), before);
    }

    #[test]
    fn results_that_json_cannot_hold_are_refused() {
        let d = tempfile::tempdir().unwrap();
        let o = Journal::open::<f64>(d.path(), &header("x"), &[10, 11, 12]).unwrap();
        assert!(matches!(o.journal.append(0, 10, &f64::NAN), Err(JournalError::NotJson { run: 0, .. })));
        o.journal.append(0, 10, &0.1).unwrap();
    }
}
