//! Friction laws: [`stickslip::studies::law::FrictionLaw`] from a finished sweep's
//! directory or from a sweep's outcome; the texts of `law.csv`, `abaqus.inp`, `ansys.mac`
//! and `law.json` are those `stickslip friction-law` writes.

use std::path::PathBuf;

use pyo3::prelude::*;
use stickslip::studies::law::{self as lib, ScaleArgs};

use crate::sweep::SweepOutcome;
use crate::{bad_input, failed};

/// A friction law, built; its files as text, or written.
#[pyclass(frozen, module = "stickslip._stickslip")]
pub struct FrictionLaw(lib::FrictionLaw);

/// The law of `source`, a finished sweep's directory (`sweep.json`, `runs.csv`) or a
/// sweep's outcome (a 2-D sweep over `plate.v` and `junctions.temperature`), in the units
/// of the scales (`None`: missing, a `ValueError` naming the option as the CLI does).
/// The scales are checked before the directory is read.
#[pyfunction]
#[pyo3(signature = (source, l0, t0, t_ref, normal_load, force_unit = None, fit_degree = lib::DEFAULT_DEGREE))]
#[allow(clippy::too_many_arguments)]
pub fn friction_law(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    l0: Option<f64>,
    t0: Option<f64>,
    t_ref: Option<f64>,
    normal_load: Option<f64>,
    force_unit: Option<f64>,
    fit_degree: u32,
) -> PyResult<FrictionLaw> {
    if !(1..=2).contains(&fit_degree) {
        return Err(bad_input(format!("--fit-degree {fit_degree}: must be 1 or 2")));
    }
    let scales = ScaleArgs { l0, t0, t_ref, normal_load, force_unit }.resolve().map_err(bad_input)?;
    let input = match source.extract::<PyRef<'_, SweepOutcome>>() {
        Ok(o) => lib::from_outcome(o.sweep(), o.outcome()).map_err(bad_input)?,
        Err(_) => {
            let dir: PathBuf = source.extract()?;
            py.detach(|| lib::read_sweep_dir(&dir)).map_err(bad_input)?
        }
    };
    Ok(FrictionLaw(lib::FrictionLaw::new(&input, scales, fit_degree).map_err(bad_input)?))
}

#[pymethods]
impl FrictionLaw {
    /// The text of `law.csv`.
    fn law_csv(&self) -> String {
        self.0.law_csv()
    }
    /// The text of `abaqus.inp`.
    fn abaqus_inp(&self) -> String {
        self.0.abaqus_inp()
    }
    /// The text of `ansys.mac`.
    fn ansys_mac(&self) -> String {
        self.0.ansys_mac()
    }
    /// The text of `law.json`.
    fn law_json(&self) -> String {
        self.0.law_json()
    }
    /// Writes `law.csv`, `abaqus.inp`, `ansys.mac` and `law.json` into the existing
    /// directory `out`, each atomically.
    fn write(&self, py: Python<'_>, out: PathBuf) -> PyResult<()> {
        py.detach(|| self.0.write(&out)).map_err(failed)
    }
}
