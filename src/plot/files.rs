//! Writes a study's or a fit's files: its tables (made by the study, [`crate::studies::sweep`],
//! [`crate::studies::compare`], [`crate::fit::report`]) and its figure (made here), each file
//! written atomically. The figure is drawn before anything is written. This is the layer above
//! the results and their figures: a study never draws, a figure never writes.

use std::path::Path;

use super::PlotError;
use crate::fit::model::Problem;
use crate::fit::report::{fit_csv, fit_json, fit_toml};
use crate::fit::solve::FitResult;
use crate::output::atomic::{WriteFileError, write_files};
use crate::studies::compare::{Study, report};
use crate::studies::sweep::{Sweep, SweepOutcome};

/// Why a sweep's or a fit's files could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error(transparent)]
    Plot(#[from] PlotError),
    #[error(transparent)]
    Write(#[from] WriteFileError),
}

/// Why a work-precision study's files could not be written.
#[derive(Debug, thiserror::Error)]
pub enum CompareWriteError {
    #[error("cannot draw compare.svg: {}", .0.0)]
    Plot(#[from] PlotError),
    #[error(transparent)]
    Write(#[from] WriteFileError),
}

impl SweepOutcome {
    /// Writes `sweep.csv`, `runs.csv`, `sweep.svg` and `sweep.json` into `dir`.
    pub fn write(&self, sweep: &Sweep, dir: &Path) -> Result<(), WriteError> {
        let svg = super::sweep::sweep_svg(sweep, self)?;
        let files = [
            ("sweep.csv", self.sweep_csv(sweep)),
            ("runs.csv", self.runs_csv(sweep)),
            ("sweep.svg", svg),
            ("sweep.json", self.sweep_json(sweep)),
        ];
        Ok(write_files(dir, &files)?)
    }
}

impl Study {
    /// Writes `compare.csv`, `compare.svg` and `compare.md` into `dir`; `command` is the
    /// command line quoted in `compare.md`.
    pub fn write(&self, dir: &Path, command: &str) -> Result<(), CompareWriteError> {
        let svg = super::compare::svg(self)?;
        let files =
            [("compare.csv", report::csv(self)), ("compare.svg", svg), ("compare.md", report::markdown(self, command))];
        Ok(write_files(dir, &files)?)
    }
}

/// Writes a fit's four files into `dir`: `fit.csv`, `fit.toml`, `fit.svg`, `fit.json`.
pub fn write_fit(prob: &Problem, r: &FitResult, dir: &Path, data_path: &str) -> Result<(), WriteError> {
    let svg = super::fit::fit_svg(prob, r)?;
    let toml = fit_toml(prob, r).map_err(PlotError)?;
    let files = [
        ("fit.csv", fit_csv(prob, r)),
        ("fit.toml", toml),
        ("fit.svg", svg),
        ("fit.json", fit_json(prob, r, data_path)),
    ];
    Ok(write_files(dir, &files)?)
}
