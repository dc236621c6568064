//! The threads that share a step's pass over the junctions (`Team`).
//!
//! A run's results do not depend on the team: the work is cut into items (the chunks of
//! [`super::chunk`]) whose results depend on the item alone, and they are handed back in
//! item order, however many threads took them and in whatever order they finished.

use std::sync::{Arc, Mutex};

use super::chunk::CHUNK;

/// Fewest junctions for which a step's pass is shared between threads; below it the pass
/// stays on the run's own thread, which is faster there: a step of `N` junctions takes a
/// few nanoseconds per junction, and handing work to another thread and waiting for it
/// costs tens of microseconds a step on a busy machine (docs/performance.md, "Fixed-step
/// engine").
pub const PARALLEL_MIN: usize = 8 * CHUNK;

/// The run's own thread and `threads - 1` workers of a private pool, which take items from
/// one queue, each as soon as it is free (so a thread the machine slows down takes fewer).
#[derive(Clone)]
pub(super) struct Team {
    pool: Arc<rayon::ThreadPool>,
    threads: usize,
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Team").field("threads", &self.threads).finish()
    }
}

impl Team {
    /// A team of `threads` threads for `n` junctions, or `None` (the pass stays on one
    /// thread) when `threads < 2`, `n < PARALLEL_MIN`, or the workers cannot be started.
    pub(super) fn for_junctions(threads: usize, n: usize) -> Option<Team> {
        if threads < 2 || n < PARALLEL_MIN {
            return None;
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads - 1)
            .thread_name(|i| format!("stickslip-fixed-{i}"))
            .build()
            .ok()?;
        Some(Team { pool: Arc::new(pool), threads })
    }

    /// Threads in the team, the caller's included.
    pub(super) fn threads(&self) -> usize {
        self.threads
    }

    /// `work(i, item)` for every item, on the team's threads (the caller's among them);
    /// the results in item order.
    pub(super) fn map<I: Send, T: Send>(
        &self,
        items: impl Iterator<Item = I> + Send,
        work: impl Fn(usize, I) -> T + Sync,
    ) -> Vec<T> {
        let queue = Mutex::new(items.enumerate());
        let done = Mutex::new(Vec::new());
        let drain = || {
            let mut mine = Vec::new();
            loop {
                // The lock is held only to take the next item, not while working on it.
                let next = queue.lock().unwrap_or_else(|e| e.into_inner()).next();
                let Some((i, item)) = next else { break };
                mine.push((i, work(i, item)));
            }
            done.lock().unwrap_or_else(|e| e.into_inner()).extend(mine);
        };
        self.pool.in_place_scope(|s| {
            for _ in 1..self.threads {
                s.spawn(|_| drain());
            }
            drain();
        });
        in_item_order(done.into_inner().unwrap_or_else(|e| e.into_inner()))
    }
}

/// The results without their item numbers, in item order. Outside [`Team::map`], so that
/// the sort is compiled once per result type rather than once per caller.
fn in_item_order<T>(mut done: Vec<(usize, T)>) -> Vec<T> {
    done.sort_unstable_by_key(|&(i, _)| i);
    done.into_iter().map(|(_, t)| t).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_or_single_threaded_runs_have_no_team() {
        assert!(Team::for_junctions(1, 10 * PARALLEL_MIN).is_none());
        assert!(Team::for_junctions(4, PARALLEL_MIN - 1).is_none());
        assert_eq!(Team::for_junctions(3, PARALLEL_MIN).map(|t| t.threads()), Some(3));
    }

    /// Items are handed back in their order, each seen once, on any number of threads,
    /// however long each takes.
    #[test]
    fn results_come_back_in_item_order() {
        for threads in [2, 3, 5] {
            let team = Team::for_junctions(threads, PARALLEL_MIN).unwrap();
            let mut data: Vec<u64> = (0..1000).collect();
            let got = team.map(data.chunks_mut(7), |i, chunk| {
                // Uneven work, so that the threads finish out of order.
                let spin = (i * 7919) % 13 * 1000;
                let mut acc = 0u64;
                for k in 0..spin {
                    acc = std::hint::black_box(acc.wrapping_add(k as u64));
                }
                for v in chunk.iter_mut() {
                    *v *= 2;
                }
                (i, chunk.iter().sum::<u64>(), acc)
            });
            assert_eq!(got.len(), 1000usize.div_ceil(7));
            for (k, &(i, sum, _)) in got.iter().enumerate() {
                assert_eq!(i, k);
                let want: u64 = (k as u64 * 7..(k as u64 * 7 + 7).min(1000)).map(|v| 2 * v).sum();
                assert_eq!(sum, want, "{threads} threads, item {k}");
            }
            assert!(data.iter().enumerate().all(|(i, &v)| v == 2 * i as u64));
        }
    }
}
