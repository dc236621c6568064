//! SIGINT and SIGTERM during a study (`sweep`, `compare`): the first one sets the study's
//! [`StopFlag`] (no run starts any more, runs in flight stop at their next grid stop and are
//! dropped, the finished ones stay in the journal) and puts the default action back, so a
//! second signal ends the process at once, which loses nothing either.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicI32, Ordering::Relaxed};

use crate::runner::StopFlag;

static FLAG: OnceLock<StopFlag> = OnceLock::new();
/// The signal received, or 0.
static RECEIVED: AtomicI32 = AtomicI32::new(0);

extern "C" fn on_signal(signal: libc::c_int) {
    // Async-signal-safe: atomic loads and stores only (the flag exists before the handler).
    RECEIVED.store(signal, Relaxed);
    if let Some(flag) = FLAG.get() {
        flag.request();
    }
}

/// Installs the handlers for SIGINT and SIGTERM; returns the flag they set.
pub(crate) fn stop_on_signals() -> &'static StopFlag {
    let flag = FLAG.get_or_init(StopFlag::new);
    for signal in [libc::SIGINT, libc::SIGTERM] {
        // SAFETY: a zeroed `sigaction` is valid; the handler only touches atomics; the
        // previous action is not asked for.
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
            action.sa_flags = libc::SA_RESETHAND | libc::SA_RESTART;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(signal, &action, std::ptr::null_mut());
        }
    }
    flag
}

/// The signal that stopped the study, as its name and the exit code that reports it
/// (128 + its number, as a shell reports a process it ended).
pub(crate) fn received() -> Option<(&'static str, u8)> {
    match RECEIVED.load(Relaxed) {
        libc::SIGINT => Some(("SIGINT", 128 + libc::SIGINT as u8)),
        libc::SIGTERM => Some(("SIGTERM", 128 + libc::SIGTERM as u8)),
        _ => None,
    }
}
