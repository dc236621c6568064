//! Runs that keep what a test reads, through the library's [`Simulation`] handle (the
//! engine the scene asks for), with no engine visitor. A whole run along the output grid is
//! [`stickslip::runner::record`].

use stickslip::Scene;
use stickslip::engine::{Counters, EngineError};
use stickslip::observe::regime::Verdict;
use stickslip::observe::{EventKind, JunctionEvent, Recorder, Sample, Segment};
use stickslip::runner::{Observed, Simulation, core_observers};

/// Runs `scene` (its own engine) from `t = 0` to `t_end` in one advance and returns its
/// junction events.
pub fn events_of(scene: &Scene) -> Vec<JunctionEvent> {
    let mut sim = Simulation::new(scene).expect("engine");
    let mut rec = Recorder::default();
    sim.advance_observed(scene.run.t_end, Observed::Recorder(&mut rec)).expect("run");
    rec.events
}

/// The samples a run of `scene` along its output grid takes (the rows of its `trace.csv`),
/// with no observer in between: for long runs whose events and segments would not fit in a
/// [`stickslip::runner::record`]ing.
pub fn samples_of(scene: &Scene) -> Vec<Sample> {
    let mut sim = Simulation::new(scene).expect("engine");
    let grid = *sim.grid();
    let mut samples = vec![sim.sample()];
    for stop in grid.stops_after(0.0) {
        sim.advance(stop.t).expect("run");
        let s = sim.sample();
        if stop.sample && samples.last().is_none_or(|last| last.t != s.t) {
            samples.push(s);
        }
    }
    samples
}

/// The regime detector's verdict on a run of `scene` along its output grid (the verdict
/// `stickslip run` reports), with no recording.
pub fn verdict_of(scene: &Scene) -> Verdict {
    let mut core = core_observers(scene);
    let mut sim = Simulation::new(scene).expect("engine");
    sim.drive(Observed::Core(&mut core), None).expect("run");
    core.1.verdict()
}

/// The time of the first rupture, if any.
pub fn first_rupture(events: &[JunctionEvent]) -> Option<f64> {
    events.iter().find(|e| e.kind == EventKind::Rupture).map(|e| e.t)
}

/// Everything a run of [`steps`] reported, with a sample after every step.
#[derive(Debug, Default)]
pub struct Trace {
    /// The state at `t = 0` and after every step.
    pub samples: Vec<Sample>,
    pub segments: Vec<Segment>,
    pub events: Vec<JunctionEvent>,
    pub counters: Counters,
    /// The error that ended the run early, if any.
    pub error: Option<EngineError>,
    /// `time()` after each advance.
    pub times: Vec<f64>,
}

/// Runs `scene` on its fixed-step engine for `steps` steps (advance `k` stops at `k dt`),
/// sampling after every step; an error ends the run and is kept in the trace.
pub fn steps(scene: &Scene, steps: u64) -> Trace {
    let mut sim = Simulation::new(scene).expect("the engine builds");
    let dt = sim.time_step().expect("a fixed-step engine");
    let mut rec = Recorder::default();
    let mut times = Vec::new();
    rec.samples.push(sim.sample());
    let mut error = None;
    for k in 1..=steps {
        if let Err(e) = sim.advance_observed(k as f64 * dt, Observed::Recorder(&mut rec)) {
            error = Some(e);
            break;
        }
        times.push(sim.time());
        rec.samples.push(sim.sample());
    }
    let Recorder { events, segments, samples } = rec;
    Trace { samples, segments, events, counters: sim.counters(), error, times }
}
