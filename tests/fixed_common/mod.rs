//! Helpers shared by the fixed-engine tests.
#![allow(dead_code)]

use stickslip::Scene;
use stickslip::engine::{Counters, Engine, EngineError, EngineVisitor, fixed};
use stickslip::observe::{JunctionEvent, Recorder, Sample, Segment};
use stickslip::testkit;

/// Everything one run reported, with a sample after every step.
#[derive(Debug, Default)]
pub struct Trace {
    pub samples: Vec<Sample>,
    pub segments: Vec<Segment>,
    pub events: Vec<JunctionEvent>,
    pub counters: Counters,
    pub error: Option<EngineError>,
    /// `time()` after each `advance`.
    pub times: Vec<f64>,
}

struct Record {
    steps: u64,
}

impl EngineVisitor for Record {
    type Output = Trace;
    fn visit<E: Engine>(self, mut engine: E) -> Trace {
        let dt = engine.time_step().expect("the fixed engine has a step");
        let mut rec = Recorder::default();
        let mut times = Vec::new();
        rec.samples.push(engine.sample());
        let mut error = None;
        for k in 1..=self.steps {
            if let Err(e) = engine.advance(k as f64 * dt, &mut rec) {
                error = Some(e);
                break;
            }
            times.push(engine.time());
            rec.samples.push(engine.sample());
        }
        Trace {
            samples: rec.samples,
            segments: rec.segments,
            events: rec.events,
            counters: engine.counters(),
            error,
            times,
        }
    }
}

/// Runs `scene` on the fixed engine for `steps` steps, sampling after every step.
pub fn record(scene: &Scene, steps: u64) -> Trace {
    fixed::dispatch(scene, Record { steps }).expect("the fixed engine builds")
}

/// The Fig. 1 scene on the fixed engine with `overrides`.
pub fn scene(overrides: &[&str]) -> Scene {
    let mut o = vec!["run.engine=fixed"];
    o.extend_from_slice(overrides);
    testkit::fig1_with(&o)
}

/// The Park-Miller sequence by hand: `s <- 16807 s mod (2^31 - 1)`, `xi = s / (2^31 - 1)`.
pub fn park_miller_uniforms(seed: u64, count: usize) -> Vec<f64> {
    const M: u64 = 2_147_483_647;
    let mut s = seed;
    (0..count)
        .map(|_| {
            s = s * 16_807 % M;
            s as f64 / M as f64
        })
        .collect()
}
