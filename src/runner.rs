//! The runner owns the loop: it builds the engine a scene asks for, walks the output grid,
//! feeds the observers (statistics, regime detector, writers) and assembles the summary.

use std::io;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::engine::{Engine, EngineError, EngineVisitor, with_engine};
use crate::observe::regime::RegimeDetector;
use crate::observe::stats::{RuptureForces, WindowStats};
use crate::observe::{Nothing, Observer, Sample};
use crate::output::Summary;
use crate::output::atomic::write_whole;
use crate::output::csv::{EventWriter, TraceWriter};
use crate::scene::{BondKind, Scene};

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Engine(#[from] EngineError),
    #[error("cannot write {path}: {source}")]
    Output {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
}

fn output_error(dir: &Path, name: &str) -> impl FnOnce(io::Error) -> RunError {
    let path = dir.join(name);
    move |source| RunError::Output { path, source }
}

/// One stop of the output grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stop {
    pub t: f64,
    /// Whether the state is sampled here.
    pub sample: bool,
}

/// The output grid: samples at `k * sample_dt` up to `t_end` (the fixed engine's grid is
/// rounded to whole steps), a final sample at `t_end`, and a silent stop at `t_warmup` so
/// that no segment straddles the start of the averaging window.
#[derive(Clone, Copy, Debug)]
pub struct OutputGrid {
    pub sample_dt: f64,
    pub t_warmup: f64,
    pub t_end: f64,
}

impl OutputGrid {
    pub fn new(scene: &Scene, time_step: Option<f64>) -> Self {
        let mut sample_dt = scene.output.sample_dt;
        if let Some(dt) = time_step {
            sample_dt = dt * (sample_dt / dt).round().max(1.0);
        }
        OutputGrid { sample_dt, t_warmup: scene.run.t_warmup, t_end: scene.run.t_end }
    }

    /// The stops after `t = t_from`, in increasing order.
    pub fn stops_after(&self, t_from: f64) -> impl Iterator<Item = Stop> + '_ {
        // A grid point within round-off of t_end is t_end itself (sampled once, as the final
        // stop). The slack is relative to t_end *and* to sample_dt: at t_end = 1e12 a slack
        // of 1e-12 t_end alone (one time unit) dropped every sample in the last time unit.
        let last = (self.t_end * (1.0 - 1e-12)).max(self.t_end - 1e-6 * self.sample_dt);
        let mut k = (t_from / self.sample_dt).floor().max(0.0) as u64;
        while k as f64 * self.sample_dt <= t_from {
            k += 1;
        }
        let mut warmup = (self.t_warmup > t_from).then_some(self.t_warmup);
        let mut done = false;
        std::iter::from_fn(move || {
            if done {
                return None;
            }
            let ts = k as f64 * self.sample_dt;
            let sample = (ts < last).then_some(ts);
            if let Some(w) = warmup {
                match sample {
                    Some(ts) if ts < w => {}
                    Some(ts) if ts == w => warmup = None,
                    _ => {
                        warmup = None;
                        return Some(Stop { t: w, sample: false });
                    }
                }
            }
            if let Some(ts) = sample {
                k += 1;
                return Some(Stop { t: ts, sample: true });
            }
            done = true;
            Some(Stop { t: self.t_end, sample: true })
        })
    }
}

/// The observers every run has: window statistics and the regime detector.
pub type CoreObservers = (WindowStats, RegimeDetector);

/// Builds the core observers for a scene.
pub fn core_observers(scene: &Scene) -> CoreObservers {
    (
        WindowStats::new(scene.run.t_warmup, scene.run.t_end, scene.junctions.n as u64),
        RegimeDetector::new(scene.run.t_warmup, scene.plate.v),
    )
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

/// Walks `engine` along the grid from its current time to `t_end`, feeding `obs`.
pub fn drive<E: Engine, O: Observer>(engine: &mut E, grid: &OutputGrid, obs: &mut O) -> Result<(), EngineError> {
    let mut last_sample_t = f64::NAN;
    if engine.time() == 0.0 {
        let s = engine.sample();
        check_finite(&s)?;
        obs.sample(&s);
        last_sample_t = s.t;
    }
    for stop in grid.stops_after(engine.time()) {
        engine.advance(stop.t, obs)?;
        let s = engine.sample();
        check_finite(&s)?;
        if stop.sample && s.t != last_sample_t {
            obs.sample(&s);
            last_sample_t = s.t;
        }
    }
    Ok(())
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
        regime: regime.regime(),
        stick_slip_cycles: regime.cycles(),
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

/// Runs a scene to its end. With `out = Some(dir)` (an existing, writable directory) the
/// files the scene asks for and `summary.json` are written there, each whole or not at all.
pub fn run_scene(scene: &Scene, out: Option<&Path>) -> Result<Summary, RunError> {
    with_engine(scene, RunVisitor { scene, out })?
}

struct RunVisitor<'a> {
    scene: &'a Scene,
    out: Option<&'a Path>,
}

impl EngineVisitor for RunVisitor<'_> {
    type Output = Result<Summary, RunError>;
    fn visit<E: Engine>(self, engine: E) -> Self::Output {
        let (scene, out) = (self.scene, self.out);
        let events = match out {
            Some(dir) if scene.output.events => {
                Some(EventWriter::create(dir).map_err(output_error(dir, "events.csv"))?)
            }
            _ => None,
        };
        let weak = scene.junctions.bond == BondKind::Weak;
        let ruptures = || RuptureForces::new(scene.run.t_warmup, scene.run.t_end);
        // Event observers are chosen statically: a run that logs no events and has no
        // weak bonds compiles the event path out of the engine.
        match (events, weak) {
            (None, false) => run_with(engine, scene, out, Nothing).map(|(s, _)| s),
            (None, true) => run_with(engine, scene, out, ruptures()).map(|(s, _)| s),
            (Some(ev), false) => finish_events(run_with(engine, scene, out, ev), out),
            (Some(ev), true) => {
                let (summary, (ev, _)) = run_with(engine, scene, out, (ev, ruptures()))?;
                finish_events(Ok((summary, ev)), out)
            }
        }
    }
}

fn finish_events(r: Result<(Summary, EventWriter), RunError>, out: Option<&Path>) -> Result<Summary, RunError> {
    let (summary, ev) = r?;
    let dir = out.expect("events are only written with an output directory");
    ev.0.finish().map_err(output_error(dir, "events.csv"))?;
    Ok(summary)
}

/// A few observers need their results back after the run.
trait Extra: Observer {
    fn rupture_forces(&self) -> Option<&RuptureForces> {
        None
    }
    fn discard(self);
}
impl Extra for Nothing {
    fn discard(self) {}
}
impl Extra for RuptureForces {
    fn rupture_forces(&self) -> Option<&RuptureForces> {
        Some(self)
    }
    fn discard(self) {}
}
impl Extra for EventWriter {
    fn discard(self) {
        self.0.discard()
    }
}
impl Extra for (EventWriter, RuptureForces) {
    fn rupture_forces(&self) -> Option<&RuptureForces> {
        Some(&self.1)
    }
    fn discard(self) {
        self.0.0.discard()
    }
}

fn run_with<E: Engine, X: Extra>(
    mut engine: E,
    scene: &Scene,
    out: Option<&Path>,
    extra: X,
) -> Result<(Summary, X), RunError> {
    let started = Instant::now();
    let trace = match out {
        Some(dir) if scene.output.trace => Some(TraceWriter::create(dir).map_err(output_error(dir, "trace.csv"))?),
        _ => None,
    };
    let grid = OutputGrid::new(scene, engine.time_step());
    let mut obs = (core_observers(scene), (trace, extra));
    if let Err(e) = drive(&mut engine, &grid, &mut obs) {
        let (_, (trace, extra)) = obs;
        if let Some(t) = trace {
            t.0.discard();
        }
        extra.discard();
        return Err(e.into());
    }
    let (core, (trace, extra)) = obs;
    let summary = match summarize(scene, &engine, &core, extra.rupture_forces(), started.elapsed().as_secs_f64()) {
        Ok(s) => s,
        Err(e) => {
            if let Some(t) = trace {
                t.0.discard();
            }
            extra.discard();
            return Err(e.into());
        }
    };
    if let Some(dir) = out {
        if let Some(t) = trace {
            t.0.finish().map_err(output_error(dir, "trace.csv"))?;
        }
        let json = serde_json::to_string_pretty(&summary).expect("summary serializes");
        write_whole(dir, "summary.json", json.as_bytes()).map_err(output_error(dir, "summary.json"))?;
    }
    Ok((summary, extra))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(sample_dt: f64, t_warmup: f64, t_end: f64) -> OutputGrid {
        OutputGrid { sample_dt, t_warmup, t_end }
    }

    #[test]
    fn stops_cover_samples_warmup_and_end() {
        let g = grid(1.0, 2.5, 4.0);
        let s: Vec<Stop> = g.stops_after(0.0).collect();
        let t: Vec<(f64, bool)> = s.iter().map(|s| (s.t, s.sample)).collect();
        assert_eq!(t, vec![(1.0, true), (2.0, true), (2.5, false), (3.0, true), (4.0, true)]);
    }

    #[test]
    fn warmup_on_a_sample_is_one_stop() {
        let t: Vec<f64> = grid(0.5, 1.0, 2.0).stops_after(0.0).map(|s| s.t).collect();
        assert_eq!(t, vec![0.5, 1.0, 1.5, 2.0]);
    }

    #[test]
    fn resuming_mid_grid_continues_it() {
        let t: Vec<f64> = grid(1.0, 0.0, 3.5).stops_after(1.0).map(|s| s.t).collect();
        assert_eq!(t, vec![2.0, 3.0, 3.5]);
        let t: Vec<f64> = grid(1.0, 0.0, 3.5).stops_after(1.25).map(|s| s.t).collect();
        assert_eq!(t, vec![2.0, 3.0, 3.5]);
    }

    #[test]
    fn end_not_on_grid_and_grid_coarser_than_run() {
        let t: Vec<f64> = grid(10.0, 0.0, 3.0).stops_after(0.0).map(|s| s.t).collect();
        assert_eq!(t, vec![3.0]);
    }

    /// Regression: at t_end = 1e12 the end slack was 1e-12 t_end = 1 time unit, and the
    /// samples at t_end - 0.5 (and any in the last time unit) were dropped.
    #[test]
    fn late_samples_are_kept_at_large_times() {
        let t0 = 1e12;
        let t: Vec<f64> = grid(0.25, 0.0, t0 + 1.0).stops_after(t0).map(|s| s.t).collect();
        assert_eq!(t, vec![t0 + 0.25, t0 + 0.5, t0 + 0.75, t0 + 1.0]);
    }
}
