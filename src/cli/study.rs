//! What `sweep` and `compare` share on the command line: the journal in the output
//! directory (opened before any run, with one line on how many runs it already holds), the
//! stop on SIGINT/SIGTERM, and the one-line report of a study that stopped early.

use std::path::Path;
use std::process::ExitCode;

use serde::de::DeserializeOwned;

use super::args::{EXIT_BAD_INPUT, EXIT_RUN_FAILED, fail};
use super::signals;
use crate::studies::execute::{Continuation, Interrupted};
use crate::studies::journal::{self, Header, Invocation, Journal, Opened, StudyKind};

/// A study's journal, open, and how the study continues from it.
pub(crate) struct StudyJournal<T> {
    pub opened: Opened<T>,
    /// Whether the journal was there before (a study continued).
    pub existed: bool,
}

/// This process's command line and working directory, for the journal's header.
pub(crate) fn invocation() -> Option<Invocation> {
    Some(Invocation { argv: std::env::args().collect(), cwd: std::env::current_dir().ok()? })
}

/// Opens (or starts) the journal in `out` for the study `header` describes; with runs
/// already done, says how many on stdout. A journal of another study is one line, exit 2.
pub(crate) fn open<T: DeserializeOwned>(
    kind: StudyKind,
    out: &Path,
    header: &Header,
    seeds: &[u64],
) -> Result<StudyJournal<T>, ExitCode> {
    // From here on a signal stops the study instead of ending the process.
    signals::stop_on_signals();
    let existed = journal::read_header(out).map_err(|e| fail(EXIT_BAD_INPUT, e))?.is_some();
    let opened = Journal::open(out, header, seeds).map_err(|e| fail(EXIT_BAD_INPUT, e))?;
    if existed {
        println!(
            "continuing the {} in {}: {} of {} runs were already done ({})",
            kind.as_str(),
            out.display(),
            opened.count(),
            seeds.len(),
            journal::FILE
        );
    }
    Ok(StudyJournal { opened, existed })
}

impl<T> StudyJournal<T> {
    /// The continuation for the study's runs: the runs done, the journal, the stop flag of
    /// SIGINT and SIGTERM.
    pub fn continuation(&mut self) -> Continuation<'_, T> {
        let done = std::mem::take(&mut self.opened.done);
        Continuation { done, journal: Some(&self.opened.journal), stop: Some(signals::stop_on_signals()) }
    }

    /// After a run failed (a deterministic failure, which continuing would meet again):
    /// a journal this process started is removed, so that no directory is left behind.
    pub fn discard_if_new(self) {
        if !self.existed {
            let path = self.opened.journal.path().to_path_buf();
            drop(self.opened);
            let _ = std::fs::remove_file(path);
        }
    }
}

/// Where the finished runs are and the command that continues the study.
fn kept(out: &Path) -> String {
    format!(
        "the finished runs are kept in {}; continue with `stickslip resume {}`",
        journal::path_in(out).display(),
        out.display()
    )
}

/// The one line of a study that stopped early, naming the command that continues it.
pub(crate) fn interrupted(e: &Interrupted, out: &Path) -> ExitCode {
    match (e, signals::received()) {
        (Interrupted::Stopped { done, total }, Some((name, code))) => {
            fail(code, format!("stopped by {name} with {done} of {total} runs done; {}", kept(out)))
        }
        _ => fail(EXIT_RUN_FAILED, format!("{e}; {}", kept(out))),
    }
}

/// The one line of a study whose runs are done but whose files could not be written.
pub(crate) fn write_failed(e: impl std::fmt::Display, out: &Path) -> ExitCode {
    fail(EXIT_RUN_FAILED, format!("{e}; {}", kept(out)))
}
