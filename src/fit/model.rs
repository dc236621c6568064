//! The misfit of a fit and its evaluations.
//!
//! An evaluation at parameter values `theta` runs every data point's conditions `c_i` with
//! `theta` applied, `R` replicas each, and takes the mean friction per junction over the
//! replicas, `F_sim(theta, c_i)`, with its standard error `se_i` (the replicas' sample
//! standard deviation over `sqrt(R)`; 0 with one replica). Replica `r` of point `i` has the
//! same seed at every `theta` (common random numbers: [`crate::studies::seeds::derive_all`]
//! of the scene's `run.seed`, the point index and the replica; with the Park–Miller
//! generator, disjoint blocks of its cycle, [`crate::studies::seeds::sweep_park_miller_seeds`]),
//! so that the misfit changes smoothly with `theta` instead of jumping with fresh noise at
//! every evaluation.
//!
//! The misfit minimised (the "score"):
//! - with `sigma` in the data: `chi2 = sum_i ((F_sim_i - F_i) / s_i)^2`,
//!   `s_i^2 = sigma_i^2 + se_i^2`;
//! - without: `SSR = sum_i (F_sim_i - F_i)^2`; the common `sigma^2` is then estimated from
//!   the residuals at the optimum, `SSR_min / (n - p)`, and `chi2 = SSR / sigma^2`.

use std::collections::HashMap;
use std::sync::Mutex;

use serde::{Deserialize, Serialize};

use super::data::DataSet;
use super::free::{FreeParam, assignment};
use crate::runner::StopFlag;
use crate::scene::{EngineKind, RngKind, Scene};
use crate::studies::journal::Journal;
use crate::studies::seeds;

/// One evaluation: the free parameters' values and, per data point, the simulated mean
/// friction per junction and its standard error over the replicas.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Evaluation {
    pub values: Vec<f64>,
    pub mean: Vec<f64>,
    pub se: Vec<f64>,
}

/// Runs scenes and returns each one's mean friction per junction, in order. The CLI runs
/// them on a rayon pool; Python hands them to Dask.
pub trait Simulator: Sync {
    fn friction_per_junction(&self, scenes: &[Scene]) -> Result<Vec<f64>, String>;
}

/// A fit's problem: the scene, the data, the free parameters, the replicas and their seeds.
#[derive(Clone, Debug)]
pub struct Problem {
    pub base: Scene,
    pub data: DataSet,
    pub free: Vec<FreeParam>,
    pub replicas: usize,
    /// `seeds[i][r]`: the seed of replica `r` at data point `i`, the same at every `theta`.
    pub seeds: Vec<Vec<u64>>,
}

/// Why a fit stopped before its result.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("at {at}: {message}")]
    Run { at: String, message: String },
    #[error("the fit was stopped after {done} evaluations")]
    Stopped { done: usize },
    #[error("the fit needs more than --max-evaluations {max} evaluations")]
    TooMany { max: usize },
    #[error("{0}")]
    Journal(String),
}

impl Problem {
    /// Checks that there are enough points for the free parameters (`n >= p` with sigma
    /// given, `n > p` without, to estimate it) and derives the replicas' seeds.
    pub fn new(base: Scene, data: DataSet, free: Vec<FreeParam>, replicas: usize) -> Result<Problem, String> {
        let (n, p) = (data.len(), free.len());
        let need = if data.has_sigma { p } else { p + 1 };
        if n < need {
            return Err(format!(
                "the data hold {n} point{} for {p} free parameter{}: a fit needs at least {need}{}",
                if n == 1 { "" } else { "s" },
                if p == 1 { "" } else { "s" },
                if data.has_sigma {
                    ""
                } else {
                    " (one more than the free parameters without a sigma column, to estimate sigma)"
                }
            ));
        }
        if replicas == 0 {
            return Err("--replicas 0: must be at least 1".into());
        }
        let mut seeds = seeds::derive_all(base.run.seed, n, replicas);
        if base.run.engine == EngineKind::Fixed && base.fixed.rng == RngKind::ParkMiller {
            // The replicas of a data point take disjoint blocks of the generator's cycle (as a
            // sweep's do), of the draws its runs can use at the smallest step the fit may set.
            for (i, row) in seeds.iter_mut().enumerate() {
                let mut o = data.overrides(i);
                if let Some(dt) = free.iter().find(|f| f.field == "fixed.dt") {
                    o.push(assignment("fixed.dt", dt.low));
                }
                let scene = base.with_overrides(&o).map_err(|e| e.to_string())?;
                let draws = seeds::replica_draws(&scene);
                *row = seeds::sweep_park_miller_seeds(base.run.seed, i as u64, replicas, draws).ok_or_else(|| {
                    let line = data.points[i].line;
                    format!("--replicas {replicas}: at data line {line} {}", seeds::blocks_do_not_fit(replicas, draws))
                })?;
            }
        }
        Ok(Problem { base, data, free, replicas, seeds })
    }

    /// The free parameters' values as `--set` assignments.
    pub fn assignments(&self, values: &[f64]) -> Vec<String> {
        self.free.iter().zip(values).map(|(p, &v)| assignment(&p.field, v)).collect()
    }

    /// The scene of every run at `values`: point by point, replicas in order.
    pub fn scenes(&self, values: &[f64]) -> Result<Vec<Scene>, FitError> {
        let mut out = Vec::with_capacity(self.data.len() * self.replicas);
        for i in 0..self.data.len() {
            let mut o = self.data.overrides(i);
            o.extend(self.assignments(values));
            let scene = self.base.with_overrides(&o).map_err(|e| FitError::Run {
                at: format!("data line {}", self.data.points[i].line),
                message: e.to_string(),
            })?;
            for &seed in &self.seeds[i] {
                let mut s = scene.clone();
                s.run.seed = seed;
                out.push(s);
            }
        }
        Ok(out)
    }

    /// Means and standard errors per point from the runs' frictions (point-major).
    pub fn evaluation(&self, values: &[f64], friction: &[f64]) -> Evaluation {
        let r = self.replicas;
        let (mut mean, mut se) = (Vec::new(), Vec::new());
        for chunk in friction.chunks(r) {
            let s = crate::studies::stats::ReplicaStats::of(chunk.iter().copied().map(Some));
            mean.push(s.mean);
            se.push(if r > 1 { s.se } else { 0.0 });
        }
        Evaluation { values: values.to_vec(), mean, se }
    }

    /// Per data point of `e`: the residual `r_i = F_sim_i - F_i`, its variance `s_i^2 =
    /// sigma_i^2 + se_i^2` (1 without sigma) and `se_i`.
    fn residuals<'e>(&'e self, e: &'e Evaluation) -> impl Iterator<Item = (f64, f64, f64)> + 'e {
        self.data.points.iter().enumerate().map(|(i, p)| {
            let se = e.se[i];
            (e.mean[i] - p.friction, p.sigma.map_or(1.0, |s| s * s + se * se), se)
        })
    }

    /// The score of an evaluation: `chi2` with sigma given, `SSR` without.
    pub fn score(&self, e: &Evaluation) -> f64 {
        self.residuals(e).map(|(r, var, _)| r * r / var).sum()
    }

    /// The standard deviation of the score's simulation noise at `e`: each mean `F_sim_i`
    /// carries noise of standard error `se_i`, which moves the score by
    /// `2 r_i se_i / s_i^2` (`r_i = F_sim_i - F_i`; `2 r_i se_i` without sigma), so
    /// `sqrt(sum_i (2 r_i se_i / s_i^2)^2)`. Differences of the score below it are noise:
    /// the optimiser's tolerance is not set below it ([`super::solve`]). 0 with one replica.
    pub fn score_noise(&self, e: &Evaluation) -> f64 {
        self.residuals(e).map(|(r, var, se)| (2.0 * r * se / var).powi(2)).sum::<f64>().sqrt()
    }

    /// The arguments that decide the evaluations, as one line (for the journal's header):
    /// the free parameters, the replicas, and a checksum of the data as read.
    pub fn arguments(&self, max_evaluations: usize) -> String {
        let free = self.free.iter().map(FreeParam::describe).collect::<Vec<_>>().join(",");
        let data = format!("{:?}", self.data);
        let sum = crate::output::checkpoint::Checksum::of(data.as_bytes());
        format!("--free {free} --replicas {} --max-evaluations {max_evaluations} --data {sum:016x}", self.replicas)
    }
}

/// The misfit as a function of the free parameters, with every evaluation cached (and
/// journaled), counted, and stoppable.
pub struct Objective<'a> {
    pub problem: &'a Problem,
    sim: &'a dyn Simulator,
    state: Mutex<Cache>,
    journal: Option<&'a Journal>,
    stop: Option<&'a StopFlag>,
    max: usize,
    /// Called after each new evaluation with (evaluations so far, best score so far, the
    /// fit's stage), one call at a time and in the order of the count.
    pub on_new: Option<OnNew<'a>>,
    stage: std::sync::atomic::AtomicU8,
}

/// A fit's progress report: (evaluations so far, best score so far, stage).
pub type OnNew<'a> = Box<dyn Fn(usize, f64, Stage) + Sync + 'a>;

/// The stage of a fit, for its progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The search for the optimum.
    Search,
    /// The profiles of the intervals.
    Profiles,
}

impl Stage {
    pub fn as_str(self) -> &'static str {
        match self {
            Stage::Search => "search for the optimum",
            Stage::Profiles => "profiles",
        }
    }
}

#[derive(Default)]
struct Cache {
    /// Every evaluation, in the order made (or read from the journal).
    list: Vec<Evaluation>,
    index: HashMap<Vec<u64>, usize>,
    /// How many of `list` were made by this process.
    new: usize,
    /// Which of `list` this process has asked for (made, or taken from the journal).
    asked: Vec<bool>,
    best: f64,
    error: Option<FitError>,
}

fn key(values: &[f64]) -> Vec<u64> {
    values.iter().map(|v| v.to_bits()).collect()
}

impl<'a> Objective<'a> {
    /// `done`: evaluations already made (from a journal), in their order.
    pub fn new(
        problem: &'a Problem,
        sim: &'a dyn Simulator,
        done: Vec<Evaluation>,
        journal: Option<&'a Journal>,
        stop: Option<&'a StopFlag>,
        max: usize,
    ) -> Self {
        let mut cache = Cache { best: f64::INFINITY, ..Cache::default() };
        for e in done {
            cache.best = cache.best.min(problem.score(&e));
            cache.index.insert(key(&e.values), cache.list.len());
            cache.list.push(e);
            cache.asked.push(false);
        }
        Objective { problem, sim, state: Mutex::new(cache), journal, stop, max, on_new: None, stage: 0.into() }
    }

    /// The evaluation at `values` (field values), made or taken from the cache.
    pub fn evaluate(&self, values: &[f64]) -> Result<Evaluation, FitError> {
        let k = key(values);
        {
            let mut c = self.state.lock().unwrap_or_else(|p| p.into_inner());
            if let Some(&i) = c.index.get(&k) {
                c.asked[i] = true;
                return Ok(c.list[i].clone());
            }
            // Another search (a profile's side) has failed: stop this one too.
            if c.error.is_some() {
                return Err(FitError::Stopped { done: c.list.len() });
            }
            if c.list.len() >= self.max {
                return Err(FitError::TooMany { max: self.max });
            }
        }
        if self.stop.is_some_and(|s| s.is_requested()) {
            return Err(FitError::Stopped { done: self.evaluations() });
        }
        let p = self.problem;
        let scenes = p.scenes(values)?;
        let friction = match self.sim.friction_per_junction(&scenes) {
            Ok(f) => f,
            Err(_) if self.stop.is_some_and(|s| s.is_requested()) => {
                return Err(FitError::Stopped { done: self.evaluations() });
            }
            Err(message) => return Err(FitError::Run { at: p.assignments(values).join(", "), message }),
        };
        if let Some(bad) = friction.iter().position(|f| !f.is_finite()) {
            return Err(FitError::Run {
                at: p.assignments(values).join(", "),
                message: format!(
                    "the run at data line {} gave a friction that is not finite",
                    p.data.points[bad / p.replicas].line
                ),
            });
        }
        let e = p.evaluation(values, &friction);
        let score = p.score(&e);
        if !score.is_finite() {
            return Err(FitError::Run {
                at: p.assignments(values).join(", "),
                message: format!(
                    "the misfit is {} (a simulated friction's distance from the data, over its sigma, overflows)",
                    crate::scene::error::compact(score)
                ),
            });
        }
        let mut c = self.state.lock().unwrap_or_else(|p| p.into_inner());
        // Made meanwhile by another search (the same values give the same evaluation):
        // kept once.
        if let Some(&i) = c.index.get(&k) {
            c.asked[i] = true;
            return Ok(c.list[i].clone());
        }
        let n = c.list.len();
        if let Some(j) = self.journal {
            j.append(n, p.base.run.seed, &e).map_err(|err| FitError::Journal(err.to_string()))?;
        }
        c.best = c.best.min(score);
        c.index.insert(k, n);
        c.list.push(e.clone());
        c.asked.push(true);
        c.new += 1;
        // Reported with the state still held, so that the calls come in the order of the
        // count even when several searches evaluate at once (the profiles' sides).
        if let Some(f) = &self.on_new {
            f(n + 1, c.best, self.stage());
        }
        drop(c);
        Ok(e)
    }

    /// The score at `values`; an error is kept (see [`Objective::take_error`]) and `None`
    /// returned.
    pub fn score(&self, values: &[f64]) -> Option<f64> {
        match self.evaluate(values) {
            Ok(e) => Some(self.problem.score(&e)),
            Err(err) => {
                self.state.lock().unwrap_or_else(|p| p.into_inner()).error.get_or_insert(err);
                None
            }
        }
    }

    /// The fit's stage, as [`Objective::set_stage`] last set it.
    pub fn stage(&self) -> Stage {
        if self.stage.load(std::sync::atomic::Ordering::Relaxed) == 0 { Stage::Search } else { Stage::Profiles }
    }

    /// Sets the fit's stage (for its progress).
    pub fn set_stage(&self, stage: Stage) {
        self.stage.store(u8::from(stage == Stage::Profiles), std::sync::atomic::Ordering::Relaxed);
    }

    /// The first error met, if any.
    pub fn take_error(&self) -> Option<FitError> {
        self.state.lock().unwrap_or_else(|p| p.into_inner()).error.take()
    }

    /// Evaluations made (in this process or read from a journal).
    pub fn evaluations(&self) -> usize {
        self.state.lock().unwrap_or_else(|p| p.into_inner()).list.len()
    }

    /// Distinct evaluations asked for by this process (made, or taken from the journal): on
    /// a resumed fit, as many as an uninterrupted one had made at the same stage.
    pub fn asked(&self) -> usize {
        self.state.lock().unwrap_or_else(|p| p.into_inner()).asked.iter().filter(|&&a| a).count()
    }

    /// Evaluations made by this process.
    pub fn new_evaluations(&self) -> usize {
        self.state.lock().unwrap_or_else(|p| p.into_inner()).new
    }

    /// Every evaluation so far.
    pub fn all(&self) -> Vec<Evaluation> {
        self.state.lock().unwrap_or_else(|p| p.into_inner()).list.clone()
    }
}

/// Runs scenes on a rayon pool; the results are in order whatever the number of threads.
pub struct PoolSimulator<'a> {
    pub pool: &'a rayon::ThreadPool,
    pub stop: Option<StopFlag>,
}

impl Simulator for PoolSimulator<'_> {
    fn friction_per_junction(&self, scenes: &[Scene]) -> Result<Vec<f64>, String> {
        use rayon::prelude::*;
        let opts = crate::runner::RunOptions { stop: self.stop.clone(), ..crate::runner::RunOptions::default() };
        self.pool.install(|| {
            scenes
                .par_iter()
                .map(|s| {
                    crate::runner::run_scene_with(s, None, &opts)
                        .map(|summary| summary.friction_per_junction)
                        .map_err(|e| format!("seed {}: {e}", s.run.seed))
                })
                .collect()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problem(replicas: usize, free: Vec<FreeParam>) -> Result<Problem, String> {
        let base = crate::test_scenes::fig1();
        let data = DataSet::parse("plate.v,friction,sigma\n0.5,1,1\n2,1,1\n", "d.csv", &base, 1.0).unwrap();
        Problem::new(base, data, free, replicas)
    }

    /// With the letter's generator (Fig. 1: `N = 300`, 150 steps), the replicas of a data
    /// point take consecutive blocks of the cycle, `N (steps + 1)` draws each, at the least
    /// step a free `fixed.dt` may take; more replicas than the cycle holds are refused.
    #[test]
    fn park_miller_replicas_take_disjoint_blocks_of_the_cycle() {
        let dt = FreeParam { field: "fixed.dt".into(), low: 0.5, high: 1.0, log: false, start: 1.0 };
        for (free, draws) in [(vec![], 300 * 151), (vec![dt], 300 * 301)] {
            let p = problem(3, free).unwrap();
            for (i, row) in p.seeds.iter().enumerate() {
                seeds::assert_consecutive_blocks(row, draws, Some(i as u64));
            }
        }
        let e = problem(50_000, vec![]).unwrap_err();
        assert!(
            e.starts_with("--replicas 50000: at data line 2 the replicas need 50000 x 45300 Park-Miller draws"),
            "{e}"
        );
    }
}
