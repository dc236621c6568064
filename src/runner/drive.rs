//! The run loop: one walk of an engine along the output grid. Runs, resumes, records,
//! simulation handles, tests and benches all drive engines with [`drive_walk`]; it returns
//! why it stopped (the run reached `t_end`, or a stop was requested) with the final state
//! and counters, in the manner of argmin's executor.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};

use super::grid::{GridPosition, OutputGrid, Walk};
use crate::engine::{Counters, Engine, EngineError};
use crate::observe::{Observer, Sample};

/// Why [`drive_walk`] returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Termination {
    /// The walk reached its last stop, `t_end`.
    ReachedEnd,
    /// A stop was requested through the [`StopFlag`]. The engine is at a grid stop, between
    /// two advances; driving it on along the same walk continues the run exactly.
    StopRequested,
}

/// How a drive ended: why, and where.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub termination: Termination,
    /// The state at the last stop reached (finite).
    pub state: Sample,
    /// The engine's counters at that stop.
    pub counters: Counters,
    /// The position on the grid at that stop.
    pub position: GridPosition,
}

/// Asks a drive to stop at the next grid stop. Clones share the flag, so another thread
/// (a signal handler, a Python binding) can set it while the drive runs. The loop reads
/// it once per grid stop (a relaxed load), never per event.
#[derive(Clone, Debug, Default)]
pub struct StopFlag(Arc<AtomicBool>);

impl StopFlag {
    pub fn new() -> Self {
        StopFlag::default()
    }
    /// Asks every drive watching this flag to stop at its next grid stop.
    pub fn request(&self) {
        self.0.store(true, Relaxed);
    }
    /// Withdraws the request (before driving on after a stop).
    pub fn clear(&self) {
        self.0.store(false, Relaxed);
    }
    pub fn is_requested(&self) -> bool {
        self.0.load(Relaxed)
    }
    /// The flag itself, for a signal handler that sets it.
    pub(crate) fn shared(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.0)
    }
}

/// Checks that a sampled state holds only finite numbers.
pub fn check_finite(s: &Sample) -> Result<(), EngineError> {
    for (quantity, value) in [("X", s.x), ("Xd", s.v), ("friction", s.friction), ("bond force", s.bond_force)] {
        if !value.is_finite() {
            return Err(EngineError::NonFinite { t: s.t, quantity, value });
        }
    }
    Ok(())
}

/// THE loop: advances `engine` from stop to stop of `walk`, feeding `obs` the segments
/// (and events) of every advance and the state at every sample stop, until the walk's end
/// or, after a stop, a request on `stop`.
///
/// At the start of a run (`t = 0`, no stop done) the initial state is sampled first. A
/// state sampled twice at one time (a fixed-step grid point that is also the warm-up stop)
/// is fed once. After every stop but the last, `at_stop` is called with the engine (between
/// two advances, in the state a checkpoint records), the observers and the position; then
/// `stop` is looked at. So a drive always makes at least one stop, and a flag left set
/// cannot stall a caller that drives again.
pub fn drive_walk<E, O, X, H>(
    engine: &mut E,
    walk: &mut Walk,
    obs: &mut O,
    stop: Option<&StopFlag>,
    mut at_stop: H,
) -> Result<Outcome, X>
where
    E: Engine,
    O: Observer,
    X: From<EngineError>,
    H: FnMut(&E, &mut O, &GridPosition) -> Result<(), X>,
{
    let mut state = None;
    if walk.position().stops_done == 0 && engine.time() == 0.0 {
        let s = engine.sample();
        check_finite(&s)?;
        obs.sample(&s);
        walk.position_mut().last_sample_t = s.t;
        state = Some(s);
    }
    let mut termination = Termination::ReachedEnd;
    while let Some(next) = walk.take() {
        engine.advance(next.t, obs)?;
        obs.stop();
        let s = engine.sample();
        check_finite(&s)?;
        let pos = walk.position_mut();
        if next.sample && s.t != pos.last_sample_t {
            obs.sample(&s);
            pos.last_sample_t = s.t;
        }
        pos.stops_done += 1;
        state = Some(s);
        if walk.finished() {
            break;
        }
        at_stop(engine, obs, &walk.position())?;
        if stop.is_some_and(StopFlag::is_requested) {
            termination = Termination::StopRequested;
            break;
        }
    }
    let state = match state {
        Some(s) => s,
        // A walk already at its end: report where the engine is.
        None => {
            let s = engine.sample();
            check_finite(&s)?;
            s
        }
    };
    Ok(Outcome { termination, state, counters: engine.counters(), position: walk.position() })
}

/// Walks `engine` along `grid` from its current time to `t_end`, feeding `obs` (no stop
/// flag, nothing done at stops): [`drive_walk`] on [`OutputGrid::walk_after`].
pub fn drive<E: Engine, O: Observer>(engine: &mut E, grid: &OutputGrid, obs: &mut O) -> Result<(), EngineError> {
    let mut walk = grid.walk_after(engine.time());
    drive_walk(engine, &mut walk, obs, None, |_, _, _| Ok::<(), EngineError>(())).map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::StopFlag;

    #[test]
    fn the_stop_flag_is_shared_and_can_be_cleared() {
        let (a, b) = (StopFlag::new(), StopFlag::new());
        let a2 = a.clone();
        assert!(!a.is_requested());
        a2.request();
        assert!(a.is_requested() && !b.is_requested());
        a.clear();
        assert!(!a2.is_requested());
    }
}
