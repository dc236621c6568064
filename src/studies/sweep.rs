//! Parameter sweeps: one scene field (`section.key`) takes a list of values; each value is
//! run `replicas` times with seeds derived from the scene's seed ([`super::seeds`]); the
//! runs execute in parallel (rayon) and are aggregated per value: means with 95% Student-t
//! confidence half-widths across replicas, the majority regime, totals.
//!
//! Every run is independent and seeded by its value index and replica, and the results are
//! gathered in index order, so the tables (`sweep.csv`, `runs.csv`) are byte-identical
//! whatever the number of threads. Wall-clock times, which are not reproducible, go to
//! `sweep.json` only.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use indicatif::ProgressBar;
use rayon::prelude::*;
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, StudentsT};

use super::seeds::{self, SeedRange};
use crate::observe::regime::Regime;
use crate::output::Summary;
use crate::output::atomic::write_whole;
use crate::output::csv::push_f64;
use crate::runner::{RunError, run_scene};
use crate::scene::{EngineKind, RngKind, Scene};

/// Most values a sweep may have.
pub const MAX_VALUES: usize = 10_000;
/// Most runs (values x replicas) a sweep may have.
pub const MAX_RUNS: usize = 1_000_000;

/// One value of the swept field: the text given to the scene and its number.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepValue {
    pub text: String,
    pub x: f64,
}

/// How the values were given on the command line.
#[derive(Clone, Copy, Debug)]
pub enum ValueSpec<'a> {
    /// `--values a,b,c`.
    List(&'a str),
    /// `--range lo:hi:count`, evenly spaced.
    Range(&'a str),
    /// `--log-range lo:hi:count`, evenly spaced in `log`.
    LogRange(&'a str),
}

/// A number as a scene value: a whole number without a fraction (so that integer fields
/// such as `junctions.n` accept it), anything else in the shortest round-trip form.
pub fn value_text(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        let mut s = String::new();
        push_f64(&mut s, x);
        s
    }
}

/// `x` rounded to 6 significant digits (the inner points of a range, so that the values
/// read well; the end points are kept exactly as given).
pub fn round_sig(x: f64) -> f64 {
    format!("{x:.5e}").parse().expect("a formatted float parses")
}

/// Parses the values. The error is one line naming the argument, the value and what is
/// allowed.
pub fn parse_values(spec: ValueSpec<'_>) -> Result<Vec<SweepValue>, String> {
    let printable = crate::scene::error::printable;
    match spec {
        ValueSpec::List(s) => {
            let mut out = Vec::new();
            for part in s.split(',') {
                let text = part.trim();
                let x = text.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                    format!(
                        "--values {}: '{}' is not a finite number (expected numbers separated by commas, e.g. 0.1,0.5,2)",
                        printable(s),
                        printable(text)
                    )
                })?;
                out.push(SweepValue { text: text.to_string(), x });
            }
            if out.len() > MAX_VALUES {
                return Err(format!("--values: {} values given, at most {MAX_VALUES} allowed", out.len()));
            }
            Ok(out)
        }
        ValueSpec::Range(s) | ValueSpec::LogRange(s) => {
            let log = matches!(spec, ValueSpec::LogRange(_));
            let arg = if log { "--log-range" } else { "--range" };
            let form = if log {
                "expected LO:HI:COUNT with 0 < LO < HI and COUNT from 2 to 10000, e.g. 0.1:10:9"
            } else {
                "expected LO:HI:COUNT with LO < HI and COUNT from 2 to 10000, e.g. 0:2:5"
            };
            let bad = |why: &str| format!("{arg} {}: {why} ({form})", printable(s));
            let parts: Vec<&str> = s.split(':').map(str::trim).collect();
            if parts.len() != 3 {
                return Err(bad("not three fields separated by ':'"));
            }
            let num = |t: &str, name: &str| {
                t.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| bad(&format!("{name} '{}' is not a finite number", printable(t))))
            };
            let (lo, hi) = (num(parts[0], "LO")?, num(parts[1], "HI")?);
            let count: usize = parts[2].parse().ok().filter(|c| (2..=MAX_VALUES).contains(c)).ok_or_else(|| {
                bad(&format!("COUNT '{}' is not a whole number from 2 to {MAX_VALUES}", printable(parts[2])))
            })?;
            if log && lo <= 0.0 {
                return Err(bad(&format!("LO = {lo} is not > 0")));
            }
            if lo >= hi {
                return Err(bad(&format!("LO = {lo} is not less than HI = {hi}")));
            }
            let xs: Vec<f64> = (0..count)
                .map(|k| {
                    let f = k as f64 / (count - 1) as f64;
                    match k {
                        0 => lo,
                        k if k == count - 1 => hi,
                        _ if log => round_sig((lo.ln() + f * (hi.ln() - lo.ln())).exp()),
                        _ => round_sig(lo + f * (hi - lo)),
                    }
                })
                .collect();
            Ok(xs.into_iter().map(|x| SweepValue { text: value_text(x), x }).collect())
        }
    }
}

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
    #[error("cannot write {path}: {source}")]
    Write {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
}

/// Mean of `x` and the half-width of its two-sided 95% Student-t confidence interval
/// (`NaN` for a single value; `sweep.csv` leaves that field empty).
pub fn mean_ci95(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    if x.len() < 2 {
        return (m, f64::NAN);
    }
    let var = x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (n - 1.0);
    let t = StudentsT::new(0.0, 1.0, n - 1.0).expect("n >= 2").inverse_cdf(0.975);
    (m, t * (var / n).sqrt())
}

/// The regime of a value across its replicas.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Majority {
    /// Fewer than half of the replicas are stick-slip.
    Smooth,
    /// More than half are.
    StickSlip,
    /// Exactly half are.
    Mixed,
}

impl Majority {
    pub fn as_str(self) -> &'static str {
        match self {
            Majority::Smooth => "smooth",
            Majority::StickSlip => "stick-slip",
            Majority::Mixed => "mixed",
        }
    }
}

/// The aggregate of one value's replicas.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub value: SweepValue,
    pub replicas: usize,
    /// `(mean, 95% CI half-width)` across replicas.
    pub friction_mean: (f64, f64),
    pub friction_per_junction: (f64, f64),
    pub friction_std: (f64, f64),
    pub attached_fraction_mean: (f64, f64),
    pub regime: Majority,
    pub stick_slip_fraction: f64,
    /// Exact-engine events summed over the replicas.
    pub events: u64,
    /// Fixed-engine steps summed over the replicas.
    pub steps: u64,
    /// Wall-clock seconds summed over the replicas' runs.
    pub wall_seconds: f64,
}

impl Row {
    pub fn from_runs(value: &SweepValue, runs: &[Summary]) -> Row {
        let col = |f: fn(&Summary) -> f64| mean_ci95(&runs.iter().map(f).collect::<Vec<_>>());
        let ss = runs.iter().filter(|s| s.regime == Regime::StickSlip).count();
        let regime = match (2 * ss).cmp(&runs.len()) {
            std::cmp::Ordering::Less => Majority::Smooth,
            std::cmp::Ordering::Greater => Majority::StickSlip,
            std::cmp::Ordering::Equal => Majority::Mixed,
        };
        Row {
            value: value.clone(),
            replicas: runs.len(),
            friction_mean: col(|s| s.friction_mean),
            friction_per_junction: col(|s| s.friction_per_junction),
            friction_std: col(|s| s.friction_std),
            attached_fraction_mean: col(|s| s.attached_fraction_mean),
            regime,
            stick_slip_fraction: ss as f64 / runs.len() as f64,
            events: runs.iter().filter_map(|s| s.counters.events).sum(),
            steps: runs.iter().filter_map(|s| s.counters.steps).sum(),
            wall_seconds: runs.iter().map(|s| s.wall_seconds).sum(),
        }
    }
}

/// What a sweep produced.
#[derive(Clone, Debug)]
pub struct SweepOutcome {
    pub rows: Vec<Row>,
    /// `summaries[i][r]`.
    pub summaries: Vec<Vec<Summary>>,
    pub wall_seconds: f64,
    pub threads: usize,
}

/// Columns of `sweep.csv` after the first (which is named by the swept field).
pub const SWEEP_COLUMNS: &str = "replicas,friction_mean,friction_mean_ci95,friction_per_junction,friction_per_junction_ci95,friction_std,friction_std_ci95,attached_fraction_mean,attached_fraction_mean_ci95,regime,stick_slip_fraction,events,steps";
/// Columns of `runs.csv` after the first.
pub const RUNS_COLUMNS: &str = "replica,seed,friction_mean,friction_per_junction,friction_std,attached_fraction_mean,regime,stick_slip_cycles,events,steps";

impl SweepOutcome {
    /// `sweep.csv`: one row per value.
    pub fn sweep_csv(&self, sweep: &Sweep) -> String {
        let mut s = format!("{},{SWEEP_COLUMNS}\n", sweep.param);
        for r in &self.rows {
            s.push_str(&value_text(r.value.x));
            let _ = write!(s, ",{}", r.replicas);
            for (m, c) in [r.friction_mean, r.friction_per_junction, r.friction_std, r.attached_fraction_mean] {
                s.push(',');
                push_f64(&mut s, m);
                s.push(',');
                // A single replica has no confidence interval: the field is left empty.
                if c.is_finite() {
                    push_f64(&mut s, c);
                }
            }
            let _ = write!(s, ",{},", r.regime.as_str());
            push_f64(&mut s, r.stick_slip_fraction);
            let _ = writeln!(s, ",{},{}", r.events, r.steps);
        }
        s
    }

    /// `runs.csv`: one row per run.
    pub fn runs_csv(&self, sweep: &Sweep) -> String {
        let mut s = format!("{},{RUNS_COLUMNS}\n", sweep.param);
        for (v, row) in sweep.values.iter().zip(&self.summaries) {
            for (r, run) in row.iter().enumerate() {
                s.push_str(&value_text(v.x));
                let _ = write!(s, ",{r},{}", run.seed);
                for x in [run.friction_mean, run.friction_per_junction, run.friction_std, run.attached_fraction_mean] {
                    s.push(',');
                    push_f64(&mut s, x);
                }
                let _ = writeln!(
                    s,
                    ",{},{},{},{}",
                    run.regime.as_str(),
                    run.stick_slip_cycles,
                    run.counters.events.unwrap_or(0),
                    run.counters.steps.unwrap_or(0)
                );
            }
        }
        s
    }

    /// `sweep.json`: what was run (scene, field, values, seeds, overrides) and how long it took.
    pub fn sweep_json(&self, sweep: &Sweep) -> String {
        #[derive(Serialize)]
        struct Record<'a> {
            scene: &'a str,
            param: &'a str,
            values: Vec<&'a str>,
            replicas: usize,
            set: &'a [String],
            seed: u64,
            seed_rule: &'static str,
            seeds: Vec<Vec<u64>>,
            threads: usize,
            wall_seconds: f64,
            run_wall_seconds: Vec<f64>,
            base_scene: &'a Scene,
        }
        let r = Record {
            scene: &sweep.base.name,
            param: &sweep.param,
            values: sweep.values.iter().map(|v| v.text.as_str()).collect(),
            replicas: sweep.replicas,
            set: &sweep.set,
            seed: sweep.base.run.seed,
            seed_rule: "seed(i, r) = mix(mix(mix(run.seed) ^ i) ^ r), mix = SplitMix64 output of x + 0x9E3779B97F4A7C15; \
                        h >> 1, or 1 + h mod (2^31 - 2) for Park-Miller; i = value index, r = replica (0-based); see src/studies/seeds.rs",
            seeds: sweep.runs.iter().map(|row| row.iter().map(|s| s.run.seed).collect()).collect(),
            threads: self.threads,
            wall_seconds: self.wall_seconds,
            run_wall_seconds: self.rows.iter().map(|r| r.wall_seconds).collect(),
            base_scene: &sweep.base,
        };
        serde_json::to_string_pretty(&r).expect("the record serializes") + "\n"
    }

    /// Writes `sweep.csv`, `runs.csv`, `sweep.svg` and `sweep.json` into `dir`, each
    /// atomically. The SVG is drawn before anything is written.
    pub fn write(&self, sweep: &Sweep, dir: &Path) -> Result<(), SweepError> {
        let svg = crate::plot::sweep::sweep_svg(sweep, self)?;
        let files = [
            ("sweep.csv", self.sweep_csv(sweep)),
            ("runs.csv", self.runs_csv(sweep)),
            ("sweep.svg", svg),
            ("sweep.json", self.sweep_json(sweep)),
        ];
        for (name, text) in files {
            write_whole(dir, name, text.as_bytes())
                .map_err(|source| SweepError::Write { path: dir.join(name).display().to_string(), source })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_hit_their_ends() {
        let v = parse_values(ValueSpec::LogRange("0.1:10:3")).unwrap();
        assert_eq!(v.iter().map(|v| v.x).collect::<Vec<_>>(), vec![0.1, 1.0, 10.0]);
        assert_eq!(v[2].text, "10");
        let v = parse_values(ValueSpec::Range("0:2:5")).unwrap();
        assert_eq!(v.iter().map(|v| v.text.as_str()).collect::<Vec<_>>(), vec!["0", "0.5", "1", "1.5", "2"]);
        let v = parse_values(ValueSpec::List("0.1, 1e-3,300")).unwrap();
        assert_eq!(v.iter().map(|v| v.text.as_str()).collect::<Vec<_>>(), vec!["0.1", "1e-3", "300"]);
    }

    #[test]
    fn bad_values_are_refused_with_the_argument_named() {
        for (spec, arg) in [
            (ValueSpec::List("0.1,,2"), "--values"),
            (ValueSpec::List("0.1,abc"), "--values"),
            (ValueSpec::List("nan"), "--values"),
            (ValueSpec::LogRange("0:1:5"), "--log-range"),
            (ValueSpec::LogRange("1:0.1:5"), "--log-range"),
            (ValueSpec::LogRange("0.1:1:1"), "--log-range"),
            (ValueSpec::LogRange("0.1:1"), "--log-range"),
            (ValueSpec::Range("1:2:x"), "--range"),
        ] {
            let e = parse_values(spec).unwrap_err();
            assert!(e.starts_with(arg), "{e}");
            assert!(!e.contains('\n'));
        }
    }

    #[test]
    fn ci_of_known_sample() {
        // t_{0.975, 3} = 3.182446305284263
        let (m, c) = mean_ci95(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(m, 2.5);
        let s = (5.0f64 / 3.0).sqrt();
        assert!((c - 3.182446305284263 * s / 2.0).abs() < 1e-12);
        assert!(mean_ci95(&[1.0]).1.is_nan());
    }
}
