//! The runner owns the loop: it builds the engine a scene asks for, walks the output grid,
//! feeds the observers (statistics, regime detector, writers) and assembles the summary.
//!
//! Long runs (docs/runs.md): outputs are streamed to `NAME.part` and flushed at line
//! boundaries at least every [`FLUSH_EVERY`]; with [`RunOptions::checkpoint_every`] the
//! runner writes `checkpoint.bin` at output-grid stops ([`checkpoint`]), from which
//! [`resume`] continues a killed run to the same bytes; [`progress`] shows where a run is.

pub mod checkpoint;
pub mod progress;

use std::io;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::engine::{Engine, EngineError, EngineVisitor, with_engine};
use crate::observe::regime::RegimeDetector;
use crate::observe::stats::{RuptureForces, WindowStats};
use crate::observe::{Nothing, Observer, Sample};
use crate::output::Summary;
use crate::output::atomic::write_whole;
use crate::output::csv::{EventWriter, TraceWriter};
use crate::scene::{BondKind, Scene};

pub use checkpoint::{ResumeError, Resumed, resume};

/// Outputs are flushed to the operating system at least this often (at grid stops).
pub const FLUSH_EVERY: Duration = Duration::from_secs(1);

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
    /// Writing failed after a checkpoint was written: the partial outputs and the
    /// checkpoint are kept, and the run can be resumed once the cause is fixed.
    #[error("{source}; the run stopped at t = {t} and can be resumed from its checkpoint with `stickslip resume {}`", dir.display())]
    Resumable {
        #[source]
        source: Box<RunError>,
        dir: PathBuf,
        t: f64,
    },
}

fn output_error(dir: &Path, name: &str) -> impl FnOnce(io::Error) -> RunError {
    let path = dir.join(name);
    move |source| RunError::Output { path, source }
}

/// How a run is carried out, beyond its scene. The default (no checkpoints, no progress)
/// is [`run_scene`]'s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunOptions {
    /// Write a checkpoint at output-grid stops, at most every this many seconds of wall
    /// time (> 0). Needs an output directory.
    pub checkpoint_every: Option<f64>,
    /// Show progress on stderr when stderr is a terminal and the run lasts more than
    /// [`progress::SHOW_AFTER`].
    pub progress: bool,
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
    (WindowStats::new(scene.run.t_warmup, scene.run.t_end, scene.junctions.n as u64), RegimeDetector::for_scene(scene))
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

/// Where a run is on its output grid: what [`drive_from`] needs to continue it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridPosition {
    /// Stops of `grid.stops_after(0.0)` done.
    pub stops_done: u64,
    /// Time of the last sample fed to the observers (NaN before the first).
    pub last_sample_t: f64,
}

impl Default for GridPosition {
    fn default() -> Self {
        GridPosition { stops_done: 0, last_sample_t: f64::NAN }
    }
}

/// As [`drive`], from grid position `pos` (the start, or a checkpoint's), keeping `pos`
/// up to date. After every stop but the last, `at_stop` is called with the engine, the
/// observers and the position: the engine is between two advances there, in the state a
/// checkpoint records.
pub fn drive_from<E, O, H>(
    engine: &mut E,
    grid: &OutputGrid,
    obs: &mut O,
    pos: &mut GridPosition,
    mut at_stop: H,
) -> Result<(), RunError>
where
    E: Engine,
    O: Observer,
    H: FnMut(&E, &mut O, &GridPosition) -> Result<(), RunError>,
{
    if pos.stops_done == 0 && engine.time() == 0.0 {
        let s = engine.sample();
        check_finite(&s)?;
        obs.sample(&s);
        pos.last_sample_t = s.t;
    }
    let mut stops = grid.stops_after(0.0).skip(pos.stops_done as usize).peekable();
    while let Some(stop) = stops.next() {
        engine.advance(stop.t, obs)?;
        let s = engine.sample();
        check_finite(&s)?;
        if stop.sample && s.t != pos.last_sample_t {
            obs.sample(&s);
            pos.last_sample_t = s.t;
        }
        pos.stops_done += 1;
        if stops.peek().is_some() {
            at_stop(engine, obs, pos)?;
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
    run_scene_with(scene, out, &RunOptions::default())
}

/// As [`run_scene`], with checkpoints and progress as `opts` asks. A checkpoint and
/// partial outputs left in `out` by an earlier, killed run are removed first.
pub fn run_scene_with(scene: &Scene, out: Option<&Path>, opts: &RunOptions) -> Result<Summary, RunError> {
    if let Some(dir) = out {
        checkpoint::remove_stale(dir)?;
    }
    with_engine(scene, RunVisitor { ctx: Ctx { scene, out, opts: *opts } })?
}

/// What a run needs besides its engine.
#[derive(Clone, Copy)]
struct Ctx<'a> {
    scene: &'a Scene,
    out: Option<&'a Path>,
    opts: RunOptions,
}

/// Where a run starts: `t = 0`, or a checkpoint.
struct Start {
    pos: GridPosition,
    core: CoreObservers,
    trace: Option<TraceWriter>,
    /// Wall time spent before this process.
    wall_seconds: f64,
    /// Checkpoints written before this process.
    checkpoints: u64,
    /// Time of the checkpoint the run was resumed from.
    checkpoint_t: Option<f64>,
}

struct RunVisitor<'a> {
    ctx: Ctx<'a>,
}

impl EngineVisitor for RunVisitor<'_> {
    type Output = Result<Summary, RunError>;
    fn visit<E: Engine>(self, engine: E) -> Self::Output {
        let scene = self.ctx.scene;
        let (trace, events) = match self.ctx.out {
            Some(dir) => create_writers(scene, dir)?,
            None => (None, None),
        };
        let start = Start {
            pos: GridPosition::default(),
            core: core_observers(scene),
            trace,
            wall_seconds: 0.0,
            checkpoints: 0,
            checkpoint_t: None,
        };
        run_extra(engine, &self.ctx, events, None, start)
    }
}

/// Creates the CSV files the scene asks for (none, or both, are left on error).
fn create_writers(scene: &Scene, dir: &Path) -> Result<(Option<TraceWriter>, Option<EventWriter>), RunError> {
    let trace = match scene.output.trace {
        true => Some(TraceWriter::create(dir).map_err(output_error(dir, TraceWriter::NAME))?),
        false => None,
    };
    let events = match scene.output.events {
        true => match EventWriter::create(dir) {
            Ok(ev) => Some(ev),
            Err(e) => {
                if let Some(t) = trace {
                    t.0.discard();
                }
                return Err(output_error(dir, EventWriter::NAME)(e));
            }
        },
        false => None,
    };
    Ok((trace, events))
}

/// Chooses the event observers and runs. `ruptures` are restored rupture-force statistics.
fn run_extra<E: Engine>(
    engine: E,
    ctx: &Ctx,
    events: Option<EventWriter>,
    ruptures: Option<RuptureForces>,
    start: Start,
) -> Result<Summary, RunError> {
    let run = &ctx.scene.run;
    let weak = ctx.scene.junctions.bond == BondKind::Weak;
    let ruptures = move || ruptures.unwrap_or_else(|| RuptureForces::new(run.t_warmup, run.t_end));
    // Event observers are chosen statically: a run that logs no events and has no
    // weak bonds compiles the event path out of the engine.
    match (events, weak) {
        (None, false) => run_engine(engine, ctx, Nothing, start),
        (None, true) => run_engine(engine, ctx, ruptures(), start),
        (Some(ev), false) => run_engine(engine, ctx, ev, start),
        (Some(ev), true) => run_engine(engine, ctx, (ev, ruptures()), start),
    }
}

/// The observers that need more than observing: rupture-force statistics for the summary,
/// the event writer for checkpoints and the end of the run.
trait Extra: Observer {
    fn rupture_forces(&self) -> Option<&RuptureForces> {
        None
    }
    fn events(&mut self) -> Option<&mut EventWriter> {
        None
    }
    fn into_events(self) -> Option<EventWriter>;
}
impl Extra for Nothing {
    fn into_events(self) -> Option<EventWriter> {
        None
    }
}
impl Extra for RuptureForces {
    fn rupture_forces(&self) -> Option<&RuptureForces> {
        Some(self)
    }
    fn into_events(self) -> Option<EventWriter> {
        None
    }
}
impl Extra for EventWriter {
    fn events(&mut self) -> Option<&mut EventWriter> {
        Some(self)
    }
    fn into_events(self) -> Option<EventWriter> {
        Some(self)
    }
}
impl Extra for (EventWriter, RuptureForces) {
    fn rupture_forces(&self) -> Option<&RuptureForces> {
        Some(&self.1)
    }
    fn events(&mut self) -> Option<&mut EventWriter> {
        Some(&mut self.0)
    }
    fn into_events(self) -> Option<EventWriter> {
        Some(self.0)
    }
}

/// Every observer of a run.
type Observers<X> = (CoreObservers, (Option<TraceWriter>, (X, progress::Probe)));

/// The engine's work counter: steps (fixed engine) or events (exact engine).
fn work(engine: &impl Engine) -> (u64, &'static str) {
    let c = engine.counters();
    match (c.steps, c.events) {
        (Some(s), _) => (s, "steps"),
        (None, e) => (e.unwrap_or(0), "events"),
    }
}

fn run_engine<E: Engine, X: Extra>(mut engine: E, ctx: &Ctx, extra: X, start: Start) -> Result<Summary, RunError> {
    let scene = ctx.scene;
    let started = Instant::now();
    let grid = OutputGrid::new(scene, engine.time_step());
    let (work0, unit) = work(&engine);
    let span = progress::Span { t0: engine.time(), t_end: scene.run.t_end, work0, unit };
    let (progress, probe) = progress::Progress::start(ctx.opts.progress, span);
    let mut control = StopControl::new(ctx, started, &start);
    let wall_before = start.wall_seconds;
    let mut pos = start.pos;
    let mut obs: Observers<X> = (start.core, (start.trace, (extra, probe)));
    let driven = drive_from(&mut engine, &grid, &mut obs, &mut pos, |e, o, p| control.at_stop(e, o, p, &progress));
    progress.finish();
    let checkpoint_t = control.checkpoint_t;
    let (core, (mut trace, (mut extra, _))) = obs;
    let wall_seconds = wall_before + started.elapsed().as_secs_f64();
    let result = driven
        .and_then(|()| summarize(scene, &engine, &core, extra.rupture_forces(), wall_seconds).map_err(RunError::from));
    // Flush everything before anything is renamed, so that a write error leaves the run
    // as it was (resumable, if it has a checkpoint).
    let result = result.and_then(|s| {
        if let Some(dir) = ctx.out {
            if let Some(t) = trace.as_mut() {
                t.0.flush().map_err(output_error(dir, TraceWriter::NAME))?;
            }
            if let Some(ev) = extra.events() {
                ev.0.flush().map_err(output_error(dir, EventWriter::NAME))?;
            }
        }
        Ok(s)
    });
    let summary = match result {
        Ok(s) => s,
        Err(e) => return Err(abandon(e, ctx.out, checkpoint_t, trace, extra)),
    };
    if let Some(dir) = ctx.out {
        if let Some(t) = trace {
            t.0.finish().map_err(output_error(dir, TraceWriter::NAME))?;
        }
        if let Some(ev) = extra.into_events() {
            ev.0.finish().map_err(output_error(dir, EventWriter::NAME))?;
        }
        // summary.json comes last: its presence says the run is complete.
        let json = serde_json::to_string_pretty(&summary).expect("summary serializes");
        write_whole(dir, "summary.json", json.as_bytes()).map_err(output_error(dir, "summary.json"))?;
        checkpoint::remove(dir)?;
    }
    Ok(summary)
}

/// A run that failed: an output error after a checkpoint keeps the partial outputs and
/// the checkpoint (the run can be resumed); any other failure removes them.
fn abandon<X: Extra>(
    e: RunError,
    out: Option<&Path>,
    checkpoint_t: Option<f64>,
    trace: Option<TraceWriter>,
    extra: X,
) -> RunError {
    if let (RunError::Output { .. }, Some(dir), Some(t)) = (&e, out, checkpoint_t) {
        return RunError::Resumable { source: Box::new(e), dir: dir.to_path_buf(), t };
    }
    if let Some(t) = trace {
        t.0.discard();
    }
    if let Some(ev) = extra.into_events() {
        ev.0.discard();
    }
    if let Some(dir) = out {
        let _ = checkpoint::remove(dir);
    }
    e
}

/// Looks at the clock only every `stride` stops, with `stride` adapted so that it does so
/// every few milliseconds: a grid stop costs a decrement, however fine the grid.
struct Pacer {
    stride: u64,
    left: u64,
    last: Instant,
}

impl Pacer {
    const MIN_GAP: Duration = Duration::from_millis(5);
    const MAX_GAP: Duration = Duration::from_millis(50);

    fn new(now: Instant) -> Pacer {
        Pacer { stride: 1, left: 1, last: now }
    }

    /// The time now, every few milliseconds; `None` at the stops in between.
    #[inline]
    fn tick(&mut self) -> Option<Instant> {
        self.left -= 1;
        if self.left > 0 {
            return None;
        }
        let now = Instant::now();
        let gap = now - self.last;
        self.last = now;
        if gap < Self::MIN_GAP {
            self.stride = (self.stride * 2).min(1 << 24);
        } else if gap > Self::MAX_GAP {
            self.stride = (self.stride / 2).max(1);
        }
        self.left = self.stride;
        Some(now)
    }
}

/// What the runner does at grid stops: progress, flushes, checkpoints.
struct StopControl<'a> {
    ctx: &'a Ctx<'a>,
    started: Instant,
    wall_before: f64,
    pacer: Pacer,
    last_flush: Instant,
    last_checkpoint: Instant,
    /// Checkpoint interval, when there is a directory to write checkpoints to.
    every: Option<(Duration, &'a Path)>,
    checkpoints: u64,
    /// Time of the checkpoint on disk, if any.
    checkpoint_t: Option<f64>,
}

impl<'a> StopControl<'a> {
    fn new(ctx: &'a Ctx<'a>, started: Instant, start: &Start) -> Self {
        let every = match (ctx.opts.checkpoint_every, ctx.out) {
            (Some(s), Some(dir)) => Some((Duration::from_secs_f64(s), dir)),
            _ => None,
        };
        StopControl {
            ctx,
            started,
            wall_before: start.wall_seconds,
            pacer: Pacer::new(started),
            last_flush: started,
            last_checkpoint: started,
            every,
            checkpoints: start.checkpoints,
            checkpoint_t: start.checkpoint_t,
        }
    }

    fn at_stop<E: Engine, X: Extra>(
        &mut self,
        engine: &E,
        obs: &mut Observers<X>,
        pos: &GridPosition,
        progress: &progress::Progress,
    ) -> Result<(), RunError> {
        let Some(now) = self.pacer.tick() else {
            return Ok(());
        };
        progress.publish(work(engine).0);
        if let Some((every, dir)) = self.every {
            if now - self.last_checkpoint >= every {
                let wall_seconds = self.wall_before + self.started.elapsed().as_secs_f64();
                checkpoint::save(dir, self.ctx, engine, obs, pos, wall_seconds, self.checkpoints + 1)?;
                self.checkpoints += 1;
                self.checkpoint_t = Some(engine.time());
                self.last_checkpoint = Instant::now();
                self.last_flush = self.last_checkpoint;
                return Ok(());
            }
        }
        if now - self.last_flush >= FLUSH_EVERY {
            if let Some(dir) = self.ctx.out {
                let (_, (trace, (extra, _))) = obs;
                if let Some(t) = trace {
                    t.0.flush().map_err(output_error(dir, TraceWriter::NAME))?;
                }
                if let Some(ev) = extra.events() {
                    ev.0.flush().map_err(output_error(dir, EventWriter::NAME))?;
                }
            }
            self.last_flush = now;
        }
        Ok(())
    }
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
