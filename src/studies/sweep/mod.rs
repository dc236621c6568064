//! Parameter sweeps: one scene field (`section.key`) takes a list of values; each value is
//! run `replicas` times with seeds derived from the scene's seed ([`super::seeds`]); the
//! runs execute in parallel (rayon) and are aggregated per value: means with 95% Student-t
//! confidence half-widths across replicas, the majority regime, totals.
//!
//! Every run is independent and seeded by its value index and replica, and the results are
//! gathered in index order, so the tables (`sweep.csv`, `runs.csv`) are byte-identical
//! whatever the number of threads. Wall-clock times, which are not reproducible, go to
//! `sweep.json` only.

pub mod files;
pub mod outcome;
pub mod tables;
pub mod values;

use std::time::Instant;

use indicatif::ProgressBar;
use rayon::prelude::*;

pub use files::WriteError;
pub use outcome::{Majority, Row, SweepOutcome};
pub use tables::{RUNS_COLUMNS, SWEEP_COLUMNS};
pub use values::{MAX_VALUES, SweepValue, ValueSpec, parse_values, round_sig, value_text};

use super::seeds::{self, SeedRange};
use crate::output::Summary;
use crate::runner::{RunError, run_scene};
use crate::scene::{EngineKind, RngKind, Scene};

/// Most runs (values x replicas) a sweep may have.
pub const MAX_RUNS: usize = 1_000_000;

/// A sweep ready to run: the scenes of all runs, built and validated.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// The scene with the `--set` overrides, before the swept value.
    pub base: Scene,
    /// The swept field, `section.key`.
    pub param: String,
    pub values: Vec<SweepValue>,
    pub replicas: usize,
    /// Draw `sweep.svg` with a log x axis.
    pub log_x: bool,
    /// `runs[i][r]`: the scene of value `i`, replica `r` (its seed set).
    pub runs: Vec<Vec<Scene>>,
    /// The `--set` overrides, for the record.
    pub set: Vec<String>,
}

impl Sweep {
    /// Checks the field and every value (applied to `base` and validated like the scene
    /// file) and derives every run's seed. Nothing runs. The error is one line.
    pub fn prepare(
        base: Scene,
        param: &str,
        values: Vec<SweepValue>,
        replicas: usize,
        log_x: bool,
        set: Vec<String>,
    ) -> Result<Sweep, String> {
        let printable = crate::scene::error::printable;
        let (section, key) = param
            .split_once('.')
            .filter(|(s, k)| !s.is_empty() && !k.is_empty() && !k.contains('.') && !param.contains('='))
            .ok_or_else(|| {
                format!("--param {}: expected a scene field as SECTION.KEY, e.g. plate.v", printable(param))
            })?;
        let table = toml::Table::try_from(base.to_file()).expect("a scene always serializes");
        let fields = |t: &toml::Table| t.keys().cloned().collect::<Vec<_>>().join(", ");
        match table.get(section).and_then(|s| s.as_table()) {
            None => {
                return Err(format!(
                    "--param {}: no section [{}] in a scene (sections: {})",
                    printable(param),
                    printable(section),
                    fields(&table)
                ));
            }
            Some(t) if !t.contains_key(key) => {
                return Err(format!(
                    "--param {}: [{}] has no field '{}' (fields: {})",
                    printable(param),
                    section,
                    printable(key),
                    fields(t)
                ));
            }
            _ => {}
        }
        if param == "run.seed" {
            return Err("--param run.seed: cannot be swept: each run's seed is derived from run.seed, the value index and the replica (use --replicas, or --set run.seed=...)".to_string());
        }
        if values.is_empty() {
            return Err("--values: no values given".to_string());
        }
        if replicas == 0 || values.len().saturating_mul(replicas) > MAX_RUNS {
            return Err(format!(
                "--replicas {replicas}: must be at least 1, with values x replicas at most {MAX_RUNS} ({} values)",
                values.len()
            ));
        }
        if let Some(v) = values.iter().find(|v| log_x && v.x <= 0.0) {
            return Err(format!(
                "--log-x: value {} of {param} is not > 0 (a log axis needs positive values)",
                printable(&v.text)
            ));
        }
        let mut scenes = Vec::with_capacity(values.len());
        for v in &values {
            let s = base
                .with_overrides(&[format!("{param}={}", v.text)])
                .map_err(|e| format!("value {} for {param}: {}", printable(&v.text), e))?;
            scenes.push(s);
        }
        let range = |i: usize| {
            let s: &Scene = &scenes[i];
            if s.run.engine == EngineKind::Fixed && s.fixed.rng == RngKind::ParkMiller {
                SeedRange::ParkMiller
            } else {
                SeedRange::Full
            }
        };
        let seeds = seeds::derive_all(base.run.seed, values.len(), replicas, range);
        let runs = scenes
            .iter()
            .zip(&seeds)
            .map(|(s, row)| {
                row.iter()
                    .map(|&seed| {
                        let mut r = s.clone();
                        r.run.seed = seed;
                        r
                    })
                    .collect()
            })
            .collect();
        Ok(Sweep { base, param: param.to_string(), values, replicas, log_x, runs, set })
    }

    /// Number of runs.
    pub fn len(&self) -> usize {
        self.values.len() * self.replicas
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Runs every (value, replica) on a pool of `threads` threads (`0`: all cores).
    /// `progress` is advanced by one per finished run. The first failed run, in value
    /// and replica order, is the error.
    pub fn run(&self, threads: usize, progress: Option<&ProgressBar>) -> Result<SweepOutcome, SweepError> {
        let started = Instant::now();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| SweepError::Pool(e.to_string()))?;
        let jobs: Vec<(usize, usize)> =
            (0..self.values.len()).flat_map(|i| (0..self.replicas).map(move |r| (i, r))).collect();
        let results: Vec<Result<Summary, RunError>> = pool.install(|| {
            jobs.par_iter()
                .map(|&(i, r)| {
                    let out = run_scene(&self.runs[i][r], None);
                    if let Some(p) = progress {
                        p.inc(1);
                    }
                    out
                })
                .collect()
        });
        let mut summaries: Vec<Vec<Summary>> = Vec::with_capacity(self.values.len());
        let mut it = jobs.iter().zip(results);
        for _ in 0..self.values.len() {
            let mut row = Vec::with_capacity(self.replicas);
            for _ in 0..self.replicas {
                let (&(i, r), res) = it.next().expect("one result per job");
                row.push(res.map_err(|source| SweepError::Run {
                    value: self.values[i].text.clone(),
                    param: self.param.clone(),
                    replica: r,
                    seed: self.runs[i][r].run.seed,
                    source,
                })?);
            }
            summaries.push(row);
        }
        let rows = summaries.iter().zip(&self.values).map(|(s, v)| Row::from_runs(v, s)).collect();
        Ok(SweepOutcome {
            rows,
            summaries,
            wall_seconds: started.elapsed().as_secs_f64(),
            threads: pool.current_num_threads(),
        })
    }
}

/// Why a sweep failed.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("cannot start the thread pool: {0}")]
    Pool(String),
    #[error("the run for {param} = {value}, replica {replica} (seed {seed}) failed: {source}")]
    Run {
        param: String,
        value: String,
        replica: usize,
        seed: u64,
        #[source]
        source: RunError,
    },
}
