//! What a run does at grid stops besides observing: progress, flushes and checkpoints,
//! paced by the clock so that a grid stop costs a counter decrement however fine the grid.

use std::path::Path;
use std::time::{Duration, Instant};

use super::checkpoint;
use super::error::RunError;
use super::grid::GridPosition;
use super::observers::{EventObservers, RunObservers};
use super::plan::{RunPlan, RunStart, work};
use super::progress::Progress;
use crate::engine::Engine;

/// Outputs are flushed to the operating system at least this often (at grid stops).
pub const FLUSH_EVERY: Duration = Duration::from_secs(1);

/// Looks at the clock only every `stride` stops, with `stride` adapted so that it does so
/// every few milliseconds: a grid stop costs a decrement, however fine the grid.
struct Pacer {
    stride: u64,
    left: u64,
    last: Instant,
}

impl Pacer {
    const MIN_GAP: Duration = Duration::from_millis(5);
    const MAX_GAP: Duration = Duration::from_millis(50);

    fn new(now: Instant) -> Pacer {
        Pacer { stride: 1, left: 1, last: now }
    }

    /// The time now, every few milliseconds; `None` at the stops in between.
    #[inline]
    fn tick(&mut self) -> Option<Instant> {
        self.left -= 1;
        if self.left > 0 {
            return None;
        }
        let now = Instant::now();
        let gap = now - self.last;
        self.last = now;
        if gap < Self::MIN_GAP {
            self.stride = (self.stride * 2).min(1 << 24);
        } else if gap > Self::MAX_GAP {
            self.stride = (self.stride / 2).max(1);
        }
        self.left = self.stride;
        Some(now)
    }
}

/// The upkeep of a run at grid stops: progress, flushes, checkpoints.
pub(super) struct Housekeeping<'a> {
    plan: &'a RunPlan<'a>,
    started: Instant,
    /// Wall time spent before this process.
    wall_before: f64,
    pacer: Pacer,
    progress: Progress,
    last_flush: Instant,
    last_checkpoint: Instant,
    /// Checkpoint interval, when there is a directory to write checkpoints to.
    every: Option<(Duration, &'a Path)>,
    /// Checkpoints written (all processes).
    checkpoints: u64,
    /// Time of the checkpoint on disk, if any.
    checkpoint_t: Option<f64>,
}

impl<'a> Housekeeping<'a> {
    pub fn new(plan: &'a RunPlan<'a>, started: Instant, start: &RunStart, progress: Progress) -> Self {
        let every = match (plan.opts.checkpoint_every, plan.out) {
            (Some(s), Some(dir)) => Some((Duration::from_secs_f64(s), dir)),
            _ => None,
        };
        Housekeeping {
            plan,
            started,
            wall_before: start.wall_seconds,
            pacer: Pacer::new(started),
            progress,
            last_flush: started,
            last_checkpoint: started,
            every,
            checkpoints: start.checkpoints,
            checkpoint_t: start.checkpoint_t,
        }
    }

    /// Wall time of the run so far (all processes).
    pub fn wall_seconds(&self) -> f64 {
        self.wall_before + self.started.elapsed().as_secs_f64()
    }

    /// Called by the loop after every grid stop but the last.
    pub fn at_stop<E: Engine, X: EventObservers>(
        &mut self,
        engine: &E,
        obs: &mut RunObservers<X>,
        pos: &GridPosition,
    ) -> Result<(), RunError> {
        let Some(now) = self.pacer.tick() else {
            return Ok(());
        };
        self.progress.publish(work(engine).0);
        if let Some((every, dir)) = self.every {
            if now - self.last_checkpoint >= every {
                return self.checkpoint(dir, engine, obs, pos);
            }
        }
        if now - self.last_flush >= FLUSH_EVERY {
            if let Some(dir) = self.plan.out {
                obs.flush(dir)?;
            }
            self.last_flush = now;
        }
        Ok(())
    }

    /// Writes a checkpoint now (the engine is between two advances, at `pos`).
    pub fn checkpoint<E: Engine, X: EventObservers>(
        &mut self,
        dir: &Path,
        engine: &E,
        obs: &mut RunObservers<X>,
        pos: &GridPosition,
    ) -> Result<(), RunError> {
        let wall_seconds = self.wall_seconds();
        checkpoint::save(dir, self.plan, engine, obs, pos, wall_seconds, self.checkpoints + 1)?;
        self.checkpoints += 1;
        self.checkpoint_t = Some(engine.time());
        self.last_checkpoint = Instant::now();
        self.last_flush = self.last_checkpoint;
        Ok(())
    }

    /// Stops the progress display; returns the time of the checkpoint on disk, if any.
    pub fn finish(self) -> Option<f64> {
        self.progress.finish();
        self.checkpoint_t
    }
}
