//! Sweeps: a prepared [`stickslip::studies::sweep::Sweep`] (its grid, every run's scene
//! with its derived seed) whose runs Python schedules anywhere (Dask), and the outcome built
//! by the library from the runs' summaries: `sweep.csv` and `runs.csv` are the bytes
//! `stickslip sweep` writes for the same scene, fields, values and replicas.

use std::path::PathBuf;
use std::sync::Arc;

use pyo3::prelude::*;
use stickslip::output::Summary;
use stickslip::output::lock::{self, DirLock};
use stickslip::studies::journal::{Header, Journal, StudyKind};
use stickslip::studies::sweep::{self as lib, SweepAxis, SweepSpec, Timing, ValueSpec};

use crate::scene::Scene;
use crate::{bad_input, failed};

/// The values a value list of `stickslip sweep` gives: `flag` is `values` (`A,B,..`),
/// `range` or `log-range` (`LO:HI:COUNT`). Returns each value's text (as a scene reads
/// it); errors are the CLI's.
#[pyfunction]
pub fn parse_values(flag: &str, text: &str) -> PyResult<Vec<String>> {
    let spec = match flag {
        "values" => ValueSpec::List(text),
        "range" => ValueSpec::Range(text),
        "log-range" => ValueSpec::LogRange(text),
        other => return Err(bad_input(format!("flag '{other}': expected values, range or log-range"))),
    };
    Ok(lib::parse_values(spec).map_err(bad_input)?.into_iter().map(|v| v.text).collect())
}

/// A prepared sweep: validated, seeded, not run.
#[pyclass(frozen, module = "stickslip._stickslip")]
pub struct Sweep(Arc<lib::Sweep>);

#[pymethods]
impl Sweep {
    /// Prepares a sweep of `base` (overrides already applied; `set` lists them for the
    /// record) over `axes`, each `(field, values, log)` with the values' texts (as
    /// `--values` takes them), `replicas` runs per grid point. Errors are the CLI's.
    #[new]
    #[pyo3(signature = (base, axes, replicas, set = Vec::new()))]
    fn new(base: &Scene, axes: Vec<(String, Vec<String>, bool)>, replicas: usize, set: Vec<String>) -> PyResult<Self> {
        let axes = axes
            .into_iter()
            .map(|(param, values, log)| {
                let values = lib::parse_values(ValueSpec::List(&values.join(","))).map_err(bad_input)?;
                Ok(SweepAxis { param, values, log })
            })
            .collect::<PyResult<Vec<_>>>()?;
        let sweep = lib::Sweep::prepare(base.0.clone(), SweepSpec { axes, replicas, set }).map_err(bad_input)?;
        Ok(Sweep(Arc::new(sweep)))
    }

    fn __len__(&self) -> usize {
        self.0.len()
    }

    /// Every run, in the order `outcome` takes their summaries: `(grid point, replica,
    /// scene with its derived seed)`.
    fn runs(&self) -> Vec<(usize, usize, Scene)> {
        self.0.runs().map(|r| (r.point, r.replica, Scene(r.scene.clone()))).collect()
    }

    /// The swept fields.
    #[getter]
    fn params(&self) -> Vec<String> {
        self.0.axes.iter().map(|a| a.param.clone()).collect()
    }

    /// Grid point `point` as `P = V` for each swept field.
    fn describe(&self, point: usize) -> PyResult<String> {
        if point >= self.0.points.len() {
            return Err(bad_input(format!("point {point}: the sweep has {} grid points", self.0.points.len())));
        }
        Ok(self.0.describe(point))
    }

    /// Opens (or starts) the journal of this sweep in the existing directory `out`
    /// (`journal.jsonl`, the one `stickslip sweep` keeps) and locks it: the runs it already
    /// holds are not run again. A journal of another sweep or scene, or a damaged one, is a
    /// `ValueError` with the CLI's message.
    fn journal(&self, py: Python<'_>, out: PathBuf) -> PyResult<SweepJournal> {
        let header = Header::new(StudyKind::Sweep, self.0.arguments(), &self.0.base, self.0.len(), None);
        let seeds = self.0.seeds();
        // The directory is held while the journal is open, as `stickslip sweep` holds it.
        let held = lock::hold(&out).map_err(bad_input)?;
        let opened = py.detach(|| Journal::open::<Summary>(&out, &header, &seeds)).map_err(bad_input)?;
        let done =
            opened.done.iter().map(|d| d.as_ref().map(|s| serde_json::to_string(s).expect("a summary serializes")));
        Ok(SweepJournal { done: done.collect(), journal: opened.journal, seeds, _held: held })
    }

    /// The outcome from every run's `summary.json` text, in the order of `runs`; with
    /// `wall_seconds` and `workers`, `sweep.json` records how long it took.
    #[pyo3(signature = (summaries, wall_seconds = None, workers = None))]
    fn outcome(
        &self,
        summaries: Vec<String>,
        wall_seconds: Option<f64>,
        workers: Option<usize>,
    ) -> PyResult<SweepOutcome> {
        let summaries = summaries
            .iter()
            .enumerate()
            .map(|(i, s)| serde_json::from_str::<Summary>(s).map_err(|e| bad_input(format!("summary {i}: {e}"))))
            .collect::<PyResult<Vec<_>>>()?;
        let mut outcome = self.0.outcome(summaries).map_err(bad_input)?;
        if let (Some(wall_seconds), Some(threads)) = (wall_seconds, workers) {
            outcome.timing = Some(Timing { wall_seconds, threads });
        }
        Ok(SweepOutcome { sweep: Arc::clone(&self.0), outcome })
    }
}

/// What a sweep produced: the library's tables and files.
#[pyclass(frozen, module = "stickslip._stickslip")]
pub struct SweepOutcome {
    sweep: Arc<lib::Sweep>,
    outcome: lib::SweepOutcome,
}

impl SweepOutcome {
    /// The prepared sweep.
    pub(crate) fn sweep(&self) -> &lib::Sweep {
        &self.sweep
    }
    /// The library's outcome.
    pub(crate) fn outcome(&self) -> &lib::SweepOutcome {
        &self.outcome
    }
}

#[pymethods]
impl SweepOutcome {
    /// The text of `sweep.csv`.
    fn sweep_csv(&self) -> String {
        self.outcome.sweep_csv(&self.sweep)
    }

    /// The text of `runs.csv`.
    fn runs_csv(&self) -> String {
        self.outcome.runs_csv(&self.sweep)
    }

    /// The text of `sweep.json`.
    fn sweep_json(&self) -> String {
        self.outcome.sweep_json(&self.sweep)
    }

    /// Writes `sweep.csv`, `runs.csv`, `sweep.svg` and `sweep.json` into the existing
    /// directory `out`, as `stickslip sweep` does.
    fn write(&self, py: Python<'_>, out: PathBuf) -> PyResult<()> {
        let _held = lock::hold(&out).map_err(bad_input)?;
        py.detach(|| self.outcome.write(&self.sweep, &out)).map_err(failed)
    }
}

/// A sweep's journal, open and locked (closed when the object is dropped).
#[pyclass(frozen, module = "stickslip._stickslip")]
pub struct SweepJournal {
    journal: Journal,
    seeds: Vec<u64>,
    done: Vec<Option<String>>,
    /// The output directory, held while the journal is open.
    _held: DirLock,
}

#[pymethods]
impl SweepJournal {
    /// Per run, in the order of `Sweep.runs`: its `summary.json` text if the journal held
    /// it when opened, else `None`.
    fn done(&self) -> Vec<Option<String>> {
        self.done.clone()
    }

    /// Appends run `run` with its `summary.json` text, as one synced line. The summary's
    /// seed must be the run's.
    fn append(&self, py: Python<'_>, run: usize, summary: &str) -> PyResult<()> {
        let s: Summary = serde_json::from_str(summary).map_err(|e| bad_input(format!("summary of run {run}: {e}")))?;
        let Some(&seed) = self.seeds.get(run) else {
            return Err(bad_input(format!("run {run}: the sweep has {} runs", self.seeds.len())));
        };
        if s.seed != seed {
            return Err(bad_input(format!("run {run} has seed {seed}; the summary's is {}", s.seed)));
        }
        py.detach(|| self.journal.append(run, seed, &s)).map_err(failed)
    }

    /// The journal's path.
    #[getter]
    fn path(&self) -> PathBuf {
        self.journal.path().to_path_buf()
    }
}
