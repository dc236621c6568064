//! [`Simulation`]: the engine a scene asks for behind one handle, for tests, benches and
//! bindings that should not need an [`EngineVisitor`] to reach an engine whose type is
//! chosen from the scene.
//!
//! The engine's type is erased at the call boundary only: each [`Simulation::advance`] or
//! [`Simulation::drive`] is one virtual call into code monomorphised for the engine and
//! the observers ([`Observed`] is matched once per call), so the event loop inside is
//! compiled as for a direct call on an engine behind a pointer (instruction counts and
//! timings: docs/performance.md, "The Simulation handle").

use std::any::type_name;

use super::drive::{Outcome, StopFlag, drive_walk};
use super::grid::{GridPosition, OutputGrid, Walk};
use super::observers::CoreObservers;
use crate::engine::{Counters, Engine, EngineError, EngineVisitor, with_engine};
use crate::observe::{Nothing, Recorder, Sample};
use crate::output::state_codec;
use crate::scene::{EngineKind, Scene};

/// The observers an advance of a [`Simulation`] can feed.
pub enum Observed<'a> {
    /// None: the engine compiles the event path out.
    Nothing,
    /// A [`Recorder`]: every segment, event and sample, in memory.
    Recorder(&'a mut Recorder),
    /// The core observers of a run (window statistics, regime detector).
    Core(&'a mut CoreObservers),
    /// Both.
    RecorderAndCore(&'a mut Recorder, &'a mut CoreObservers),
}

/// Why a saved state cannot be restored.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    #[error(transparent)]
    Engine(#[from] EngineError),
    #[error("the state is not a simulation state: {0}")]
    Malformed(#[source] state_codec::CodecError),
    #[error("the state holds engine {found}, but the scene builds {expected}")]
    WrongEngine { found: String, expected: &'static str },
}

/// An engine chosen from a scene, behind one handle.
pub struct Simulation {
    engine: Box<dyn ErasedEngine>,
    grid: OutputGrid,
    /// The walk of the last [`Simulation::drive`], and the engine's time when it returned.
    walk: Option<(Walk, f64)>,
}

impl Simulation {
    /// Builds the engine the scene asks for, at `t = 0`.
    pub fn new(scene: &Scene) -> Result<Self, EngineError> {
        with_engine(scene, Build { scene })
    }

    /// Restores a simulation of `scene` from [`Simulation::state`].
    pub fn from_state(scene: &Scene, state: &[u8]) -> Result<Self, StateError> {
        with_engine(scene, Restore { scene, state })?
    }

    fn with<E: Engine>(scene: &Scene, engine: E) -> Self {
        let grid = OutputGrid::new(scene, engine.time_step());
        Simulation { engine: Box::new(engine), grid, walk: None }
    }

    /// Which engine this is.
    pub fn kind(&self) -> EngineKind {
        self.engine.kind()
    }
    /// The engine's concrete type (law, bond kind, generator, ...).
    pub fn engine_type(&self) -> &'static str {
        self.engine.type_name()
    }
    /// The scene's output grid, for this engine.
    pub fn grid(&self) -> &OutputGrid {
        &self.grid
    }
    /// Current time.
    pub fn time(&self) -> f64 {
        self.engine.time()
    }
    /// The engine's fixed step, if it has one.
    pub fn time_step(&self) -> Option<f64> {
        self.engine.time_step()
    }
    /// The state now.
    pub fn sample(&self) -> Sample {
        self.engine.sample()
    }
    /// Counters so far.
    pub fn counters(&self) -> Counters {
        self.engine.counters()
    }

    /// Advances to `t_stop` (as [`Engine::advance`]) with no observers.
    pub fn advance(&mut self, t_stop: f64) -> Result<(), EngineError> {
        self.engine.advance(t_stop, Observed::Nothing)
    }

    /// Advances to `t_stop`, feeding `obs` the segments and events on the way.
    pub fn advance_observed(&mut self, t_stop: f64, obs: Observed<'_>) -> Result<(), EngineError> {
        self.engine.advance(t_stop, obs)
    }

    /// Walks the scene's output grid with the run loop ([`drive_walk`]), feeding `obs`,
    /// until `t_end` or, after a stop, a request on `stop`. Called again after a requested
    /// stop, it continues the same walk (so the run is the one an uninterrupted drive
    /// makes); after an [`Simulation::advance`] it walks the stops after the engine's time.
    pub fn drive(&mut self, obs: Observed<'_>, stop: Option<&StopFlag>) -> Result<Outcome, EngineError> {
        let t = self.engine.time();
        let mut walk = match self.walk.take() {
            Some((w, left_at)) if left_at == t => w,
            _ => self.grid.walk_after(t),
        };
        let outcome = self.engine.drive(&mut walk, obs, stop)?;
        self.walk = Some((walk, self.engine.time()));
        Ok(outcome)
    }

    /// Shares the engine's work among `threads` threads from now on ([`Engine::set_threads`]):
    /// the same results for every count.
    pub fn set_threads(&mut self, threads: usize) {
        self.engine.set_threads(threads);
    }

    /// The engine's whole state (MessagePack, as in a checkpoint, tagged with the engine's
    /// type), for [`Simulation::from_state`].
    pub fn state(&self) -> Vec<u8> {
        self.engine.state()
    }
}

/// A recorder, and the core observers if given: the one observer type of
/// [`Observed::Recorder`] and [`Observed::RecorderAndCore`].
type Recording<'a> = (&'a mut Recorder, Option<&'a mut CoreObservers>);

fn recording<'a>(r: &'a mut Recorder, c: Option<&'a mut CoreObservers>) -> Recording<'a> {
    (r, c)
}

/// What [`Simulation`] needs of an engine, object-safe. Every method is one virtual call
/// into code monomorphised for the engine.
trait ErasedEngine: Send {
    fn kind(&self) -> EngineKind;
    fn type_name(&self) -> &'static str;
    fn time(&self) -> f64;
    fn time_step(&self) -> Option<f64>;
    fn sample(&self) -> Sample;
    fn counters(&self) -> Counters;
    fn advance(&mut self, t_stop: f64, obs: Observed<'_>) -> Result<(), EngineError>;
    fn drive(&mut self, walk: &mut Walk, obs: Observed<'_>, stop: Option<&StopFlag>) -> Result<Outcome, EngineError>;
    fn state(&self) -> Vec<u8>;
    fn set_threads(&mut self, threads: usize);
}

impl<E: Engine> ErasedEngine for E {
    fn kind(&self) -> EngineKind {
        E::KIND
    }
    fn type_name(&self) -> &'static str {
        type_name::<E>()
    }
    fn time(&self) -> f64 {
        Engine::time(self)
    }
    fn time_step(&self) -> Option<f64> {
        Engine::time_step(self)
    }
    fn sample(&self) -> Sample {
        Engine::sample(self)
    }
    fn counters(&self) -> Counters {
        Engine::counters(self)
    }
    fn advance(&mut self, t_stop: f64, obs: Observed<'_>) -> Result<(), EngineError> {
        // Three observer types, not four: a recorder, with or without the core observers, is
        // one type (`Recording`: the core's presence is a predictable branch per segment), so
        // each engine is compiled once less.
        match obs {
            Observed::Nothing => Engine::advance(self, t_stop, &mut Nothing),
            Observed::Core(c) => Engine::advance(self, t_stop, c),
            Observed::Recorder(r) => Engine::advance(self, t_stop, &mut recording(r, None)),
            Observed::RecorderAndCore(r, c) => Engine::advance(self, t_stop, &mut recording(r, Some(c))),
        }
    }
    fn drive(&mut self, walk: &mut Walk, obs: Observed<'_>, stop: Option<&StopFlag>) -> Result<Outcome, EngineError> {
        match obs {
            Observed::Nothing => drive_walk(self, walk, &mut Nothing, stop, nothing_at_stops),
            Observed::Core(c) => drive_walk(self, walk, c, stop, nothing_at_stops),
            Observed::Recorder(r) => drive_walk(self, walk, &mut recording(r, None), stop, nothing_at_stops),
            Observed::RecorderAndCore(r, c) => {
                drive_walk(self, walk, &mut recording(r, Some(c)), stop, nothing_at_stops)
            }
        }
    }
    fn set_threads(&mut self, threads: usize) {
        Engine::set_threads(self, threads);
    }
    fn state(&self) -> Vec<u8> {
        let mut v = Vec::new();
        state_codec::encode(&mut v, &(type_name::<E>(), self)).expect("an engine serializes to memory");
        v
    }
}

/// What a [`Simulation`] does at grid stops: nothing (no files, no clock).
fn nothing_at_stops<E, O>(_: &E, _: &mut O, _: &GridPosition) -> Result<(), EngineError> {
    Ok(())
}

struct Build<'a> {
    scene: &'a Scene,
}

impl EngineVisitor for Build<'_> {
    type Output = Simulation;
    fn visit<E: Engine>(self, engine: E) -> Simulation {
        Simulation::with(self.scene, engine)
    }
}

struct Restore<'a> {
    scene: &'a Scene,
    state: &'a [u8],
}

impl EngineVisitor for Restore<'_> {
    type Output = Result<Simulation, StateError>;
    fn visit<E: Engine>(self, fresh: E) -> Self::Output {
        // The fresh engine only told the type; the state replaces it.
        drop(fresh);
        let (found, body) = state_codec::split_named(self.state).map_err(StateError::Malformed)?;
        if found != type_name::<E>() {
            return Err(StateError::WrongEngine { found: found.to_owned(), expected: type_name::<E>() });
        }
        let engine: E = state_codec::decode(body).map_err(StateError::Malformed)?;
        Ok(Simulation::with(self.scene, engine))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observe::Segment;
    use crate::runner::drive::Termination;
    use crate::runner::observers::core_observers;
    use crate::test_scenes::fig1_with;

    /// Everything a recorder saw, with every bit of every number.
    fn seen(r: &Recorder) -> String {
        format!("{:?}", (&r.events, &r.segments, &r.samples))
    }

    /// Advances an engine built by `with_engine` directly (no handle) through `stops`,
    /// recording, and returns what it saw with its final sample, counters and type.
    struct Unwrapped<'a>(&'a [f64]);

    impl EngineVisitor for Unwrapped<'_> {
        type Output = (String, Sample, Counters, &'static str, Option<f64>);
        fn visit<E: Engine>(self, mut e: E) -> Self::Output {
            let mut rec = Recorder::default();
            for &t in self.0 {
                e.advance(t, &mut rec).unwrap();
                rec.samples.push(e.sample());
            }
            (seen(&rec), e.sample(), e.counters(), type_name::<E>(), e.time_step())
        }
    }

    const SCENES: [&[&str]; 4] = [
        &["junctions.bond=weak", "fixed.rng=pcg"],
        &["plate.mass=0", "junctions.force_law=linear"],
        &["run.engine=exact", "junctions.force_law=linear", "junctions.bond=weak"],
        &["run.engine=exact", "junctions.bond=weak", "run.t_end=40"],
    ];

    #[test]
    fn the_handle_advances_as_the_engine_it_erases() {
        let stops = [0.5, 3.0, 7.25, 20.0, 40.0];
        for overrides in SCENES {
            let scene = fig1_with(overrides);
            let (direct, sample, counters, ty, dt) = with_engine(&scene, Unwrapped(&stops)).unwrap();
            let mut sim = Simulation::new(&scene).unwrap();
            assert_eq!((sim.engine_type(), sim.kind(), sim.time_step()), (ty, scene.run.engine, dt));
            assert_eq!(*sim.grid(), OutputGrid::new(&scene, dt));
            assert_eq!(sim.time(), 0.0);
            let mut rec = Recorder::default();
            for &t in &stops {
                sim.advance_observed(t, Observed::Recorder(&mut rec)).unwrap();
                rec.samples.push(sim.sample());
                assert!(sim.time() >= t - 1e-9 * dt.unwrap_or(1.0), "{overrides:?}: stopped at {} < {t}", sim.time());
            }
            assert!(rec.events.len() > 10, "{overrides:?}: too few events to test anything");
            assert_eq!(seen(&rec), direct, "{overrides:?}");
            assert_eq!((sim.sample(), sim.counters()), (sample, counters), "{overrides:?}");
        }
    }

    /// A handle can be moved to another thread (a binding's worker, a Python thread).
    #[test]
    fn a_simulation_is_send() {
        fn send<T: Send>(_: &T) {}
        let sim = Simulation::new(&fig1_with(&[])).unwrap();
        send(&sim);
        let t = std::thread::spawn(move || {
            let mut sim = sim;
            sim.advance(3.0).unwrap();
            sim.time()
        });
        assert_eq!(t.join().unwrap(), 3.0);
    }

    #[test]
    fn observers_do_not_change_the_run() {
        // Advancing with no observers, with the core observers, with a recorder or with
        // both gives the same engine state, and the core observers see what the recorder
        // sees.
        for overrides in SCENES {
            let scene = fig1_with(overrides);
            let mut sims: Vec<Simulation> = (0..4).map(|_| Simulation::new(&scene).unwrap()).collect();
            let (mut core_a, mut core_b) = (core_observers(&scene), core_observers(&scene));
            let (mut rec_a, mut rec_b) = (Recorder::default(), Recorder::default());
            for t in [10.0, 25.0, 40.0] {
                sims[0].advance(t).unwrap();
                sims[1].advance_observed(t, Observed::Core(&mut core_a)).unwrap();
                sims[2].advance_observed(t, Observed::Recorder(&mut rec_a)).unwrap();
                sims[3].advance_observed(t, Observed::RecorderAndCore(&mut rec_b, &mut core_b)).unwrap();
            }
            let states: Vec<Vec<u8>> = sims.iter().map(Simulation::state).collect();
            assert!(states.iter().all(|s| *s == states[0]), "{overrides:?}");
            assert_eq!(seen(&rec_a), seen(&rec_b));
            // The regime detector reads samples: the same bit for bit.
            assert_eq!(format!("{:?}", core_a.1), format!("{:?}", core_b.1));
            let mut from_segments = core_observers(&scene).0;
            rec_a.segments.iter().for_each(|s: &Segment| crate::observe::Observer::segment(&mut from_segments, s));
            // Stretches summed by the engine (core alone), its pieces (with a recorder) and
            // the pieces' means (segments): the same statistics to rounding.
            let w = &core_a.0;
            let scale = w.friction_mean().abs() + w.friction_std();
            for s in [&core_b.0, &from_segments] {
                for (a, b, tol) in [
                    (w.covered(), s.covered(), 1e-12 * w.covered()),
                    (w.friction_mean(), s.friction_mean(), 1e-12 * scale),
                    (w.friction_std(), s.friction_std(), 1e-10 * scale),
                    (w.bond_force_mean(), s.bond_force_mean(), 1e-12 * scale),
                    (w.viscous_mean(), s.viscous_mean(), 1e-12 * scale),
                    (w.attached_fraction_mean(), s.attached_fraction_mean(), 1e-13),
                ] {
                    assert!((a - b).abs() <= tol, "{overrides:?}: {a} vs {b}");
                }
            }
            assert!(core_a.0.covered() > 0.0);
        }
    }

    #[test]
    fn a_restored_simulation_continues_identically() {
        for overrides in SCENES {
            let scene = fig1_with(overrides);
            let mut a = Simulation::new(&scene).unwrap();
            a.advance(13.0).unwrap();
            let mut b = Simulation::from_state(&scene, &a.state()).unwrap();
            assert_eq!(a.state(), b.state());
            let (mut ra, mut rb) = (Recorder::default(), Recorder::default());
            a.advance_observed(40.0, Observed::Recorder(&mut ra)).unwrap();
            b.advance_observed(40.0, Observed::Recorder(&mut rb)).unwrap();
            assert!(ra.events.len() > 10, "{overrides:?}: too few events to test anything");
            assert_eq!(seen(&ra), seen(&rb), "{overrides:?}");
            assert_eq!((a.sample(), a.counters(), a.state()), (b.sample(), b.counters(), b.state()));
        }
    }

    #[test]
    fn a_state_restores_only_into_its_own_engine() {
        let fixed = fig1_with(&[]);
        let exact = fig1_with(&["run.engine=exact"]);
        let state = Simulation::new(&fixed).unwrap().state();
        match Simulation::from_state(&exact, &state) {
            Err(StateError::WrongEngine { found, expected }) => {
                assert!(found.contains("Fixed") && expected.contains("Exact"), "{found} / {expected}")
            }
            other => panic!("expected WrongEngine, got {:?}", other.map(|s| s.engine_type())),
        }
        let weak = fig1_with(&["junctions.bond=weak"]);
        assert!(matches!(Simulation::from_state(&weak, &state), Err(StateError::WrongEngine { .. })));
        for bad in [&b""[..], b"not a state", &state[..state.len() / 2]] {
            assert!(matches!(Simulation::from_state(&fixed, bad), Err(StateError::Malformed(_))), "{bad:?}");
        }
    }

    /// Scenes whose grids have a warm-up stop between samples; the fixed engine's step does
    /// not divide the warm-up time, so it stops past it, on the next sample point.
    const WARMUP_SCENES: [&[&str]; 3] = [
        &["run.t_end=12", "run.t_warmup=2.5", "output.sample_dt=1", "fixed.dt=0.75", "junctions.bond=weak"],
        &["run.engine=exact", "junctions.force_law=linear", "junctions.bond=weak", "run.t_end=30", "run.t_warmup=2.5"],
        &["run.engine=exact", "junctions.bond=weak", "run.t_end=12", "run.t_warmup=2.5", "output.sample_dt=0.5"],
    ];

    #[test]
    fn a_drive_stopped_at_every_stop_is_the_uninterrupted_drive() {
        for overrides in WARMUP_SCENES {
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
}
