//! The checks before a run: memory (the estimate against what is available) and disk (the
//! outputs against the free space where they go), and how many runs of a study fit in
//! memory at once.

use std::path::Path;

use super::memory::BASELINE_BYTES;
use super::run::{Estimate, bytes};
use super::system::{Available, available_memory, free_disk};
use crate::scene::Scene;

/// Why a run or study is refused before it starts. Each is one line naming the field.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResourceError {
    #[error(
        "junctions.n = {n}: the run needs an estimated {} of memory ({}), but {} is available ({from}); lower junctions.n",
        bytes(*needed), detail, bytes(*available)
    )]
    Memory { n: usize, needed: u64, detail: String, available: u64, from: &'static str },
    #[error(
        "{field}: the outputs need an estimated {} on disk ({detail}), but {} is free at {path}; write fewer or smaller outputs (output.events, output.trace, run.t_end, junctions.n) or choose another --out",
        bytes(*needed), bytes(*free)
    )]
    Disk { field: &'static str, needed: u64, detail: String, free: u64, path: String },
}

/// Checks that a run of `scene` fits in memory and its outputs fit on the disk of `out`.
/// Returns the estimate.
pub fn check_run(scene: &Scene, out: &Path, checkpoints: bool) -> Result<Estimate, ResourceError> {
    let est = check_memory(scene, checkpoints)?;
    if let Some(free) = free_disk(out).filter(|&free| est.output_bytes() > free) {
        let biggest = est.files.iter().max_by_key(|f| f.bytes).expect("a run writes summary.json");
        let detail = est.files.iter().map(|f| format!("{} {}", f.name, bytes(f.bytes))).collect::<Vec<_>>();
        return Err(ResourceError::Disk {
            field: biggest.field,
            needed: est.output_bytes(),
            detail: detail.join(", "),
            free,
            path: crate::scene::error::printable(&out.display().to_string()),
        });
    }
    Ok(est)
}

/// Checks that a run of `scene` fits in memory (the disk is not looked at: `resume`
/// continues outputs that are already there). Returns the estimate.
pub fn check_memory(scene: &Scene, checkpoints: bool) -> Result<Estimate, ResourceError> {
    let est = Estimate::of(scene, checkpoints);
    if let Some(a) = available_memory().filter(|a| est.peak_bytes() > a.bytes) {
        return Err(memory_error(&est, 1, &a));
    }
    Ok(est)
}

fn memory_error(est: &Estimate, runs: usize, a: &Available) -> ResourceError {
    let runs_text = if runs > 1 { format!("{runs} runs at once x ") } else { String::new() };
    ResourceError::Memory {
        n: est.n,
        needed: BASELINE_BYTES.saturating_add(est.run_bytes().saturating_mul(runs as u64)),
        detail: format!("{runs_text}{}, {}, plus {}", est.method.name(), est.per_junction(), bytes(BASELINE_BYTES)),
        available: a.bytes,
        from: a.source,
    }
}

/// How many runs of `run_bytes` each fit at once in `available` bytes beside the program
/// ([`BASELINE_BYTES`]): `asked`, or fewer; `None` when not even one fits.
pub fn fit_threads(run_bytes: u64, asked: usize, available: u64) -> Option<usize> {
    let room = available.checked_sub(BASELINE_BYTES)?;
    let fit = room.checked_div(run_bytes).unwrap_or(u64::MAX);
    (fit >= 1).then(|| asked.min(usize::try_from(fit).unwrap_or(usize::MAX)).max(1))
}

/// Worker threads for a study whose largest run is `largest` and that asked for `asked`
/// threads: `asked` when that many runs fit in memory at once, fewer (with a note on
/// stderr saying how many and why) when not, and the error when not even one fits.
pub fn threads_for(largest: &Estimate, asked: usize, what: &str) -> Result<usize, ResourceError> {
    let Some(a) = available_memory() else { return Ok(asked) };
    match fit_threads(largest.run_bytes(), asked, a.bytes) {
        None => Err(memory_error(largest, 1, &a)),
        Some(t) => {
            if t < asked {
                eprintln!(
                    "note: {what} uses {t} worker thread{} instead of {asked}: each run needs an estimated {} (junctions.n = {}) and {} is available ({})",
                    if t == 1 { "" } else { "s" },
                    bytes(largest.run_bytes()),
                    largest.n,
                    bytes(a.bytes),
                    a.source
                );
            }
            Ok(t)
        }
    }
}

/// [`threads_for`] for a study running `scenes` (its largest run counts) on `asked`
/// threads (`None`: one per core, as rayon counts them).
pub fn study_threads<'a>(
    scenes: impl IntoIterator<Item = &'a Scene>,
    asked: Option<usize>,
    what: &str,
) -> Result<usize, ResourceError> {
    let largest = scenes.into_iter().map(|s| Estimate::of(s, false)).max_by_key(Estimate::run_bytes);
    let asked = asked.unwrap_or_else(rayon::current_num_threads).max(1);
    match largest {
        Some(e) => threads_for(&e, asked, what),
        None => Ok(asked),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threads_are_cut_to_what_fits() {
        let gib = 1u64 << 30;
        let avail = BASELINE_BYTES + 10 * gib;
        assert_eq!(fit_threads(gib, 8, avail), Some(8));
        assert_eq!(fit_threads(3 * gib, 8, avail), Some(3));
        assert_eq!(fit_threads(10 * gib, 8, avail), Some(1));
        assert_eq!(fit_threads(10 * gib + 1, 8, avail), None);
        assert_eq!(fit_threads(0, 8, avail), Some(8));
        assert_eq!(fit_threads(1, 8, BASELINE_BYTES - 1), None);
    }
}
