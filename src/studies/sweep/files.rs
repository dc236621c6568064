//! Writes a sweep's files: the tables ([`super::tables`]) and `sweep.svg`
//! ([`crate::plot::sweep`]). This is the layer above the sweep's data and its figure: the
//! sweep never draws, the figure never writes.

use std::path::Path;

use super::outcome::SweepOutcome;
use super::plan::Sweep;
use crate::output::atomic::{WriteFileError, write_files};
use crate::plot::PlotError;

/// Why a sweep's files could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error(transparent)]
    Plot(#[from] PlotError),
    #[error(transparent)]
    Write(#[from] WriteFileError),
}

impl SweepOutcome {
    /// Writes `sweep.csv`, `runs.csv`, `sweep.svg` and `sweep.json` into `dir`, each
    /// atomically. The SVG is drawn before anything is written.
    pub fn write(&self, sweep: &Sweep, dir: &Path) -> Result<(), WriteError> {
        let svg = crate::plot::sweep::sweep_svg(sweep, self)?;
        let files = [
            ("sweep.csv", self.sweep_csv(sweep)),
            ("runs.csv", self.runs_csv(sweep)),
            ("sweep.svg", svg),
            ("sweep.json", self.sweep_json(sweep)),
        ];
        write_files(dir, &files)?;
        Ok(())
    }
}
