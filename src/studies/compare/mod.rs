//! `stickslip compare`: error against run time (a work-precision diagram) of the fixed-step
//! engine and the exact engine on one scene.
//!
//! **What is estimated.** Each observable is a window average of one run (`friction_mean`,
//! `friction_std`, `attached_fraction_mean` over `[t_warmup, t_end]`, and for weak bonds the
//! run's mean rupture force). Its *target* is its expectation under the exact process for the
//! scene's own window, estimated by the **reference**: the exact engine over `ref_replicas`
//! independent replicas (mean and standard error over replicas).
//!
//! **Points.** The fixed engine at each `dt`, `replicas` replicas each: bias plus sampling
//! error. The exact engine at increasing *run lengths*, where the run length is the number of
//! replicas `r = 1, 2, 4, .., replicas` of the scene's window (total simulated time
//! `r t_end`): it has no bias, so its error is pure sampling error and falls as
//! `1/sqrt(r)`, i.e. as `1/sqrt(cost)`. (Lengthening `t_end` instead would change the
//! target: the window would hold less of the start-up transient and a finite-window standard
//! deviation has its own bias, so the exact engine would appear biased against a reference
//! computed for the scene's window.)
//!
//! **Tolerance of the exact points** (`--exact-rtol`, tilted law). The exact engine's one
//! approximation is the bond-force series' stated error `exact.rtol` (relative to `kappa l0
//! N`); the reference always runs at the scene's. Exact points at a looser tolerance are
//! cheaper, and their errors against that reference include whatever bias the looser
//! tolerance brings: the study shows what the tolerance costs instead of assuming it.
//!
//! **Errors and intervals.** For a point with mean `m` the error is `m - m_ref`. Its
//! standard deviation under zero bias is the **floor** `sqrt(se^2 + se_ref^2)`: the error
//! expected from sampling alone at that point's cost. The 95 % interval is
//! `error +- t * floor`, with `t` the Student-t quantile: for fixed points `se` is the
//! point's own standard error over its replicas and the degrees of freedom are
//! Welch–Satterthwaite's; for exact points, whose replicas have the reference's
//! distribution, `se = sd_ref / sqrt(r)` (a single replica has no spread of its own) and
//! the degrees of freedom are `ref_replicas - 1`.
//!
//! **Wall time** of a point is the sum of its replicas' measured wall times: its cost on
//! one core, as a campaign of such replicas would pay it. Jobs run in runs of consecutive
//! replicas of one point (`RUN_LENGTH`), the runs in a pseudo-random order (so that a change
//! of machine load still spreads over all points): a replica that follows one of the other
//! engine starts on caches and branch history that engine left behind, which cost the
//! exact engine's replicas more than the fixed-step ones (measured on the Fig. 1 scene:
//! docs/results.md, "Fig. 1 scene (strong bonds, tilted law)"). Replicas run one at a time
//! unless the caller asks for more threads (side by side they share the machine, which can
//! slow them; on the project machine two at a time measured the same), and `compare.md`
//! states how many ran at a time.
//!
//! **Guards.** A fixed point in which any replica diverges (`EngineError::Diverged`, or a
//! non-finite state) is reported as `diverged` with the number of diverged replicas. A
//! point at which any replica's run is `unstable` (the verdict of `stickslip run`,
//! [`crate::observe::regime::numerics`]: predicted by the stability analysis or seen as a
//! locked period-2 oscillation) is reported as `unstable`, with its numbers and the plate
//! growth factor with every junction attached ([`PlateLimit::radius_all`] of
//! [`crate::engine::fixed::stability::analyse`]).
//!
//! Layout: this file plans, runs and aggregates (data only); [`fit`] the bias model,
//! [`report`] `compare.csv` and `compare.md` ([`crate::plot::files`] writes them with
//! `compare.svg`, [`crate::plot::compare`]).
//!
//! [`PlateLimit::radius_all`]: crate::engine::fixed::stability::PlateLimit::radius_all

pub mod fit;
pub mod report;

use std::fmt::Write as _;
use std::time::Instant;

use super::execute::{Continuation, Interrupted, run_missing};
use super::seeds::{self, Role};
use super::stats::{ReplicaStats, t_quantile};
use crate::engine::EngineError;
use crate::observe::regime::Regime;
use crate::output::Summary;
use crate::runner::{RunError, RunOptions, run_scene_with};
use crate::scene::error::compact;
use crate::scene::{BondKind, EngineKind, RngKind, Scene};

/// An observable compared between the engines.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Observable {
    FrictionMean,
    FrictionStd,
    AttachedFraction,
    RuptureForce,
}

impl Observable {
    /// Column-name stem, as in `summary.json`.
    pub fn key(self) -> &'static str {
        match self {
            Observable::FrictionMean => "friction_mean",
            Observable::FrictionStd => "friction_std",
            Observable::AttachedFraction => "attached_fraction_mean",
            Observable::RuptureForce => "rupture_force_mean",
        }
    }
    /// Human-readable name.
    pub fn label(self) -> &'static str {
        match self {
            Observable::FrictionMean => "mean friction",
            Observable::FrictionStd => "friction std",
            Observable::AttachedFraction => "attached fraction",
            Observable::RuptureForce => "mean rupture force",
        }
    }
    fn of(self, s: &Summary) -> Option<f64> {
        match self {
            Observable::FrictionMean => Some(s.friction_mean),
            Observable::FrictionStd => Some(s.friction_std),
            Observable::AttachedFraction => Some(s.attached_fraction_mean),
            Observable::RuptureForce => s.rupture_force_mean,
        }
    }
    /// The observables of a scene: the rupture force for weak bonds only.
    pub fn for_scene(scene: &Scene) -> Vec<Observable> {
        let mut v = vec![Observable::FrictionMean, Observable::FrictionStd, Observable::AttachedFraction];
        if scene.junctions.bond == BondKind::Weak {
            v.push(Observable::RuptureForce);
        }
        v
    }
}

/// The default ladder: the scene's `fixed.dt` and its halvings down to `dt / 256`.
pub fn default_dts(scene: &Scene) -> Vec<f64> {
    (0..=8).map(|k| scene.fixed.dt / f64::from(1u32 << k)).collect()
}

/// Most replicas of a point (`--replicas`); the reference may have four times as many
/// (every job holds its scene, so a plan's memory grows with them).
pub const REPLICAS_MAX: usize = 10_000;

/// Replica counts of the exact engine's points: `1, 2, 4, ..` up to `replicas` (which is
/// always the last).
pub fn exact_counts(replicas: usize) -> Vec<usize> {
    let mut v: Vec<usize> =
        std::iter::successors(Some(1usize), |r| Some(r * 2)).take_while(|&r| r < replicas).collect();
    v.push(replicas);
    v
}

/// Bad study parameters: the message names the argument, the value and what is allowed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct PlanError(pub String);

/// Why a study failed after it started.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error("{what} (seed {seed}): {source}")]
    Run {
        what: String,
        seed: u64,
        #[source]
        source: RunError,
    },
    #[error("cannot build a thread pool: {0}")]
    Threads(String),
    #[error(transparent)]
    Interrupted(#[from] Interrupted),
}

/// Consecutive jobs run one after the other ([`Plan::run_from`]).
const RUN_LENGTH: usize = 16;

/// One simulation of a study.
#[derive(Clone, Debug)]
struct Job {
    role: Role,
    point: usize,
    scene: Scene,
}

/// A checked study, ready to run.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The scene as given (engine and step as in the file).
    pub scene: Scene,
    pub dts: Vec<f64>,
    pub replicas: usize,
    pub ref_replicas: usize,
    /// `exact.rtol` of the exact points when it differs from the scene's (`--exact-rtol`);
    /// the reference always runs at the scene's.
    pub exact_rtol: Option<f64>,
    pub exact_counts: Vec<usize>,
    pub observables: Vec<Observable>,
    /// Per step of `dts`: the plate update's growth factor per step with every junction
    /// attached ([`crate::engine::fixed::stability::PlateLimit::radius_all`] of the fixed-step scene).
    pub plate_growth: Vec<f64>,
    jobs: Vec<Job>,
}

fn quiet(scene: &Scene, extra: &[String]) -> Result<Scene, crate::scene::SceneError> {
    let mut o =
        vec!["output.trace=false".to_string(), "output.events=false".to_string(), "output.plot=false".to_string()];
    o.extend_from_slice(extra);
    scene.with_overrides(&o)
}

impl Plan {
    /// Checks the parameters and builds every job (scene and seed). Nothing runs.
    /// `exact_rtol`: the exact points' `exact.rtol` (`None`: the scene's); the reference
    /// keeps the scene's, so the points' errors include what a looser tolerance costs.
    pub fn new(
        scene: &Scene,
        dts: Vec<f64>,
        replicas: usize,
        ref_replicas: usize,
        exact_rtol: Option<f64>,
    ) -> Result<Plan, PlanError> {
        if dts.is_empty() {
            return Err(PlanError(
                "--dts: the list is empty; give one or more steps > 0, e.g. --dts 1,0.5,0.25".into(),
            ));
        }
        for &dt in &dts {
            if !(dt.is_finite() && dt > 0.0) {
                let dt = compact(dt);
                return Err(PlanError(format!("--dts: {dt} is not allowed: each step must be a finite number > 0")));
            }
        }
        if !(2..=REPLICAS_MAX).contains(&replicas) {
            return Err(PlanError(format!("--replicas = {replicas}: must be from 2 to {REPLICAS_MAX}")));
        }
        if !(2..=4 * REPLICAS_MAX).contains(&ref_replicas) {
            return Err(PlanError(format!("--ref-replicas = {ref_replicas}: must be from 2 to {}", 4 * REPLICAS_MAX)));
        }
        let base = scene.run.seed;
        let mut jobs = Vec::new();
        let exact = quiet(scene, &["run.engine=exact".into()]).map_err(|e| PlanError(e.to_string()))?;
        let exact_rtol = exact_rtol.filter(|&r| r.to_bits() != scene.exact.rtol.to_bits());
        let exact_points = match exact_rtol {
            None => exact.clone(),
            Some(r) => {
                let set = format!("exact.rtol={}", ryu::Buffer::new().format(r));
                quiet(scene, &["run.engine=exact".into(), set]).map_err(|e| PlanError(format!("--exact-rtol: {e}")))?
            }
        };
        let with_seed = |s: &Scene, seed: u64| {
            let mut s = s.clone();
            s.run.seed = seed;
            s
        };
        for r in 0..ref_replicas {
            let seed = seeds::pcg_seed(base, Role::Reference, 0, r as u64);
            jobs.push(Job { role: Role::Reference, point: 0, scene: with_seed(&exact, seed) });
        }
        let counts = exact_counts(replicas);
        let mut plate_growth = Vec::with_capacity(dts.len());
        for (k, &count) in counts.iter().enumerate() {
            for r in 0..count {
                let seed = seeds::pcg_seed(base, Role::Exact, k as u64, r as u64);
                jobs.push(Job { role: Role::Exact, point: k, scene: with_seed(&exact_points, seed) });
            }
        }
        for (j, &dt) in dts.iter().enumerate() {
            // The seed is replaced below; 1 is valid for every generator.
            let set_dt = format!("fixed.dt={}", ryu::Buffer::new().format(dt));
            let fixed = quiet(scene, &["run.engine=fixed".into(), "run.seed=1".into(), set_dt])
                .map_err(|e| PlanError(format!("--dts: {}: {e}", compact(dt))))?;
            plate_growth.push(crate::engine::fixed::stability::analyse(&fixed).selected().radius_all);
            let seeds: Vec<u64> = match fixed.fixed.rng {
                RngKind::Pcg => (0..replicas).map(|r| seeds::pcg_seed(base, Role::Fixed, j as u64, r as u64)).collect(),
                RngKind::ParkMiller => {
                    let draws = seeds::replica_draws(&fixed);
                    seeds::park_miller_seeds(base, j as u64, replicas, draws).ok_or_else(|| {
                        PlanError(format!(
                            "--replicas = {replicas}: at --dts {dt} the replicas need {replicas} x {draws} Park-Miller \
                             draws, more than the generator's period {}; use fewer replicas, a larger step or \
                             --set fixed.rng=pcg",
                            seeds::PARK_MILLER_PERIOD
                        ))
                    })?
                }
            };
            for seed in seeds {
                jobs.push(Job { role: Role::Fixed, point: j, scene: with_seed(&fixed, seed) });
            }
        }
        Ok(Plan {
            scene: scene.clone(),
            dts,
            replicas,
            ref_replicas,
            exact_rtol,
            exact_counts: counts,
            observables: Observable::for_scene(scene),
            plate_growth,
            jobs,
        })
    }

    /// Runs every job (on `threads` threads, or rayon's default) and aggregates.
    pub fn run(&self, threads: Option<usize>) -> Result<Study, StudyError> {
        self.run_from(threads, Continuation::fresh(self.jobs.len()))
    }

    /// The seed of every job, in job order (the order of the journal's run indices).
    pub fn seeds(&self) -> Vec<u64> {
        self.jobs.iter().map(|j| j.scene.run.seed).collect()
    }

    /// The study's arguments besides its scene, as one line in the command's syntax (the
    /// journal's record of what decides the runs and the files).
    pub fn arguments(&self) -> String {
        let dts: Vec<String> = self.dts.iter().map(|&d| ryu::Buffer::new().format(d).to_string()).collect();
        let mut a =
            format!("--dts {} --replicas {} --ref-replicas {}", dts.join(","), self.replicas, self.ref_replicas);
        if let Some(r) = self.exact_rtol {
            let _ = write!(a, " --exact-rtol {}", ryu::Buffer::new().format(r));
        }
        a
    }

    /// As [`Plan::run`], running only the jobs not done in `from`, appending each finished
    /// job to `from.journal`, and stopping when `from.stop` is set
    /// ([`StudyError::Interrupted`]).
    pub fn run_from(&self, threads: Option<usize>, from: Continuation<'_, JobRecord>) -> Result<Study, StudyError> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.unwrap_or(0))
            .build()
            .map_err(|e| StudyError::Threads(e.to_string()))?;
        let obs = &self.observables;
        // Jobs run in runs of `RUN_LENGTH` consecutive jobs (replicas of one point, mostly),
        // the runs in a fixed pseudo-random order: a change of machine load during the study
        // (other processes) spreads over all points instead of hitting one, and a replica
        // follows replicas of its own engine, as in any campaign of replicas, instead of
        // starting on caches and branch history that the other engine left behind (module
        // doc). The outcomes are put back in job order.
        let mut order: Vec<usize> = (0..self.jobs.len()).collect();
        order.sort_by_key(|&i| (seeds::mix((i / RUN_LENGTH) as u64), i));
        let outcomes = run_missing(&pool, &order, &self.seeds(), from, None, |i, opts| run_job(&self.jobs[i], opts))?;
        // The first failure in job order, so the message does not depend on scheduling.
        let mut results = Vec::with_capacity(outcomes.len());
        for (job, o) in self.jobs.iter().zip(outcomes) {
            match o {
                Err(source) => {
                    let what = match job.role {
                        Role::Reference => "the exact reference run failed".to_string(),
                        Role::Exact => "an exact run failed".to_string(),
                        Role::Fixed => format!("a fixed-step run at dt = {} failed", job.scene.fixed.dt),
                    };
                    return Err(StudyError::Run { what, seed: job.scene.run.seed, source });
                }
                Ok(record) => results.push((job, record.outcome(obs))),
            }
        }
        Ok(self.aggregate(&results, pool.current_num_threads()))
    }

    fn aggregate(&self, results: &[(&Job, Outcome)], threads: usize) -> Study {
        let pick = |role: Role, point: usize| -> Vec<&Outcome> {
            results.iter().filter(|(j, _)| j.role == role && j.point == point).map(|(_, o)| o).collect()
        };
        let nobs = self.observables.len();
        // Reference.
        let refs = pick(Role::Reference, 0);
        let ref_wall: f64 = refs.iter().map(|o| o.wall()).sum();
        let ref_cpu: f64 = refs.iter().map(|o| o.cpu()).sum();
        let ref_stats: Vec<ReplicaStats> =
            (0..nobs).map(|i| ReplicaStats::of(refs.iter().map(|o| o.value(i)))).collect();
        let reference = Reference {
            replicas: self.ref_replicas,
            wall_seconds: ref_wall,
            cpu_seconds: ref_cpu,
            stats: ref_stats.clone(),
        };
        let mut points = Vec::new();
        for (k, &count) in self.exact_counts.iter().enumerate() {
            let outs = pick(Role::Exact, k);
            let wall = outs.iter().map(|o| o.wall()).sum();
            let cpu = outs.iter().map(|o| o.cpu()).sum();
            let obs = (0..nobs)
                .map(|i| {
                    let s = ReplicaStats::of(outs.iter().map(|o| o.value(i)));
                    let r = &ref_stats[i];
                    let se = r.sd / (count as f64).sqrt();
                    PointObs::new(s.mean, se, r, r.n.saturating_sub(1) as f64)
                })
                .collect();
            points.push(Point {
                engine: EngineKind::Exact,
                dt: None,
                replicas: count,
                wall_seconds: wall,
                cpu_seconds: cpu,
                status: Status::Ok,
                diverged_replicas: 0,
                plate_growth: None,
                obs,
            });
        }
        for (j, &dt) in self.dts.iter().enumerate() {
            let outs = pick(Role::Fixed, j);
            let wall = outs.iter().map(|o| o.wall()).sum();
            let cpu = outs.iter().map(|o| o.cpu()).sum();
            let diverged = outs.iter().filter(|o| matches!(o, Outcome::Diverged { .. })).count();
            let growth = self.plate_growth[j];
            let status = if diverged > 0 {
                Status::Diverged
            } else if outs.iter().any(|o| matches!(o, Outcome::Done { unstable: true, .. })) {
                Status::Unstable
            } else {
                Status::Ok
            };
            let obs = (0..nobs)
                .map(|i| {
                    if diverged > 0 {
                        return PointObs::none();
                    }
                    let s = ReplicaStats::of(outs.iter().map(|o| o.value(i)));
                    let r = &ref_stats[i];
                    let (a, b) = (s.se * s.se, r.se * r.se);
                    let df = (a + b) * (a + b) / (a * a / (s.n as f64 - 1.0) + b * b / (r.n as f64 - 1.0));
                    PointObs::new(s.mean, s.se, r, df)
                })
                .collect();
            points.push(Point {
                engine: EngineKind::Fixed,
                dt: Some(dt),
                replicas: self.replicas,
                wall_seconds: wall,
                cpu_seconds: cpu,
                status,
                diverged_replicas: diverged,
                plate_growth: Some(growth),
                obs,
            });
        }
        Study {
            scene: self.scene.clone(),
            observables: self.observables.clone(),
            replicas: self.replicas,
            exact_rtol: self.exact_rtol,
            reference,
            points,
            threads,
        }
    }
}

/// What one job gave, as its study's journal records it: a finished run's summary, or a
/// fixed-step run that diverged; with the wall and CPU seconds it took.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum JobRecord {
    Done { summary: Box<Summary>, wall: f64, cpu: f64 },
    Diverged { wall: f64, cpu: f64 },
}

impl JobRecord {
    fn outcome(&self, obs: &[Observable]) -> Outcome {
        match self {
            JobRecord::Done { summary, wall, cpu } => Outcome::Done {
                values: obs.iter().map(|o| o.of(summary)).collect(),
                unstable: summary.regime == Regime::Unstable,
                wall: *wall,
                cpu: *cpu,
            },
            JobRecord::Diverged { wall, cpu } => Outcome::Diverged { wall: *wall, cpu: *cpu },
        }
    }
}

/// What one job gave, for the aggregation.
#[derive(Debug)]
enum Outcome {
    /// `unstable`: the run's regime is `unstable`.
    Done {
        values: Vec<Option<f64>>,
        unstable: bool,
        wall: f64,
        cpu: f64,
    },
    Diverged {
        wall: f64,
        cpu: f64,
    },
}

impl Outcome {
    fn wall(&self) -> f64 {
        match self {
            Outcome::Done { wall, .. } | Outcome::Diverged { wall, .. } => *wall,
        }
    }
    fn cpu(&self) -> f64 {
        match self {
            Outcome::Done { cpu, .. } | Outcome::Diverged { cpu, .. } => *cpu,
        }
    }
    fn value(&self, i: usize) -> Option<f64> {
        match self {
            Outcome::Done { values, .. } => values[i],
            Outcome::Diverged { .. } => None,
        }
    }
}

/// CPU time consumed by the calling thread, in seconds (0 where the clock is unavailable).
pub fn thread_cpu_seconds() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `ts` is a valid, writable timespec; the call only writes into it.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    if rc == 0 { ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9 } else { 0.0 }
}

fn run_job(job: &Job, opts: &RunOptions) -> Result<JobRecord, RunError> {
    let cpu0 = thread_cpu_seconds();
    let started = Instant::now();
    let r = run_scene_with(&job.scene, None, opts);
    let wall = started.elapsed().as_secs_f64();
    let cpu = thread_cpu_seconds() - cpu0;
    match r {
        Ok(s) => Ok(JobRecord::Done { summary: Box::new(s), wall, cpu }),
        Err(RunError::Engine(EngineError::Diverged { .. } | EngineError::NonFinite { .. }))
            if job.role == Role::Fixed =>
        {
            Ok(JobRecord::Diverged { wall, cpu })
        }
        Err(e) => Err(e),
    }
}

/// The reference: the exact engine over many replicas.
#[derive(Clone, Debug)]
pub struct Reference {
    pub replicas: usize,
    pub wall_seconds: f64,
    pub cpu_seconds: f64,
    /// One per observable.
    pub stats: Vec<ReplicaStats>,
}

/// How a point ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    Ok,
    /// Completed, but a replica's run is `unstable` (its plate step failed).
    Unstable,
    /// At least one replica diverged; no estimate.
    Diverged,
}

impl Status {
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Unstable => "unstable",
            Status::Diverged => "diverged",
        }
    }
}

/// One observable at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointObs {
    pub estimate: f64,
    pub se: f64,
    /// `estimate - reference`.
    pub error: f64,
    pub ci_low: f64,
    pub ci_high: f64,
    /// Standard deviation of the error from sampling alone: `sqrt(se^2 + se_ref^2)`.
    pub floor: f64,
}

impl PointObs {
    fn none() -> PointObs {
        PointObs {
            estimate: f64::NAN,
            se: f64::NAN,
            error: f64::NAN,
            ci_low: f64::NAN,
            ci_high: f64::NAN,
            floor: f64::NAN,
        }
    }
    fn new(estimate: f64, se: f64, reference: &ReplicaStats, df: f64) -> PointObs {
        let error = estimate - reference.mean;
        let floor = (se * se + reference.se * reference.se).sqrt();
        let half = t_quantile(df) * floor;
        PointObs { estimate, se, error, ci_low: error - half, ci_high: error + half, floor }
    }
}

/// One point of the diagram.
#[derive(Clone, Debug)]
pub struct Point {
    pub engine: EngineKind,
    /// The fixed engine's step.
    pub dt: Option<f64>,
    pub replicas: usize,
    /// Sum over replicas of each replica's measured wall time.
    pub wall_seconds: f64,
    /// Sum over replicas of the CPU time of the thread that ran each replica (less
    /// sensitive than the wall time to other processes on a shared machine).
    pub cpu_seconds: f64,
    pub status: Status,
    pub diverged_replicas: usize,
    /// Fixed engine: growth factor per step of the plate update, all junctions attached.
    pub plate_growth: Option<f64>,
    /// One per observable.
    pub obs: Vec<PointObs>,
}

/// A finished study.
#[derive(Clone, Debug)]
pub struct Study {
    pub scene: Scene,
    pub observables: Vec<Observable>,
    /// Replicas per fixed point (and of the largest exact point).
    pub replicas: usize,
    /// The exact points' `exact.rtol` when it differs from the scene's (the reference's).
    pub exact_rtol: Option<f64>,
    pub reference: Reference,
    pub points: Vec<Point>,
    /// Replicas run at a time (the thread pool's size).
    pub threads: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ladders() {
        assert_eq!(exact_counts(64), vec![1, 2, 4, 8, 16, 32, 64]);
        assert_eq!(exact_counts(5), vec![1, 2, 4, 5]);
        assert_eq!(exact_counts(2), vec![1, 2]);
        let s = crate::test_scenes::fig1();
        let d = default_dts(&s);
        assert_eq!(d.len(), 9);
        assert_eq!(d[0], 1.0);
        assert_eq!(d[8], 1.0 / 256.0);
    }

    #[test]
    fn bad_plans_name_their_argument() {
        let s = crate::test_scenes::fig1();
        for dts in [vec![], vec![-1.0], vec![0.0], vec![f64::NAN], vec![f64::INFINITY]] {
            let e = Plan::new(&s, dts, 4, 4, None).unwrap_err();
            assert!(e.0.starts_with("--dts"), "{e}");
        }
        assert!(Plan::new(&s, vec![0.5], 1, 4, None).unwrap_err().0.starts_with("--replicas"));
        assert!(Plan::new(&s, vec![0.5], 4, 1, None).unwrap_err().0.starts_with("--ref-replicas"));
        // 1e-5 over 150 time units is 1.5e7 steps of 300 junctions: 4.5e9 draws per replica.
        assert!(Plan::new(&s, vec![1e-5], 4, 4, None).unwrap_err().0.starts_with("--replicas"));
    }

    /// `--exact-rtol` reaches the exact points only: the reference keeps the scene's
    /// tolerance, the arguments (the journal's record) name it, a value equal to the
    /// scene's is no change, and a bad one names the flag and the field.
    #[test]
    fn exact_rtol_sets_the_exact_points_only() {
        let s = crate::test_scenes::fig1();
        let p = Plan::new(&s, vec![0.5], 2, 3, Some(1e-6)).unwrap();
        let rtol =
            |role: Role| -> Vec<f64> { p.jobs.iter().filter(|j| j.role == role).map(|j| j.scene.exact.rtol).collect() };
        assert!(rtol(Role::Reference).iter().all(|&r| r == s.exact.rtol), "{:?}", rtol(Role::Reference));
        assert_eq!(rtol(Role::Exact), vec![1e-6; 3]);
        assert!(rtol(Role::Fixed).iter().all(|&r| r == s.exact.rtol));
        assert!(p.arguments().ends_with(" --exact-rtol 1e-6"), "{}", p.arguments());
        let same = Plan::new(&s, vec![0.5], 2, 3, Some(s.exact.rtol)).unwrap();
        assert_eq!(same.exact_rtol, None);
        assert_eq!(same.arguments(), Plan::new(&s, vec![0.5], 2, 3, None).unwrap().arguments());
        for bad in [0.0, -1e-6, f64::NAN, 2.0] {
            let e = Plan::new(&s, vec![0.5], 2, 3, Some(bad)).unwrap_err().0;
            assert!(e.starts_with("--exact-rtol: ") && e.contains("exact.rtol"), "{bad}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn fig1_plate_growth_is_that_of_the_stability_analysis() {
        // Fig. 1, every junction attached: w2 = (150 + 30)/75 = 2.4, c = 1; at dt = 1 the
        // semi-implicit Euler matrix is [[-1.4, 0], [-2.4, 0]], radius 1.4; at dt = 0.5,
        // a complex pair of modulus sqrt(det) = sqrt(1 - 0.5).
        let p = Plan::new(&crate::test_scenes::fig1(), vec![1.0, 0.5], 2, 2, None).unwrap();
        assert!((p.plate_growth[0] - 1.4).abs() < 1e-12);
        assert!((p.plate_growth[1] - 0.5f64.sqrt()).abs() < 1e-12);
    }
}
