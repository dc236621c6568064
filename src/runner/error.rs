//! Why a run failed.

use std::io;
use std::path::{Path, PathBuf};

use crate::engine::EngineError;

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Engine(#[from] EngineError),
    #[error("cannot write {path}: {source}")]
    Output {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// Writing failed after a checkpoint was written: the partial outputs and the
    /// checkpoint are kept, and the run can be resumed once the cause is fixed.
    #[error("{source}; the run stopped at t = {t} and can be resumed from its checkpoint with `stickslip resume {}`", dir.display())]
    Resumable {
        #[source]
        source: Box<RunError>,
        dir: PathBuf,
        t: f64,
    },
    /// A stop was requested ([`super::StopFlag`]) before the run reached `t_end`. With an
    /// output directory, a checkpoint was written there and the run can be resumed.
    #[error("the run was stopped on request at t = {t}{}", match dir {
        Some(d) => format!("; resume it with `stickslip resume {}`", d.display()),
        None => String::new(),
    })]
    Stopped { t: f64, dir: Option<PathBuf> },
}

/// The error of writing `dir/name`.
pub(super) fn output_error(dir: &Path, name: &str) -> impl FnOnce(io::Error) -> RunError {
    let path = dir.join(name);
    move |source| RunError::Output { path, source }
}
