//! What a run is (`RunPlan`: its scene, where it writes, [`RunOptions`]) and where it starts
//! (`RunStart`: `t = 0` or a checkpoint): plain data shared by [`super::run`],
//! [`super::control`], [`super::checkpoint`] and [`super::resume`](mod@super::resume).

use std::path::Path;

use super::drive::StopFlag;
use super::grid::GridPosition;
use super::observers::{CoreObservers, Writers};
use crate::engine::Engine;
use crate::observe::stats::RuptureForces;
use crate::scene::Scene;

/// How a run is carried out, beyond its scene. The default (no checkpoints, no progress,
/// no stop flag) is [`run_scene`](super::run_scene)'s.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Write a checkpoint at output-grid stops, at most every this many seconds of wall
    /// time (> 0). Needs an output directory.
    pub checkpoint_every: Option<f64>,
    /// Show progress on stderr when stderr is a terminal and the run lasts more than
    /// [`SHOW_AFTER`](super::progress::SHOW_AFTER).
    pub progress: bool,
    /// Stop at the next grid stop once this flag is set: the run returns
    /// [`RunError::Stopped`](super::RunError::Stopped), after writing a checkpoint into the output directory (if it
    /// has one) from which `stickslip resume` continues it.
    pub stop: Option<StopFlag>,
    /// Threads the engine may share its work among ([`Engine::set_threads`]); `0` and `1`
    /// keep it on the run's own thread. The results are the same for every count.
    pub threads: usize,
}

/// What a run is: its scene, where it writes, and how it is carried out.
#[derive(Clone, Copy)]
pub(super) struct RunPlan<'a> {
    pub scene: &'a Scene,
    pub out: Option<&'a Path>,
    pub opts: &'a RunOptions,
}

/// Where a run starts: `t = 0`, or a checkpoint.
pub(super) struct RunStart {
    pub position: GridPosition,
    pub core: CoreObservers,
    pub writers: Writers,
    /// Rupture-force statistics so far (weak bonds; `None` starts them afresh).
    pub ruptures: Option<RuptureForces>,
    /// Wall time spent before this process.
    pub wall_seconds: f64,
    /// Checkpoints written before this process.
    pub checkpoints: u64,
    /// Time of the checkpoint the run was resumed from.
    pub checkpoint_t: Option<f64>,
}

/// The engine's work counter: steps (fixed engine) or events (exact engine).
pub(super) fn work(engine: &impl Engine) -> (u64, &'static str) {
    let c = engine.counters();
    match (c.steps, c.events) {
        (Some(s), _) => (s, "steps"),
        (None, e) => (e.unwrap_or(0), "events"),
    }
}
