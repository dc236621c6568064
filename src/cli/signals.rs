//! SIGINT and SIGTERM during a study (`sweep`, `compare`): the first one sets the study's
//! [`StopFlag`] (no run starts any more, runs in flight stop at their next grid stop and are
//! dropped, the finished ones stay in the journal) and arms the default action of that
//! signal, so a second one ends the process at once, which loses nothing either. The
//! handlers are signal-hook's, which only store to atomics.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering::Relaxed};

use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::flag;

use crate::runner::StopFlag;

static FLAG: OnceLock<StopFlag> = OnceLock::new();
/// The signal received, or 0.
static RECEIVED: AtomicUsize = AtomicUsize::new(0);
/// Per signal (SIGINT, SIGTERM): received once, so the next one takes the default action.
static ARMED: [AtomicBool; 2] = [AtomicBool::new(false), AtomicBool::new(false)];

/// Installs the handlers for SIGINT and SIGTERM (once); returns the flag they set.
pub(crate) fn stop_on_signals() -> &'static StopFlag {
    let mut installed = false;
    let flag = FLAG.get_or_init(|| {
        installed = true;
        StopFlag::new()
    });
    if installed {
        for (signal, armed) in [SIGINT, SIGTERM].into_iter().zip(&ARMED) {
            // The default action first: it runs only once the flag below is set, by an
            // earlier signal.
            let registered = flag::register_conditional_default(signal, armed)
                .and_then(|_| flag::register(signal, armed))
                .and_then(|_| flag::register(signal, flag.shared()))
                .and_then(|_| flag::register_usize(signal, &RECEIVED, signal as usize));
            registered.expect("SIGINT and SIGTERM accept handlers");
        }
    }
    flag
}

/// The signal that stopped the study, as its name and the exit code that reports it
/// (128 + its number, as a shell reports a process it ended).
pub(crate) fn received() -> Option<(&'static str, u8)> {
    match RECEIVED.load(Relaxed) as libc::c_int {
        SIGINT => Some(("SIGINT", 128 + SIGINT as u8)),
        SIGTERM => Some(("SIGTERM", 128 + SIGTERM as u8)),
        _ => None,
    }
}
