//! Progress on stderr: simulated time against `t_end`, events (exact engine) or steps
//! (fixed engine) per second, and the time left.
//!
//! Nothing here touches the engine or the output grid, so a run's results are the same
//! with and without progress:
//! - a [`Probe`] observer stores the end time of every segment the engine reports in an
//!   atomic (one relaxed store per event or step), so the bar moves between grid stops
//!   however coarse the grid;
//! - the runner publishes the engine's event or step counter at grid stops (when its
//!   pacer looks at the clock anyway);
//! - a thread wakes five times a second, reads both, and draws with `indicatif`.
//!
//! The bar is drawn only when stderr is a terminal, and only once the run has lasted
//! [`SHOW_AFTER`]: short runs, and runs whose stderr is a file or a pipe, print nothing.

use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use indicatif::{HumanDuration, ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::observe::{Observer, Piece, Segment, Stretch};

/// A run that lasts longer than this shows progress.
pub const SHOW_AFTER: Duration = Duration::from_millis(1500);
/// Interval between redraws.
const TICK: Duration = Duration::from_millis(200);
/// Resolution of the bar's position.
const SCALE: u64 = 1_000_000;

#[derive(Debug, Default)]
struct Shared {
    /// Bits of the latest simulated time reported.
    t: AtomicU64,
    /// Engine work counter (events or steps) at the last publication, and when it was
    /// published (nanoseconds since the progress started).
    work: AtomicU64,
    work_nanos: AtomicU64,
    done: AtomicBool,
}

/// The observer that lets the progress thread see the simulated time.
#[derive(Debug)]
pub struct Probe(Arc<Shared>);

impl Observer for Probe {
    const STRETCHES: bool = true;
    #[inline]
    fn segment(&mut self, s: &Segment) {
        self.0.t.store(s.t1.to_bits(), Relaxed);
    }
    #[inline]
    fn piece(&mut self, p: &Piece) {
        self.0.t.store(p.t1.to_bits(), Relaxed);
    }
    #[inline]
    fn stretch(&mut self, s: &Stretch) {
        self.0.t.store(s.t1.to_bits(), Relaxed);
    }
    #[inline]
    fn integrals_after(&self) -> f64 {
        f64::INFINITY
    }
}

/// What the progress line reports.
#[derive(Clone, Copy, Debug)]
pub struct Span {
    /// Simulated time at the start of this process (0, or the checkpoint's time).
    pub t0: f64,
    pub t_end: f64,
    /// Work counter at the start of this process.
    pub work0: u64,
    /// `"events"` or `"steps"`.
    pub unit: &'static str,
}

/// The progress display of one run (possibly inactive).
pub struct Progress {
    shared: Arc<Shared>,
    started: Instant,
    thread: Option<JoinHandle<()>>,
}

impl Progress {
    /// Starts the display if `wanted` and stderr is a terminal; the probe is returned
    /// either way (it costs one store per segment). The environment variable
    /// `STICKSLIP_PROGRESS` overrides the terminal test: `never` (or `0`) turns the display
    /// off, `always` (or `1`) runs it even when stderr is not a terminal (indicatif then
    /// draws nothing, but everything else runs: tests use it).
    pub fn start(wanted: bool, span: Span) -> (Progress, Probe) {
        let active = wanted
            && match std::env::var("STICKSLIP_PROGRESS").as_deref() {
                Ok("never" | "0") => false,
                Ok("always" | "1") => true,
                _ => std::io::stderr().is_terminal(),
            };
        Self::start_on(active, span, ProgressDrawTarget::stderr)
    }

    /// As [`Progress::start`], drawing to `target` (tests draw to a hidden target).
    pub fn start_on(active: bool, span: Span, target: fn() -> ProgressDrawTarget) -> (Progress, Probe) {
        let shared = Arc::new(Shared::default());
        shared.t.store(span.t0.to_bits(), Relaxed);
        shared.work.store(span.work0, Relaxed);
        let started = Instant::now();
        let thread = active.then(|| {
            let shared = Arc::clone(&shared);
            std::thread::spawn(move || draw_loop(&shared, started, span, target))
        });
        (Progress { shared: Arc::clone(&shared), started, thread }, Probe(shared))
    }

    /// Publishes the engine's work counter (called at grid stops).
    pub fn publish(&self, work: u64) {
        if self.thread.is_some() {
            self.shared.work.store(work, Relaxed);
            self.shared.work_nanos.store(self.started.elapsed().as_nanos() as u64, Relaxed);
        }
    }

    /// Stops the display and clears the bar.
    pub fn finish(mut self) {
        self.stop();
    }

    fn stop(&mut self) {
        if let Some(h) = self.thread.take() {
            self.shared.done.store(true, Relaxed);
            h.thread().unpark();
            let _ = h.join();
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.stop();
    }
}

fn draw_loop(shared: &Shared, started: Instant, span: Span, target: fn() -> ProgressDrawTarget) {
    let bar = ProgressBar::with_draw_target(Some(SCALE), ProgressDrawTarget::hidden());
    let style = ProgressStyle::with_template("{bar:30.cyan/blue} {percent:>3}%  {msg}")
        .expect("a valid template")
        .progress_chars("=> ");
    bar.set_style(style);
    let mut shown = false;
    while !shared.done.load(Relaxed) {
        std::thread::park_timeout(TICK);
        if shared.done.load(Relaxed) {
            break;
        }
        let elapsed = started.elapsed();
        if elapsed < SHOW_AFTER {
            continue;
        }
        if !shown {
            bar.set_draw_target(target());
            shown = true;
        }
        let t = f64::from_bits(shared.t.load(Relaxed));
        bar.set_position(((t / span.t_end).clamp(0.0, 1.0) * SCALE as f64) as u64);
        bar.set_message(message(shared, span, t, elapsed));
    }
    bar.finish_and_clear();
}

fn message(shared: &Shared, span: Span, t: f64, elapsed: Duration) -> String {
    let work = shared.work.load(Relaxed).saturating_sub(span.work0);
    let nanos = shared.work_nanos.load(Relaxed);
    let rate = if nanos > 0 { work as f64 / (nanos as f64 * 1e-9) } else { 0.0 };
    let done = (t - span.t0) / (span.t_end - span.t0);
    let eta = if done > 0.0 && done.is_finite() {
        let left = elapsed.as_secs_f64() * (1.0 - done).max(0.0) / done;
        format!("{:#}", HumanDuration(Duration::from_secs_f64(left.min(1e9))))
    } else {
        "?".to_string()
    };
    format!("t = {} / {}  {} {}/s  ETA {eta}", short(t), span.t_end, short(rate), span.unit)
}

/// A number with four significant digits and an SI suffix (`1.234M`).
fn short(v: f64) -> String {
    let a = v.abs();
    let (x, suffix) = if a >= 1e9 {
        (v / 1e9, "G")
    } else if a >= 1e6 {
        (v / 1e6, "M")
    } else if a >= 1e3 {
        (v / 1e3, "k")
    } else {
        (v, "")
    };
    let digits = if x.abs() >= 100.0 {
        1
    } else if x.abs() >= 10.0 {
        2
    } else {
        3
    };
    format!("{x:.digits$}{suffix}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_numbers() {
        assert_eq!(short(0.5), "0.500");
        assert_eq!(short(123.456), "123.5");
        assert_eq!(short(1234.5), "1.234k");
        assert_eq!(short(2.5e7), "25.00M");
    }

    #[test]
    fn the_message_has_time_rate_and_eta() {
        let shared = Shared::default();
        shared.work.store(3_000, Relaxed);
        shared.work_nanos.store(2_000_000_000, Relaxed);
        let span = Span { t0: 0.0, t_end: 100.0, work0: 1_000, unit: "events" };
        let m = message(&shared, span, 25.0, Duration::from_secs(10));
        assert!(m.starts_with("t = 25.00 / 100  1.000k events/s  ETA 30"), "{m}");
    }

    #[test]
    fn an_inactive_display_spawns_nothing_and_the_probe_still_works() {
        let span = Span { t0: 0.0, t_end: 10.0, work0: 0, unit: "steps" };
        let (p, mut probe) = Progress::start_on(false, span, ProgressDrawTarget::hidden);
        assert!(p.thread.is_none());
        probe.segment(&Segment { t0: 0.0, t1: 2.5, ..Default::default() });
        assert_eq!(f64::from_bits(p.shared.t.load(Relaxed)), 2.5);
        p.finish();
        let (p, _probe) = Progress::start_on(true, span, ProgressDrawTarget::hidden);
        p.publish(5);
        p.finish();
    }
}
