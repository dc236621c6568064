//! [`record()`]: a scene run along its output grid with everything it reports kept in
//! memory, for tests and analyses that need the trajectory rather than the summary.

use super::drive::Termination;
use super::observers::{CoreObservers, core_observers};
use super::simulation::{Observed, Simulation};
use crate::engine::{Counters, EngineError};
use crate::observe::{JunctionEvent, Recorder, Sample, Segment};
use crate::scene::Scene;

/// Everything a run of a scene reported ([`record()`]).
#[derive(Clone, Debug)]
pub struct Recording {
    /// The state at every sample stop of the output grid (`t = 0` first, `t_end` last):
    /// the rows of `trace.csv`.
    pub samples: Vec<Sample>,
    /// The segments, tiling `[0, t]`.
    pub segments: Vec<Segment>,
    /// Every junction event: the rows of `events.csv`.
    pub events: Vec<JunctionEvent>,
    /// The run's core observers (window statistics and regime detector), as the summary
    /// reads them.
    pub core: CoreObservers,
    /// The engine's counters where the run ended.
    pub counters: Counters,
    /// Why the run ended, if it did not fail.
    pub termination: Option<Termination>,
    /// Why the run failed: what came before the failure is kept.
    pub error: Option<EngineError>,
}

impl Recording {
    /// Whether the run reached `t_end`.
    pub fn completed(&self) -> bool {
        self.termination == Some(Termination::ReachedEnd)
    }
}

/// Runs `scene` along its output grid from `t = 0` to `t_end` (the engine and the grid a
/// `stickslip run` uses, with the same results), recording samples, segments and events.
/// A failure (an engine that cannot run the scene, numerical trouble) ends the recording
/// and is returned in it.
pub fn record(scene: &Scene) -> Recording {
    let mut rec = Recorder::default();
    let mut core = core_observers(scene);
    let (counters, result) = match Simulation::new(scene) {
        Ok(mut sim) => {
            let r = sim.drive(Observed::RecorderAndCore(&mut rec, &mut core), None);
            (sim.counters(), r)
        }
        Err(e) => (Counters::default(), Err(e)),
    };
    let (termination, error) = match result {
        Ok(outcome) => (Some(outcome.termination), None),
        Err(e) => (None, Some(e)),
    };
    let Recorder { events, segments, samples } = rec;
    Recording { samples, segments, events, core, counters, termination, error }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observe::Observer;
    use crate::observe::stats::RuptureForces;
    use crate::output::csv::{EventWriter, TraceWriter};
    use crate::runner::run::run_scene;
    use crate::scene::BondKind;
    use crate::test_scenes::fig1_with;

    /// `trace.csv` and `events.csv` as the writers write them for a recording.
    fn csv_of(r: &Recording) -> (Vec<u8>, Vec<u8>) {
        let dir = tempfile::tempdir().unwrap();
        let (mut trace, mut events) =
            (TraceWriter::create(dir.path()).unwrap(), EventWriter::create(dir.path()).unwrap());
        r.samples.iter().for_each(|s| trace.sample(s));
        r.events.iter().for_each(|e| events.event(e));
        trace.0.finish().unwrap();
        events.0.finish().unwrap();
        let read = |name| std::fs::read(dir.path().join(name)).unwrap();
        (read(TraceWriter::NAME), read(EventWriter::NAME))
    }

    #[test]
    fn a_recording_is_the_run_a_plain_run_makes() {
        for overrides in [
            &["run.t_warmup=20"][..],
            &["junctions.bond=weak", "junctions.force_law=linear", "fixed.dt=0.25", "run.t_warmup=20.1"],
            &["run.engine=exact", "junctions.force_law=linear", "junctions.bond=weak", "run.t_warmup=20"],
            &["run.engine=exact", "junctions.bond=weak", "run.t_end=60", "run.t_warmup=20", "output.sample_dt=0.5"],
        ] {
            let mut o = vec!["output.events=true"];
            o.extend_from_slice(overrides);
            let scene = fig1_with(&o);
            let dir = tempfile::tempdir().unwrap();
            let summary = run_scene(&scene, Some(dir.path())).unwrap();
            let r = record(&scene);
            assert!(r.completed() && r.error.is_none(), "{o:?}: {:?}", r.error);
            assert!(r.events.len() > 100, "{o:?}: too few events to test anything");
            let (trace, events) = csv_of(&r);
            assert_eq!(trace, std::fs::read(dir.path().join("trace.csv")).unwrap(), "{o:?}: trace.csv");
            assert_eq!(events, std::fs::read(dir.path().join("events.csv")).unwrap(), "{o:?}: events.csv");
            let (stats, regime) = &r.core;
            assert_eq!(summary.counters, r.counters, "{o:?}");
            let bits = |v: f64| v.to_bits();
            // A plain exact run sums stretches, a recording its pieces: the same statistics
            // to rounding (the fixed engine's bit for bit).
            let scale = stats.friction_mean().abs() + stats.friction_std();
            let rel = if scene.run.engine == crate::scene::EngineKind::Exact { 1e-12 } else { 0.0 };
            for (name, a, b, tol) in [
                ("friction_mean", summary.friction_mean, stats.friction_mean(), rel * scale),
                ("friction_std", summary.friction_std, stats.friction_std(), 1e2 * rel * scale),
                ("bond_force_mean", summary.bond_force_mean, stats.bond_force_mean(), rel * scale),
                ("attached_fraction_mean", summary.attached_fraction_mean, stats.attached_fraction_mean(), rel),
            ] {
                assert!((a - b).abs() <= tol, "{o:?}: {name} {a} vs {b}");
            }
            let v = regime.verdict();
            assert_eq!((summary.regime, summary.stick_slip_cycles), (v.regime, v.cycles));
            // The segments tile [0, t_end].
            assert_eq!(r.segments.first().map(|s| s.t0), Some(0.0));
            assert!(r.segments.windows(2).all(|w| w[0].t1 == w[1].t0), "{o:?}");
            assert_eq!(r.samples.last().map(|s| s.t), r.segments.last().map(|s| s.t1));
            if scene.junctions.bond == BondKind::Weak {
                let mut ruptures = RuptureForces::new(scene.run.t_warmup, scene.run.t_end);
                r.events.iter().for_each(|e| ruptures.event(e));
                assert_eq!(summary.rupture_force_mean.map(bits), Some(bits(ruptures.mean())), "{o:?}");
            }
        }
    }

    #[test]
    fn a_failed_run_is_recorded_up_to_its_failure() {
        // A stiff plate far beyond the explicit integrator's limit diverges within steps.
        let scene = fig1_with(&["plate.mass=1e-6", "plate.k=1e9", "fixed.integrator=explicit-euler"]);
        let r = record(&scene);
        assert!(matches!(r.error, Some(EngineError::Diverged { .. })), "{:?}", r.error);
        assert_eq!(r.termination, None);
        assert!(!r.completed());
        assert!(!r.samples.is_empty(), "the initial state is kept");
        assert!(r.samples.iter().all(|s| s.x.is_finite() && s.v.is_finite() && s.friction.is_finite()));
        assert!(r.counters.steps.is_some_and(|n| n > 0 && n < 150));
    }
}
