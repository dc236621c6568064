//! `stickslip._stickslip`: the native module of the Python package `stickslip`
//! (python/stickslip/). Thin bindings of the library: scenes ([`scene`]), runs ([`run`]),
//! sweeps ([`sweep`]), friction laws ([`law`]) and fits ([`fit`]). Every rule (validation, seeds,
//! aggregation, the tables' text) stays in the library, so Python and the CLI cannot drift apart; the Python layer adds
//! arrays, DataFrames and the Dask scheduling.
//!
//! Errors: bad input is a `ValueError` whose text is the CLI's one-line message (what
//! `stickslip` prints after `error: `); a run that fails is a `RuntimeError`.

mod fit;
mod law;
mod run;
mod scene;
mod sweep;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use stickslip::scene::error::printable;

/// Bad input: the CLI's one-line message as a `ValueError`.
pub(crate) fn bad_input(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(printable(&e.to_string()))
}

/// A run or a write that failed: its one-line message as a `RuntimeError`.
pub(crate) fn failed(e: impl std::fmt::Display) -> PyErr {
    PyRuntimeError::new_err(printable(&e.to_string()))
}

#[pymodule]
fn _stickslip(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<sweep::Sweep>()?;
    m.add_class::<sweep::SweepOutcome>()?;
    m.add_class::<sweep::SweepJournal>()?;
    m.add_function(wrap_pyfunction!(run::run_to_dir, m)?)?;
    m.add_function(wrap_pyfunction!(run::run_summary_json, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::parse_values, m)?)?;
    m.add_class::<law::FrictionLaw>()?;
    m.add_function(wrap_pyfunction!(law::friction_law, m)?)?;
    m.add_class::<fit::Fit>()?;
    m.add_function(wrap_pyfunction!(fit::fit_run, m)?)?;
    Ok(())
}
