//! `Scene`: a validated scene (the library's [`stickslip::Scene`]), read from a TOML file
//! or text with `section.key=value` overrides exactly as `stickslip run --set` reads it.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyType;

use crate::bad_input;

/// A validated scene. Immutable; pickles as its complete TOML text and name.
#[pyclass(frozen, module = "stickslip._stickslip")]
pub struct Scene(pub stickslip::Scene);

impl Scene {
    /// The scene as a complete scene file (every field explicit): re-reading it gives the
    /// same scene (the library's sweeps rely on the same round trip).
    pub fn toml(&self) -> String {
        toml::to_string(&self.0.to_file()).expect("a scene always serializes")
    }
}

#[pymethods]
impl Scene {
    /// Reads TOML text, applies the overrides (`section.key=value`) and validates; `name`
    /// is the scene's name (a file's stem when read from a file).
    #[new]
    #[pyo3(signature = (text, name = "scene", overrides = Vec::new()))]
    fn new(text: &str, name: &str, overrides: Vec<String>) -> PyResult<Self> {
        stickslip::Scene::from_toml_str(text, name, name, &overrides).map(Scene).map_err(bad_input)
    }

    /// Reads a scene file, applies the overrides and validates (the CLI's `SCENE --set ..`).
    #[staticmethod]
    #[pyo3(signature = (path, overrides = Vec::new()))]
    fn from_file(path: PathBuf, overrides: Vec<String>) -> PyResult<Self> {
        stickslip::Scene::from_file(&path, &overrides).map(Scene).map_err(bad_input)
    }

    /// This scene with further overrides applied and validated.
    fn with_overrides(&self, overrides: Vec<String>) -> PyResult<Self> {
        self.0.with_overrides(&overrides).map(Scene).map_err(bad_input)
    }

    /// The scene's name (file stem).
    #[getter]
    fn name(&self) -> &str {
        &self.0.name
    }

    /// `run.seed`.
    #[getter]
    fn seed(&self) -> u64 {
        self.0.run.seed
    }

    /// The warning `stickslip run` prints before a fixed-step run whose step is beyond the
    /// plate integrator's stability limit (docs/stability.md), or `None`.
    fn stability_warning(&self) -> Option<String> {
        stickslip::cli::stability::warning(&self.0)
    }

    /// The complete scene file as TOML text.
    fn to_toml(&self) -> String {
        self.toml()
    }

    /// The resolved parameters as JSON (the `parameters` of `summary.json`).
    fn to_json(&self) -> String {
        serde_json::to_string(&self.0).expect("a scene always serializes")
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> (Bound<'py, PyType>, (String, String)) {
        let s = slf.get();
        (slf.get_type(), (s.toml(), s.0.name.clone()))
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.0.name == other.0.name && self.toml() == other.toml()
    }

    fn __repr__(&self) -> String {
        format!("Scene(name={:?}, engine={:?}, seed={})", self.0.name, self.0.run.engine, self.0.run.seed)
    }
}
