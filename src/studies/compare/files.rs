//! Writes a finished study: `compare.csv` and `compare.md` ([`super::report`]) and
//! `compare.svg` ([`crate::plot::compare`]). This is the layer above the study's data and
//! its figure: the study never draws, the figure never writes.

use std::path::Path;

use super::{Study, report};
use crate::output::atomic::{WriteFileError, write_files};
use crate::plot::PlotError;

/// Why a study's files could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("cannot draw compare.svg: {}", .0.0)]
    Plot(#[from] PlotError),
    #[error(transparent)]
    Write(#[from] WriteFileError),
}

impl Study {
    /// Writes `compare.csv`, `compare.svg` and `compare.md` into `dir`, each atomically;
    /// `command` is the command line quoted in `compare.md`. The SVG is drawn before
    /// anything is written.
    pub fn write(&self, dir: &Path, command: &str) -> Result<(), WriteError> {
        let svg = crate::plot::compare::svg(self)?;
        let files =
            [("compare.csv", report::csv(self)), ("compare.svg", svg), ("compare.md", report::markdown(self, command))];
        write_files(dir, &files)?;
        Ok(())
    }
}
