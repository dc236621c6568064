//! Parameter sweeps (`stickslip sweep`): one scene field, or two for a map, each over a list
//! of values; every grid point is run `replicas` times with seeds derived from the scene's
//! seed, the grid point index and the replica ([`crate::studies::seeds`]); the runs are
//! aggregated per grid point (means with 95 % Student-t half-widths across replicas, the
//! majority regime, the oscillation's amplitude and period, totals).
//!
//! # Library API
//!
//! The CLI goes through exactly these functions, so a caller that runs the scenes elsewhere
//! (a Python/Dask layer, a cluster) and hands back the summaries gets byte-identical tables:
//!
//! ```no_run
//! use stickslip::studies::sweep::{Sweep, SweepAxis, SweepSpec, ValueSpec, parse_values};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let base = stickslip::Scene::from_file("scenarios/fig2.toml".as_ref(), &[])?;
//! // 1. Describe and prepare: every grid point's scene is validated, every seed derived;
//! //    nothing runs.
//! let v = SweepAxis { param: "plate.v".into(), values: parse_values(ValueSpec::LogRange("0.1:10:9"))?, log: true };
//! let t = SweepAxis { param: "junctions.temperature".into(), values: parse_values(ValueSpec::List("0.5,1,2"))?, log: false };
//! let sweep = Sweep::prepare(base, SweepSpec { axes: vec![v, t], replicas: 2, set: vec![] })?;
//! // 2. The runs, in order: (grid point index, replica, scene with its derived seed).
//! let summaries: Vec<stickslip::output::Summary> = sweep
//!     .runs()
//!     .map(|run| stickslip::run_scene(run.scene, None)) // or anywhere else; JSON travels
//!     .collect::<Result<_, _>>()?;
//! // 3. The outcome from all summaries, in the order of `runs()` (checked by seed).
//! let outcome = sweep.outcome(summaries)?;
//! // 4. The tables (and `write` for the files, sweep.svg included).
//! let (table, runs, record) = (outcome.sweep_csv(&sweep), outcome.runs_csv(&sweep), outcome.sweep_json(&sweep));
//! outcome.write(&sweep, "out/map".as_ref())?;
//! # Ok(()) }
//! ```
//!
//! - [`Sweep::prepare`]`(base, spec)`: `base` is the scene with the `--set` overrides applied;
//!   `spec` lists one or two [`SweepAxis`] (field `section.key`, values, log scale for the
//!   figure), the replicas per grid point and the overrides (for the record). Errors are
//!   one line ([`SpecError`]).
//! - [`Sweep::runs`]: every run as a [`RunSpec`] `{ point, replica, scene }`, grid point by
//!   grid point (row-major: the first field varies slowest), replicas in order.
//!   [`Sweep::points`] holds the same scenes per grid point.
//! - [`Sweep::outcome`]`(summaries)`: the [`SweepOutcome`] from the runs' summaries in that
//!   order (`output::Summary` is Serialize + Deserialize: summaries can travel as JSON). A
//!   summary whose seed is not its run's is refused ([`OutcomeError`]).
//! - [`SweepOutcome::sweep_csv`], [`SweepOutcome::runs_csv`], [`SweepOutcome::sweep_json`]
//!   (wall times only if [`SweepOutcome::timing`] is set), [`SweepOutcome::write`]
//!   (`sweep.csv`, `runs.csv`, `sweep.svg`, `sweep.json`, each atomically).
//! - [`Sweep::run`]: runs every scene here, on a rayon pool, then calls `outcome`.
//!
//! Every run is independent and seeded by its grid point and replica, so the tables are
//! byte-identical whatever runs them and on however many threads; wall-clock times, which
//! are not reproducible, are only in `sweep.json`.
//!
//! Files: [`plan`] (spec, preparation, runs), [`values`] (value lists from the command line),
//! [`outcome`] (aggregation), [`tables`] (the text of the files; [`crate::plot::files`] writes
//! them with the figure of [`crate::plot::sweep`]).

pub mod outcome;
pub mod plan;
pub mod tables;
pub mod values;

use std::time::Instant;

use indicatif::ProgressBar;

pub use outcome::{Majority, OutcomeError, Row, SweepOutcome, Timing};
pub use plan::{GridPoint, MAX_AXES, MAX_RUNS, RunSpec, SpecError, Sweep, SweepAxis, SweepSpec};
pub use tables::{RUNS_COLUMNS, SWEEP_COLUMNS};
pub use values::{MAX_VALUES, RangeProblem, SweepValue, ValueSpec, ValuesError, parse_values, round_sig, value_text};

use super::execute::{Continuation, Interrupted, run_missing};
use crate::output::Summary;
use crate::runner::{RunError, run_scene_with};

/// Why a sweep failed while running.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("cannot start the thread pool: {0}")]
    Pool(String),
    #[error("the run for {point}, replica {replica} (seed {seed}) failed: {source}")]
    Run {
        /// `P = V` for each swept field.
        point: String,
        replica: usize,
        seed: u64,
        #[source]
        source: RunError,
    },
    #[error(transparent)]
    Outcome(#[from] OutcomeError),
    #[error(transparent)]
    Interrupted(#[from] Interrupted),
}

impl Sweep {
    /// Runs every scene of [`Sweep::runs`] on a pool of `threads` threads (`0`: all cores)
    /// and builds the outcome with [`Sweep::outcome`]; `progress` is advanced by one per
    /// finished run. The first failed run, in the order of `runs`, is the error.
    pub fn run(&self, threads: usize, progress: Option<&ProgressBar>) -> Result<SweepOutcome, SweepError> {
        self.run_from(threads, progress, Continuation::fresh(self.len()))
    }

    /// As [`Sweep::run`], running only the runs not done in `from` (their summaries are
    /// taken as they are), appending each finished run to `from.journal`, and stopping
    /// when `from.stop` is set ([`SweepError::Interrupted`]).
    pub fn run_from(
        &self,
        threads: usize,
        progress: Option<&ProgressBar>,
        from: Continuation<'_, Summary>,
    ) -> Result<SweepOutcome, SweepError> {
        let started = Instant::now();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| SweepError::Pool(e.to_string()))?;
        let runs: Vec<RunSpec<'_>> = self.runs().collect();
        let seeds: Vec<u64> = runs.iter().map(|r| r.scene.run.seed).collect();
        let order: Vec<usize> = (0..runs.len()).collect();
        let results =
            run_missing(&pool, &order, &seeds, from, progress, |i, opts| run_scene_with(runs[i].scene, None, opts))?;
        let mut summaries = Vec::with_capacity(results.len());
        for (run, res) in runs.iter().zip(results) {
            summaries.push(res.map_err(|source| SweepError::Run {
                point: self.describe(run.point),
                replica: run.replica,
                seed: run.scene.run.seed,
                source,
            })?);
        }
        let mut outcome = self.outcome(summaries)?;
        outcome.timing =
            Some(Timing { wall_seconds: started.elapsed().as_secs_f64(), threads: pool.current_num_threads() });
        Ok(outcome)
    }

    /// The seed of every run, in the order of [`Sweep::runs`].
    pub fn seeds(&self) -> Vec<u64> {
        self.runs().map(|r| r.scene.run.seed).collect()
    }

    /// The sweep's arguments besides its scene, as one line in the command's syntax (the
    /// journal's record of what decides the runs and the tables). The `--set` overrides
    /// are not among them: their effect is in the scene's fingerprint, however spelt.
    pub fn arguments(&self) -> String {
        let mut parts = Vec::new();
        for (k, a) in self.axes.iter().enumerate() {
            let values = a.values.iter().map(|v| v.text.as_str()).collect::<Vec<_>>().join(",");
            parts.push(format!("--param {} --values {values}", a.param));
            if a.log {
                parts.push(if k == 0 { "--log-x" } else { "--log-y" }.to_string());
            }
        }
        parts.push(format!("--replicas {}", self.replicas));
        crate::scene::error::printable(&parts.join(" "))
    }

    /// Grid point `g` as `P = V` for each swept field, e.g. `plate.v = 0.5, plate.k = 15`.
    pub fn describe(&self, g: usize) -> String {
        self.axes
            .iter()
            .zip(&self.points[g].values)
            .map(|(a, v)| format!("{} = {}", a.param, v.text))
            .collect::<Vec<_>>()
            .join(", ")
    }
}
