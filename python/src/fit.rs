//! Fits: a prepared [`stickslip::fit`] problem (`stickslip fit`'s scene, data, free
//! parameters and replicas, refused with the CLI's messages) and the fit itself, run by the
//! library's optimiser and profiles, with each batch of runs (an evaluation: every data
//! point's replicas) handed to a Python callable that maps them onto Dask. The journal,
//! the output lock and the files are the library's, so a fit from Python writes the bytes
//! of `stickslip fit` and each can continue the other's journal.

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError};
use pyo3::prelude::*;
use stickslip::fit::model::{Evaluation, FitError, Objective, Problem, Simulator};
use stickslip::fit::{prepare, solve};
use stickslip::output::lock;
use stickslip::runner::{StopFlag, run_scene};
use stickslip::studies::journal::{self, Journal};

use crate::scene::Scene;
use crate::{bad_input, failed};

/// One run of a fit, without files: the scene's complete TOML text (its seed in it) and
/// name in, its mean friction per junction out (the value `stickslip fit` takes from the
/// same run). A pure function of its arguments, for a Dask worker; the GIL is released
/// while the engine runs. A run that fails is a `RuntimeError` naming its seed.
#[pyfunction]
pub fn fit_run(py: Python<'_>, scene_toml: &str, name: &str) -> PyResult<f64> {
    let scene = stickslip::Scene::from_toml_str(scene_toml, name, name, &[]).map_err(bad_input)?;
    let seed = scene.run.seed;
    py.detach(|| run_scene(&scene, None))
        .map(|s| s.friction_per_junction)
        .map_err(|e| failed(format!("seed {seed}: {e}")))
}

/// A prepared fit: validated and seeded, not run.
#[pyclass(frozen, module = "stickslip._stickslip")]
pub struct Fit {
    problem: Problem,
    max: usize,
    data_name: String,
    /// The command's arguments, for the journal's command line (`stickslip resume`).
    data: PathBuf,
    free: Vec<String>,
    friction_scale: f64,
}

/// Runs an evaluation's scenes through the Python callable `simulate(tomls, names) ->
/// list[float]` (their mean frictions per junction, in order). A `KeyboardInterrupt`
/// stops the fit after the evaluations in progress; any other exception is kept and
/// becomes the fit's error.
struct PySimulator {
    simulate: Py<PyAny>,
    stop: StopFlag,
    error: Mutex<Option<PyErr>>,
}

impl Simulator for PySimulator {
    fn friction_per_junction(&self, scenes: &[stickslip::Scene]) -> Result<Vec<f64>, String> {
        let tomls: Vec<String> =
            scenes.iter().map(|s| toml::to_string(&s.to_file()).expect("a scene always serializes")).collect();
        let names: Vec<&str> = scenes.iter().map(|s| s.name.as_str()).collect();
        Python::attach(|py| {
            let out = self.simulate.call1(py, (tomls, names)).and_then(|r| r.extract::<Vec<f64>>(py));
            match out {
                Ok(v) if v.len() == scenes.len() => Ok(v),
                Ok(v) => Err(format!("the simulator returned {} values for {} runs", v.len(), scenes.len())),
                Err(e) => {
                    if e.is_instance_of::<PyKeyboardInterrupt>(py) {
                        self.stop.request();
                    }
                    let message = e.value(py).str().map_or_else(|_| e.to_string(), |s| s.to_string());
                    self.error.lock().unwrap_or_else(|p| p.into_inner()).get_or_insert(e);
                    Err(message)
                }
            }
        })
    }
}

#[pymethods]
impl Fit {
    /// Prepares the fit of the scene fields `free` (`--free` texts) of `base` (overrides
    /// applied) to the data file `data`, `replicas` runs per point and evaluation, friction
    /// and sigma multiplied by `friction_scale`, at most `max_evaluations` evaluations.
    /// Errors are the CLI's.
    #[new]
    #[pyo3(signature = (base, data, free, replicas = 4, friction_scale = 1.0, max_evaluations = 5000))]
    fn new(
        base: &Scene,
        data: PathBuf,
        free: Vec<String>,
        replicas: usize,
        friction_scale: f64,
        max_evaluations: usize,
    ) -> PyResult<Self> {
        if !(1..=10_000).contains(&replicas) {
            return Err(bad_input(format!("--replicas {replicas}: must be from 1 to 10000")));
        }
        if !stickslip::fit::data::in_window(friction_scale) {
            return Err(bad_input(format!("--friction-scale {friction_scale}: must be a number from 1e-100 to 1e100")));
        }
        if !(1..=1_000_000).contains(&max_evaluations) {
            return Err(bad_input(format!("--max-evaluations {max_evaluations}: must be from 1 to 1000000")));
        }
        let problem = prepare::problem(base.0.clone(), &data, &free, replicas, friction_scale).map_err(bad_input)?;
        Ok(Fit { problem, max: max_evaluations, data_name: prepare::data_name(&data), data, free, friction_scale })
    }

    /// Data points times replicas: the runs of one evaluation.
    fn runs_per_evaluation(&self) -> usize {
        self.problem.data.len() * self.problem.replicas
    }

    /// The free fields.
    #[getter(free)]
    fn free_fields(&self) -> Vec<String> {
        self.problem.free.iter().map(|f| f.field.clone()).collect()
    }

    /// Runs the fit into the existing directory `out` (held while it runs, as `stickslip
    /// fit` holds it), journaling every evaluation in `out/journal.jsonl` (a journal there
    /// of the same fit is continued: its evaluations are not made again), and writes
    /// `fit.json`, `fit.csv`, `fit.toml` and `fit.svg`. A new journal records the command
    /// line of the same fit (its scene written to `out/input/`), so that `stickslip resume
    /// out` continues it. Each evaluation's runs go to `simulate(tomls, names) ->
    /// list[float]`, called from several threads at once (the profiles' sides);
    /// `progress(evaluations, best_misfit, stage)`, if given, is called after each new
    /// evaluation (from those threads too). Returns `(evaluations, made now)`. Ctrl-C stops
    /// the fit after the evaluations in progress (the journal kept) and raises
    /// `KeyboardInterrupt`.
    #[pyo3(signature = (out, simulate, progress = None))]
    fn run(
        &self,
        py: Python<'_>,
        out: PathBuf,
        simulate: Py<PyAny>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<(usize, usize)> {
        let held = lock::hold(&out).map_err(bad_input)?;
        let existed = journal::read_header(&out).map_err(bad_input)?.is_some();
        let input = out.join(prepare::INPUT_DIR);
        let had_input = input.exists();
        let command = if existed {
            None
        } else {
            let p = &self.problem;
            let c = prepare::python_invocation(p, &self.data, &self.free, self.friction_scale, self.max, &out);
            Some(c.map_err(|e| failed(format!("cannot write the fit's scene into {}: {e}", input.display())))?)
        };
        let forget_input = || {
            if !had_input {
                let _ = std::fs::remove_dir_all(&input);
            }
        };
        let header = prepare::header(&self.problem, self.max, command);
        let seeds = vec![self.problem.base.run.seed; self.max];
        let mut opened = match py.detach(|| Journal::open::<Evaluation>(&out, &header, &seeds)) {
            Ok(o) => o,
            Err(e) => {
                forget_input();
                return Err(bad_input(e));
            }
        };
        let done: Vec<Evaluation> = std::mem::take(&mut opened.done).into_iter().map_while(|d| d).collect();
        let stop = StopFlag::new();
        let sim = PySimulator { simulate, stop: stop.clone(), error: Mutex::new(None) };
        let mut obj = Objective::new(&self.problem, &sim, done, Some(&opened.journal), Some(&stop), self.max);
        if let Some(f) = progress {
            // Progress is best effort: an exception in it is printed, not raised.
            obj.on_new = Some(Box::new(move |n, best, stage| {
                Python::attach(|py| {
                    if let Err(e) = f.call1(py, (n, best, stage.as_str())) {
                        e.print(py);
                    }
                })
            }));
        }
        // The fit runs on its own thread; this one answers Ctrl-C (Python sees signals on
        // the main thread only).
        let mut interrupt = None;
        let result = py.detach(|| {
            std::thread::scope(|s| {
                let fit = s.spawn(|| solve::fit(&obj));
                while !fit.is_finished() {
                    std::thread::sleep(Duration::from_millis(50));
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
                        stop.request();
                        interrupt.get_or_insert(e);
                    }
                }
                fit.join()
            })
        });
        let made = obj.new_evaluations();
        drop(obj);
        let kept = || {
            format!(
                "the evaluations are kept in {}; continue by calling the fit again",
                journal::path_in(&out).display()
            )
        };
        let python_error = sim.error.lock().unwrap_or_else(|p| p.into_inner()).take();
        let r = match result {
            Ok(Ok(r)) => r,
            Ok(Err(FitError::Stopped { .. })) if interrupt.is_some() || python_error.is_some() => {
                return Err(interrupt.or(python_error).expect("one is set"));
            }
            Ok(Err(e @ (FitError::Stopped { .. } | FitError::TooMany { .. } | FitError::Journal(_)))) => {
                return Err(PyRuntimeError::new_err(format!("{e}; {}", kept())));
            }
            Ok(Err(e)) => {
                if !existed {
                    let path = opened.journal.path().to_path_buf();
                    drop(opened);
                    let _ = std::fs::remove_file(path);
                    forget_input();
                }
                let err = failed(e);
                err.set_cause(py, python_error);
                return Err(err);
            }
            Err(_) => return Err(PyRuntimeError::new_err("the fit panicked")),
        };
        py.detach(|| stickslip::plot::files::write_fit(&self.problem, &r, &out, &self.data_name))
            .map_err(|e| failed(format!("{e}; {}", kept())))?;
        drop(held);
        Ok((r.evaluations, made))
    }
}
