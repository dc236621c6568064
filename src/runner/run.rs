//! A run from start to end: builds the engine and the observers, drives the engine along
//! the grid with [`drive_walk`], and finishes (files renamed into place, `summary.json`),
//! or abandons the outputs when it fails. A resume enters here too, from a checkpoint.

use std::path::Path;
use std::time::Instant;

use super::checkpoint;
use super::control::Housekeeping;
use super::drive::{Termination, drive_walk};
use super::error::{RunError, output_error};
use super::grid::{GridPosition, OutputGrid};
use super::observers::{CoreObservers, EventObservers, RunObservers, Writers, core_observers};
use super::plan::{RunOptions, RunPlan, RunStart, work};
use super::progress;
use crate::engine::{Engine, EngineError, EngineVisitor, with_engine};
use crate::observe::Nothing;
use crate::observe::stats::RuptureForces;
use crate::output::atomic::write_whole;
use crate::output::{SUMMARY, Summary};
use crate::scene::{BondKind, Scene};

/// Runs a scene to its end. With `out = Some(dir)` (an existing, writable directory) the
/// files the scene asks for and `summary.json` are written there, each whole or not at all,
/// in place of any an earlier run left.
pub fn run_scene(scene: &Scene, out: Option<&Path>) -> Result<Summary, RunError> {
    run_scene_with(scene, out, &RunOptions::default())
}

/// As [`run_scene`], with checkpoints, progress and a stop flag as `opts` asks. Every file
/// an earlier run left in `out` (finished or partial, and its checkpoint) is removed first.
pub fn run_scene_with(scene: &Scene, out: Option<&Path>, opts: &RunOptions) -> Result<Summary, RunError> {
    if let Some(dir) = out {
        checkpoint::remove_stale(dir)?;
    }
    with_engine(scene, FreshRun(RunPlan { scene, out, opts }))?
}

/// A run from `t = 0`, once the engine type is known.
struct FreshRun<'a>(RunPlan<'a>);

impl EngineVisitor for FreshRun<'_> {
    type Output = Result<Summary, RunError>;
    fn visit<E: Engine>(self, engine: E) -> Self::Output {
        let plan = self.0;
        let writers = match plan.out {
            Some(dir) => Writers::create(plan.scene, dir)?,
            None => Writers::none(),
        };
        let start = RunStart {
            position: GridPosition::default(),
            core: core_observers(plan.scene),
            writers,
            ruptures: None,
            wall_seconds: 0.0,
            checkpoints: 0,
            checkpoint_t: None,
        };
        run_from(engine, &plan, start)
    }
}

/// Chooses the event observers (statically: a run that logs no events and has no weak
/// bonds compiles the event path out of the engine) and runs from `start`.
pub(super) fn run_from<E: Engine>(engine: E, plan: &RunPlan, mut start: RunStart) -> Result<Summary, RunError> {
    let run = &plan.scene.run;
    let weak = plan.scene.junctions.bond == BondKind::Weak;
    let ruptures = start.ruptures.take().unwrap_or_else(|| RuptureForces::new(run.t_warmup, run.t_end));
    debug_assert_eq!(weak, E::WEAK_BONDS, "the engine's bonds are the scene's");
    // `E::WEAK_BONDS` is a constant, so each engine is compiled with the two observer sets
    // of its own bond kind only.
    let events = start.writers.events.take();
    if E::WEAK_BONDS {
        match events {
            None => run_engine(engine, plan, ruptures, start),
            Some(ev) => run_engine(engine, plan, (ev, ruptures), start),
        }
    } else {
        match events {
            None => run_engine(engine, plan, Nothing, start),
            Some(ev) => run_engine(engine, plan, ev, start),
        }
    }
}

fn run_engine<E: Engine, X: EventObservers>(
    mut engine: E,
    plan: &RunPlan,
    events: X,
    start: RunStart,
) -> Result<Summary, RunError> {
    let scene = plan.scene;
    engine.set_threads(plan.opts.threads);
    let started = Instant::now();
    let (work0, unit) = work(&engine);
    let span = progress::Span { t0: engine.time(), t_end: scene.run.t_end, work0, unit };
    let (progress, probe) = progress::Progress::start(plan.opts.progress, span);
    let mut housekeeping = Housekeeping::new(plan, started, &start, progress);
    let mut walk = OutputGrid::new(scene, engine.time_step()).walk_from(start.position);
    let mut obs = RunObservers { core: start.core, trace: start.writers.trace, events, probe };
    let driven =
        drive_walk(&mut engine, &mut walk, &mut obs, plan.opts.stop.as_ref(), |e, o, p| housekeeping.at_stop(e, o, p));
    let wall_seconds = housekeeping.wall_seconds();
    let result = driven.and_then(|outcome| match outcome.termination {
        Termination::ReachedEnd => {
            let ruptures = obs.events.rupture_forces();
            let summary = summarize(scene, &engine, &obs.core, ruptures, wall_seconds)?;
            // Flush everything before anything is renamed, so that a write error leaves
            // the run as it was (resumable, if it has a checkpoint).
            if let Some(dir) = plan.out {
                obs.flush(dir)?;
            }
            Ok(summary)
        }
        Termination::StopRequested => {
            if let Some(dir) = plan.out {
                housekeeping.checkpoint(dir, &engine, &mut obs, &outcome.position)?;
            }
            Err(RunError::Stopped { t: engine.time(), dir: plan.out.map(Path::to_path_buf) })
        }
    });
    let checkpoint_t = housekeeping.finish();
    let summary = match result {
        Ok(s) => s,
        Err(e) => return Err(abandon(e, plan.out, checkpoint_t, obs)),
    };
    if let Some(dir) = plan.out {
        obs.commit_files(dir)?;
        // summary.json comes last: its presence says the run is complete.
        let json = serde_json::to_string_pretty(&summary).expect("summary serializes");
        write_whole(dir, SUMMARY, json.as_bytes()).map_err(output_error(dir, SUMMARY))?;
        checkpoint::remove(dir)?;
    }
    Ok(summary)
}

/// A run that failed or was stopped: an output error after a checkpoint, or a stop, keeps
/// the partial outputs and the checkpoint (the run can be resumed); any other failure
/// removes them.
fn abandon<X: EventObservers>(
    e: RunError,
    out: Option<&Path>,
    checkpoint_t: Option<f64>,
    obs: RunObservers<X>,
) -> RunError {
    if let RunError::Stopped { dir: Some(_), .. } = e {
        return e;
    }
    if let (RunError::Output { .. }, Some(dir), Some(t)) = (&e, out, checkpoint_t) {
        return RunError::Resumable { source: Box::new(e), dir: dir.to_path_buf(), t };
    }
    obs.discard_files();
    if let Some(dir) = out {
        let _ = checkpoint::remove(dir);
    }
    e
}

/// Assembles the summary from the core observers and the engine's counters.
pub fn summarize<E: Engine>(
    scene: &Scene,
    engine: &E,
    core: &CoreObservers,
    ruptures: Option<&RuptureForces>,
    wall_seconds: f64,
) -> Result<Summary, EngineError> {
    let (stats, regime) = core;
    let verdict = regime.verdict();
    let summary = Summary {
        scene: scene.name.clone(),
        engine: E::KIND,
        seed: scene.run.seed,
        n: scene.junctions.n as u64,
        t_end: scene.run.t_end,
        t_warmup: scene.run.t_warmup,
        friction_mean: stats.friction_mean(),
        friction_std: stats.friction_std(),
        friction_per_junction: stats.friction_mean() / scene.junctions.n as f64,
        bond_force_mean: stats.bond_force_mean(),
        viscous_force_mean: stats.viscous_mean(),
        attached_fraction_mean: stats.attached_fraction_mean(),
        rupture_force_mean: ruptures.filter(|r| r.count > 0).map(|r| r.mean()),
        rupture_force_sem: ruptures.filter(|r| r.count > 1).map(|r| r.standard_error()),
        regime: verdict.regime,
        stick_slip_cycles: verdict.cycles,
        oscillation: verdict.oscillation,
        stability: verdict.numerics,
        rng_period_exceeded: engine
            .counters()
            .steps
            .and_then(|steps| crate::engine::fixed::park_miller_period_exceeded(scene, steps)),
        counters: engine.counters(),
        wall_seconds,
        parameters: scene.clone(),
    };
    let t = engine.time();
    for (quantity, value) in [
        ("friction_mean", summary.friction_mean),
        ("friction_std", summary.friction_std),
        ("bond_force_mean", summary.bond_force_mean),
        ("viscous_force_mean", summary.viscous_force_mean),
        ("attached_fraction_mean", summary.attached_fraction_mean),
    ] {
        if !value.is_finite() {
            return Err(EngineError::NonFinite { t, quantity, value });
        }
    }
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runner::drive::StopFlag;
    use crate::test_scenes::{fig1_with, summary_without_wall_time};

    #[test]
    fn a_run_without_a_stop_request_is_not_stopped() {
        // The flag is only read: an unset flag changes nothing.
        let scene = fig1_with(&["run.t_end=30"]);
        let opts = RunOptions { stop: Some(StopFlag::new()), ..RunOptions::default() };
        let a = run_scene_with(&scene, None, &opts).unwrap();
        let b = run_scene(&scene, None).unwrap();
        assert_eq!(summary_without_wall_time(&a), summary_without_wall_time(&b));
    }

    /// `trace.csv`'s last row is at `t_end` for the exact engine, and at the end of the
    /// fixed engine's last step, `ceil(t_end / dt) dt`, when `t_end` is not a whole number of
    /// steps (docs/runs.md); the window of the summary ends at `t_end` either way.
    #[test]
    fn the_trace_ends_at_t_end_or_at_the_end_of_the_last_step() {
        for (engine, last) in [("exact", "10.3"), ("fixed", "10.5")] {
            let scene =
                fig1_with(&[&format!("run.engine={engine}"), "fixed.dt=0.5", "run.t_end=10.3", "output.sample_dt=1"]);
            let dir = tempfile::tempdir().unwrap();
            let s = run_scene(&scene, Some(dir.path())).unwrap();
            let trace = std::fs::read_to_string(dir.path().join("trace.csv")).unwrap();
            let times: Vec<&str> = trace.lines().skip(1).map(|l| l.split(',').next().unwrap()).collect();
            assert_eq!(times.len(), 12, "{engine}: {times:?}");
            assert_eq!((times[10], times[11]), ("10.0", last), "{engine}");
            assert_eq!(s.t_end, 10.3);
            if engine == "fixed" {
                assert_eq!(s.counters.steps, Some(21));
            }
        }
    }
}
