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
    use crate::observe::Recorder;
    use crate::runner::{Observed, Simulation, StopFlag, Termination};
    use crate::test_scenes::fig1_with;

    /// Everything a recorder saw, with every bit of every number.
    fn seen(r: &Recorder) -> String {
        format!("{:?}", (&r.events, &r.segments, &r.samples))
    }

    /// Scenes whose grids have a warm-up stop between samples; the fixed engine's step does
    /// not divide the warm-up time, so it stops past it, on the next sample point.
    const SCENES: [&[&str]; 3] = [
        &["run.t_end=12", "run.t_warmup=2.5", "output.sample_dt=1", "fixed.dt=0.75", "junctions.bond=weak"],
        &["run.engine=exact", "junctions.force_law=linear", "junctions.bond=weak", "run.t_end=30", "run.t_warmup=2.5"],
        &["run.engine=exact", "junctions.bond=weak", "run.t_end=12", "run.t_warmup=2.5", "output.sample_dt=0.5"],
    ];

    #[test]
    fn a_drive_stopped_at_every_stop_is_the_uninterrupted_drive() {
        for overrides in SCENES {
            let scene = fig1_with(overrides);
            let mut whole = Recorder::default();
            let end = Simulation::new(&scene).unwrap().drive(Observed::Recorder(&mut whole), None).unwrap();
            assert_eq!(end.termination, Termination::ReachedEnd);
            assert!(whole.events.len() > 10, "{overrides:?}: too few events to test anything");

            // The flag stays set: every drive makes exactly one stop, then returns.
            let (stop, mut rec) = (StopFlag::new(), Recorder::default());
            stop.request();
            let mut sim = Simulation::new(&scene).unwrap();
            let mut drives = 0;
            let last = loop {
                let o = sim.drive(Observed::Recorder(&mut rec), Some(&stop)).unwrap();
                drives += 1;
                assert_eq!(o.position.stops_done, drives, "{overrides:?}: one stop per drive");
                assert_eq!(o.state, sim.sample());
                if o.termination == Termination::ReachedEnd {
                    break o;
                }
                assert_eq!(o.termination, Termination::StopRequested);
            };
            assert_eq!(seen(&rec), seen(&whole), "{overrides:?}");
            assert_eq!(last, end, "{overrides:?}");
            assert!(drives >= 12, "{overrides:?}: {drives} stops");
            // A finished walk stays finished.
            let again = sim.drive(Observed::Nothing, None).unwrap();
            assert_eq!((again.termination, again.position), (Termination::ReachedEnd, end.position));
        }
    }

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
