//! A scaling study (`stickslip bench`): one scene run at growing `N` in both engines, in
//! this process, one run at a time, without output files, timing what a user's run costs.
//!
//! The scene is scaled with `N` as a junction count is (plate `k`, `mass` and `eta` times
//! `N / N_scene`, so that each junction sees the same plate) and run for about `work` units
//! of work: exact-engine events (ruptures and formations, expected as
//! [`crate::estimate::work::expected`] counts them) or fixed-engine junction-steps
//! (`N t_end / dt`), but at least [`MIN_SAMPLES`] output intervals (and fixed steps). The
//! warm-up keeps its share of `t_end`. Each run gives:
//!
//! - the cost per unit of work: `wall_seconds / events` (exact) or
//!   `wall_seconds / (N steps)` (fixed), from the run's own `wall_seconds` (the run's loop,
//!   statistics included);
//! - its set-up time: the whole call less `wall_seconds` (building the engine and its
//!   initial state, and the summary);
//! - memory per junction, twice: the estimate `stickslip validate` prints (engine state), and
//!   the rise of this process's peak resident memory during the run (`VmHWM`, reset before
//!   each run through `/proc/self/clear_refs`; the buffers that do not grow with `N` are in it
//!   too, so it is meaningful where `N` is large).

use std::time::Instant;

use crate::estimate::{self, Estimate};
use crate::runner::{RunError, run_scene};
use crate::scene::{EngineKind, Scene, SceneError};

/// Fewest output intervals (and fixed steps) a run of the study covers.
pub const MIN_SAMPLES: f64 = 20.0;

/// What the study runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Spec {
    /// Junction counts, increasing.
    pub sizes: Vec<usize>,
    /// Events (exact) or junction-steps (fixed) per run.
    pub work: f64,
    /// A fixed `t_end` for every run instead of `work`.
    pub t_end: Option<f64>,
}

/// `per_decade` junction counts per factor of ten from `n_min` to `n_max` (both included),
/// geometrically spaced and rounded to integers.
pub fn sizes(n_min: usize, n_max: usize, per_decade: u32) -> Vec<usize> {
    let (lo, hi) = (n_min as f64, n_max as f64);
    let steps = ((hi / lo).log10() * per_decade as f64 - 1e-9).ceil().max(0.0) as usize;
    let mut v: Vec<usize> = (0..=steps)
        .map(|i| if i == steps { n_max } else { (lo * 10f64.powf(i as f64 / per_decade as f64)).round() as usize })
        .collect();
    v.dedup();
    v
}

/// `base` with `n` junctions in `engine`, its plate scaled with `n`, no output files, run
/// for `t_end` (`None`: the scene's).
pub fn scene_at(base: &Scene, n: usize, engine: EngineKind, t_end: Option<f64>) -> Result<Scene, SceneError> {
    let scale = n as f64 / base.junctions.n as f64;
    let p = &base.plate;
    let t = t_end.unwrap_or(base.run.t_end);
    let warmup = base.run.t_warmup / base.run.t_end * t;
    let engine = engine_name(engine);
    base.with_overrides(&[
        format!("junctions.n={n}"),
        format!("plate.k={:?}", p.k * scale),
        format!("plate.mass={:?}", p.mass * scale),
        format!("plate.eta={:?}", p.eta * scale),
        format!("run.engine={engine}"),
        format!("run.t_end={t:?}"),
        format!("run.t_warmup={warmup:?}"),
        "output.trace=false".into(),
        "output.events=false".into(),
        "output.plot=false".into(),
    ])
}

/// The `t_end` that gives `scene` (at its `N` and engine) about `work` units of work, at
/// least [`MIN_SAMPLES`] output intervals and fixed steps.
pub fn t_end_for(scene: &Scene, work: f64) -> f64 {
    let floor = MIN_SAMPLES * scene.output.sample_dt.max(scene.fixed.dt);
    let t = match scene.run.engine {
        EngineKind::Fixed => work * scene.fixed.dt / scene.junctions.n as f64,
        EngineKind::Exact => {
            // Events grow about linearly in t: two corrections from the scene's own t_end.
            let events_at = |t: f64| {
                let mut s = scene.clone();
                s.run.t_end = t;
                estimate::work::expected(&s).events
            };
            let mut t = scene.run.t_end;
            for _ in 0..2 {
                let events = events_at(t);
                if events.is_nan() || events <= 0.0 {
                    return floor.max(scene.run.t_end);
                }
                t *= work / events;
            }
            t
        }
    };
    t.max(floor)
}

/// One run of the study.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub engine: EngineKind,
    pub n: usize,
    pub t_end: f64,
    /// Events (exact) or junction-steps (fixed) done.
    pub work: u64,
    pub run_seconds: f64,
    pub setup_seconds: f64,
    /// Bytes of the engine's state per junction, estimated.
    pub estimated_bytes_per_junction: f64,
    /// Rise of the peak resident memory during the run, per junction (`None` where the
    /// peak cannot be reset or read).
    pub measured_bytes_per_junction: Option<f64>,
}

impl Row {
    /// Nanoseconds per event (exact) or junction-step (fixed); NaN without work.
    pub fn ns_per_unit(&self) -> f64 {
        if self.work == 0 { f64::NAN } else { self.run_seconds * 1e9 / self.work as f64 }
    }
    /// What one unit of work is.
    pub fn unit(&self) -> &'static str {
        match self.engine {
            EngineKind::Exact => "event",
            EngineKind::Fixed => "junction-step",
        }
    }
}

/// The engine's name, as scene files write it.
pub fn engine_name(engine: EngineKind) -> &'static str {
    match engine {
        EngineKind::Exact => "exact",
        EngineKind::Fixed => "fixed",
    }
}

/// Why the study stopped.
#[derive(Debug, thiserror::Error)]
pub enum ScalingError {
    #[error("N = {n}: {source}")]
    Scene { n: usize, source: SceneError },
    #[error("N = {n}, {engine} engine: {source}")]
    Run { n: usize, engine: &'static str, source: RunError },
}

/// The two engines, in the order the study runs them at each `N`.
pub const ENGINES: [EngineKind; 2] = [EngineKind::Exact, EngineKind::Fixed];

/// The scene of each run, in order (per `N`, exact then fixed), with its estimate.
pub fn plan(base: &Scene, spec: &Spec) -> Result<Vec<(Scene, Estimate)>, ScalingError> {
    let mut runs = Vec::new();
    for &n in &spec.sizes {
        for engine in ENGINES {
            let scene_err = |source| ScalingError::Scene { n, source };
            let mut scene = scene_at(base, n, engine, spec.t_end).map_err(scene_err)?;
            if spec.t_end.is_none() {
                scene = scene_at(base, n, engine, Some(t_end_for(&scene, spec.work))).map_err(scene_err)?;
            }
            let est = Estimate::of(&scene, false);
            runs.push((scene, est));
        }
    }
    Ok(runs)
}

/// Runs `scene` once and measures it.
pub fn measure(scene: &Scene, est: &Estimate) -> Result<Row, ScalingError> {
    let n = scene.junctions.n;
    let engine = scene.run.engine;
    let before = reset_peak_resident();
    let started = Instant::now();
    let summary =
        run_scene(scene, None).map_err(|source| ScalingError::Run { n, engine: engine_name(engine), source })?;
    let total = started.elapsed().as_secs_f64();
    let peak = estimate::system::peak_resident();
    let work = match engine {
        EngineKind::Exact => summary.counters.events.unwrap_or(0),
        EngineKind::Fixed => summary.counters.steps.unwrap_or(0).saturating_mul(n as u64),
    };
    Ok(Row {
        engine,
        n,
        t_end: scene.run.t_end,
        work,
        run_seconds: summary.wall_seconds,
        setup_seconds: (total - summary.wall_seconds).max(0.0),
        estimated_bytes_per_junction: est.engine_bytes() as f64 / n as f64,
        measured_bytes_per_junction: before.zip(peak).map(|(b, p)| p.saturating_sub(b) as f64 / n as f64),
    })
}

/// Resets this process's peak resident memory to its current resident memory (Linux,
/// `/proc/self/clear_refs`); returns that, or `None` if either cannot be done.
fn reset_peak_resident() -> Option<u64> {
    std::fs::write("/proc/self/clear_refs", b"5").ok()?;
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = text.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

/// The header of `bench.csv`.
pub const CSV_HEADER: &str = "engine,n,t_end,unit,work,run_seconds,ns_per_unit,setup_seconds,estimated_bytes_per_junction,measured_bytes_per_junction";

/// `bench.csv`: one line per run (empty field where a figure is missing).
pub fn csv(rows: &[Row]) -> String {
    let mut s = format!("{CSV_HEADER}\n");
    for r in rows {
        let engine = engine_name(r.engine);
        let num = |v: f64| if v.is_finite() { format!("{v:?}") } else { String::new() };
        s.push_str(&format!(
            "{engine},{},{},{},{},{},{},{},{},{}\n",
            r.n,
            num(r.t_end),
            r.unit(),
            r.work,
            num(r.run_seconds),
            num(r.ns_per_unit()),
            num(r.setup_seconds),
            num(r.estimated_bytes_per_junction),
            r.measured_bytes_per_junction.map_or(String::new(), num),
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_geometric_and_include_both_ends() {
        assert_eq!(sizes(1000, 1000, 2), [1000]);
        assert_eq!(sizes(1000, 100_000, 1), [1000, 10_000, 100_000]);
        assert_eq!(sizes(1000, 100_000, 2), [1000, 3162, 10_000, 31_623, 100_000]);
        assert_eq!(sizes(1000, 20_000, 1), [1000, 10_000, 20_000]);
        assert_eq!(sizes(1, 3, 10), [1, 2, 3]);
    }
}
