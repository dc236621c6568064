//! The kit's one engine visitor: work on the engine a scene asks for with its concrete
//! type known (no [`stickslip::runner::Simulation`] handle in between), the reference the
//! handle's cost is measured against (`benches/simulation.rs`,
//! `examples/simulation_cost.rs`; docs/performance.md, "The Simulation handle").

use std::time::{Duration, Instant};

use stickslip::Scene;
use stickslip::engine::{Engine, EngineVisitor, with_engine};
use stickslip::observe::{Nothing, Recorder};
use stickslip::runner::core_observers;

/// Advances `k = 1 ..= advances` to `t = warm + k span` after a first advance to `warm`,
/// feeding the core observers (`core`) or none.
#[derive(Clone, Copy)]
pub struct Concrete<'a> {
    pub scene: &'a Scene,
    pub warm: f64,
    pub span: f64,
    pub advances: u64,
    pub core: bool,
    /// The engine behind a pointer the optimiser cannot see through (as behind a handle)
    /// rather than a local variable.
    pub boxed: bool,
}

/// What a [`Concrete`] run did.
#[derive(Clone, Copy, Debug)]
pub struct ConcreteRun {
    /// Wall time of the advances after the warm-up.
    pub elapsed: Duration,
    /// The friction at the end (the same work through the handle gives the same).
    pub friction: f64,
}

impl Concrete<'_> {
    /// Runs the work on a fresh engine.
    pub fn run(self) -> ConcreteRun {
        with_engine(self.scene, self).expect("engine")
    }
}

impl EngineVisitor for Concrete<'_> {
    type Output = ConcreteRun;
    fn visit<E: Engine>(self, e: E) -> ConcreteRun {
        if self.boxed { work(self, &mut *std::hint::black_box(Box::new(e))) } else { work(self, &mut { e }) }
    }
}

/// The loop also holds the engine's `advance` for the other observers a `Simulation` offers
/// (a recorder, a recorder and the core observers), never called: the same code the
/// handle's program holds.
#[inline(always)]
fn work<E: Engine>(w: Concrete, e: &mut E) -> ConcreteRun {
    let mut core = core_observers(w.scene);
    let mut rec = Recorder::default();
    e.advance(w.warm, &mut core).unwrap();
    let start = Instant::now();
    for k in 1..=w.advances {
        let t = w.warm + k as f64 * w.span;
        match (w.core, std::hint::black_box(k == 0)) {
            (true, true) => e.advance(t, &mut (&mut rec, &mut core)).unwrap(),
            (false, true) => e.advance(t, &mut rec).unwrap(),
            (true, false) => e.advance(t, &mut core).unwrap(),
            (false, false) => e.advance(t, &mut Nothing).unwrap(),
        }
    }
    let elapsed = start.elapsed();
    ConcreteRun { elapsed, friction: e.sample().friction + rec.events.len() as f64 }
}
