//! Standard output of the commands.
//!
//! A command's report is written whole with [`emit`]. When standard output (or error) is a
//! pipe whose reader has gone (`stickslip validate scene.toml | head -1`), the process ends
//! as other Unix tools do: killed by `SIGPIPE` at the write, quietly (a shell reports
//! status 141), after everything before the report (a run's files) is complete. Any other
//! write error (a full disk) is reported on stderr in one line, with exit code 1.

use std::io::{self, Write};
use std::process::ExitCode;

use super::args::{EXIT_RUN_FAILED, fail};

/// Exit status a shell reports for a process ended by `SIGPIPE` (128 + 13): what [`emit`]
/// returns if a closed pipe reaches it as an error (when `SIGPIPE` could not be restored).
pub const EXIT_CLOSED_PIPE: u8 = 141;

/// Restores the default action of `SIGPIPE` (the Rust runtime ignores it, which turns a
/// write to a closed pipe into an error that `println!` panics on). Called once, first
/// thing in [`super::main`].
pub fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: `signal` with `SIG_DFL` installs no handler; nothing else runs yet.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Writes `text` to standard output and flushes it; returns the command's exit code
/// (success, or a write error reported).
pub fn emit(text: &str) -> ExitCode {
    let mut out = io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => write_failed(&e),
    }
}

/// The exit code (and message) for a failed write to standard output.
pub fn write_failed(e: &io::Error) -> ExitCode {
    if e.kind() == io::ErrorKind::BrokenPipe {
        return ExitCode::from(EXIT_CLOSED_PIPE);
    }
    fail(EXIT_RUN_FAILED, format!("cannot write to standard output: {e}"))
}
