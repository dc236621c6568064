//! Running the runs of a study that are not done yet: in parallel on a pool, each finished
//! run appended to the study's [`Journal`] at once, and stoppable: once the stop flag is
//! set no run starts, runs in flight stop at their next grid stop and are dropped, and the
//! finished ones stay in the journal.

use indicatif::ProgressBar;
use rayon::prelude::*;
use serde::Serialize;
use serde::de::DeserializeOwned;

use super::journal::{Journal, JournalError};
use crate::runner::{RunError, RunOptions, StopFlag};

/// What a study starts from: the runs already done (from its journal), the journal to
/// append finished runs to, and a flag that stops it.
#[derive(Debug)]
pub struct Continuation<'a, T> {
    /// `done[i]`: run `i`'s result, if it is done.
    pub done: Vec<Option<T>>,
    pub journal: Option<&'a Journal>,
    /// Stops the study when set (a journal that cannot be written sets it too).
    pub stop: Option<&'a StopFlag>,
}

impl<T> Continuation<'_, T> {
    /// `runs` runs, none done, no journal, no stop flag.
    pub fn fresh(runs: usize) -> Self {
        Continuation { done: (0..runs).map(|_| None).collect(), journal: None, stop: None }
    }
}

/// Why a study ended before all its runs were done. The finished runs are in its journal.
#[derive(Debug, thiserror::Error)]
pub enum Interrupted {
    #[error("the study was stopped with {done} of {total} runs done")]
    Stopped { done: usize, total: usize },
    #[error("{source}; the study stopped with {done} of {total} runs done")]
    Journal {
        #[source]
        source: Box<JournalError>,
        done: usize,
        total: usize,
    },
}

/// Runs every run `i` of `order` not done in `from` with `job(i, options)` on `pool`, and
/// returns every run's result in index order (the done ones as they were). A run that
/// fails is returned as its error (the others go on); a run stopped by the flag is dropped
/// and the study is [`Interrupted`]. `seeds[i]` is run `i`'s seed, for the journal.
pub fn run_missing<T, F>(
    pool: &rayon::ThreadPool,
    order: &[usize],
    seeds: &[u64],
    from: Continuation<'_, T>,
    progress: Option<&ProgressBar>,
    job: F,
) -> Result<Vec<Result<T, RunError>>, Interrupted>
where
    T: Send + Sync + Serialize + DeserializeOwned + PartialEq,
    F: Fn(usize, &RunOptions) -> Result<T, RunError> + Sync,
{
    let total = from.done.len();
    let own = StopFlag::new();
    let stop = from.stop.unwrap_or(&own);
    let opts = RunOptions { stop: Some(stop.clone()), ..RunOptions::default() };
    let failed_write: std::sync::Mutex<Option<JournalError>> = std::sync::Mutex::new(None);
    if let Some(p) = progress {
        p.inc(from.done.iter().filter(|d| d.is_some()).count() as u64);
    }
    let ran: Vec<(usize, Option<Result<T, RunError>>)> = pool.install(|| {
        order
            .par_iter()
            .filter(|&&i| from.done[i].is_none())
            .map(|&i| {
                if stop.is_requested() {
                    return (i, None);
                }
                let result = match job(i, &opts) {
                    Err(RunError::Stopped { .. }) => return (i, None),
                    r => r,
                };
                if let (Ok(t), Some(journal)) = (&result, from.journal) {
                    if let Err(e) = journal.append(i, seeds[i], t) {
                        failed_write.lock().unwrap_or_else(|p| p.into_inner()).get_or_insert(e);
                        stop.request();
                        return (i, None);
                    }
                }
                if let Some(p) = progress {
                    p.inc(1);
                }
                (i, Some(result))
            })
            .collect()
    });
    let mut results: Vec<Option<Result<T, RunError>>> = from.done.into_iter().map(|d| d.map(Ok)).collect();
    for (i, r) in ran {
        results[i] = r;
    }
    let finished = results.iter().filter(|r| matches!(r, Some(Ok(_)))).count();
    if let Some(source) = failed_write.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(Interrupted::Journal { source: Box::new(source), done: finished, total });
    }
    if results.iter().any(Option::is_none) {
        return Err(Interrupted::Stopped { done: finished, total });
    }
    Ok(results.into_iter().map(|r| r.expect("every run ran")).collect())
}
