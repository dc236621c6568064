//! Runs: [`run_to_dir`] is `stickslip run SCENE --out DIR` (the same files, byte for byte,
//! written by the same runner) with the trace and events read back as columns;
//! [`run_summary_json`] is one run of a sweep (no files), for a Dask worker. Both release
//! the GIL while the engine runs.

use std::path::{Path, PathBuf};

use pyo3::prelude::*;
use pyo3::types::PyBytes;
use stickslip::output::csv::{EventWriter, TraceWriter};
use stickslip::runner::run_scene;

use crate::scene::Scene;
use crate::{bad_input, failed};

/// A CSV file's columns: f64 columns as native-endian bytes (numpy's `float64`), except
/// `junction` (`uint32`) and `kind` (`uint8` codes into `kinds`).
#[derive(Default)]
struct Columns {
    names: Vec<String>,
    data: Vec<Vec<u8>>,
    kinds: Vec<String>,
}

/// Reads a CSV file written by the runner's writers (a header, then numbers, or an event
/// kind in column `kind`). Numbers are in their shortest round-trip form, so each parses
/// back to the very `f64` the run produced.
fn read_columns(path: &Path) -> Result<Columns, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header = lines.next().ok_or_else(|| format!("{}: empty file", path.display()))?;
    let mut c = Columns { names: header.split(',').map(str::to_string).collect(), ..Columns::default() };
    c.data = vec![Vec::new(); c.names.len()];
    for (row, line) in lines.enumerate() {
        let mut fields = line.split(',');
        for (k, name) in c.names.iter().enumerate() {
            let bad = || format!("{}: row {}: column {name} is missing or not a number", path.display(), row + 1);
            let f = fields.next().ok_or_else(bad)?;
            match name.as_str() {
                "junction" => c.data[k].extend(f.parse::<u32>().map_err(|_| bad())?.to_ne_bytes()),
                "kind" => {
                    let code = match c.kinds.iter().position(|s| s == f) {
                        Some(i) => i,
                        None => {
                            c.kinds.push(f.to_string());
                            c.kinds.len() - 1
                        }
                    };
                    c.data[k].push(u8::try_from(code).map_err(|_| bad())?);
                }
                _ => c.data[k].extend(f.parse::<f64>().map_err(|_| bad())?.to_ne_bytes()),
            }
        }
    }
    Ok(c)
}

/// `(names, column bytes, kinds)` for Python.
type PyColumns<'py> = (Vec<String>, Vec<Bound<'py, PyBytes>>, Vec<String>);

fn to_py(py: Python<'_>, c: Columns) -> PyColumns<'_> {
    let data = c.data.iter().map(|d| PyBytes::new(py, d)).collect();
    (c.names, data, c.kinds)
}

/// Runs `scene` into the existing directory `out` as `stickslip run` does (`trace.csv`,
/// `events.csv` as the scene asks, `trace.svg` with `output.plot`, then `summary.json`),
/// and returns `summary.json`'s text with the trace's and the events' columns (`None`
/// for a file the scene does not write). The GIL is released while the engine runs.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn run_to_dir<'py>(
    py: Python<'py>,
    scene: &Scene,
    out: PathBuf,
) -> PyResult<(String, Option<PyColumns<'py>>, Option<PyColumns<'py>>)> {
    let s = &scene.0;
    if !out.is_dir() {
        return Err(bad_input(format!("output directory {}: not a directory", out.display())));
    }
    // Held until the run's files are written and read back, as `stickslip run` holds it.
    let _held = stickslip::output::lock::hold(&out).map_err(bad_input)?;
    let done = py.detach(|| -> Result<_, String> {
        let summary = run_scene(s, Some(&out)).map_err(|e| e.to_string())?;
        if s.output.plot {
            stickslip::plot::trace::write_trace_svg(&out, s)
                .map_err(|e| format!("cannot write {}: {e}", out.join("trace.svg").display()))?;
        }
        let json = serde_json::to_string_pretty(&summary).expect("summary serializes");
        let read = |on: bool, name: &str| on.then(|| read_columns(&out.join(name))).transpose();
        Ok((json, read(s.output.trace, TraceWriter::NAME)?, read(s.output.events, EventWriter::NAME)?))
    });
    let (json, trace, events) = done.map_err(failed)?;
    Ok((json, trace.map(|c| to_py(py, c)), events.map(|c| to_py(py, c))))
}

/// One run of a sweep, without files: the scene's complete TOML text (from
/// `Scene.to_toml`) and name in, `summary.json`'s text out. A pure function of its
/// arguments (the seed is in the scene), so a task retried anywhere gives the same
/// summary, apart from `wall_seconds`. The GIL is released while the engine runs.
#[pyfunction]
pub fn run_summary_json(py: Python<'_>, scene_toml: &str, name: &str) -> PyResult<String> {
    let scene = stickslip::Scene::from_toml_str(scene_toml, name, name, &[]).map_err(bad_input)?;
    let summary = py.detach(|| run_scene(&scene, None)).map_err(failed)?;
    Ok(serde_json::to_string(&summary).expect("summary serializes"))
}
