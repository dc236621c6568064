//! `resume`: continues a killed run from its checkpoint ([`super::checkpoint`]).
//!
//! [`resume`] reads the checkpoint, rebuilds the engine of the same concrete type through the
//! engine dispatch ([`with_engine`] on the checkpointed scene, then the state is decoded into
//! that type), cuts the partial outputs back to the recorded lengths and continues the run.
//! Everything is checked before any file is touched: a bad checkpoint, or a run that does
//! not fit in the memory available now, changes nothing.

use std::any::type_name;
use std::path::{Path, PathBuf};

use super::checkpoint::{Header, PROGRAM};
use super::error::RunError;
use super::observers::Writers;
use super::plan::{RunOptions, RunPlan, RunStart};
use super::run::run_from;
use crate::engine::{Engine, EngineVisitor, with_engine};
use crate::output::Summary;
use crate::output::atomic::ReopenError;
use crate::output::checkpoint::{self as file, CheckpointError, FILE, Loaded};
use crate::output::csv::{CsvFile, EventWriter, TraceWriter};
use crate::scene::BondKind;

/// Why a run cannot be resumed.
#[derive(Debug, thiserror::Error)]
pub enum ResumeError {
    #[error("{} is not a directory", dir.display())]
    NotADirectory { dir: PathBuf },
    #[error(
        "{} holds no {FILE} and no summary.json: nothing to resume (only a run started with --checkpoint-every leaves a checkpoint)",
        dir.display()
    )]
    NoCheckpoint { dir: PathBuf },
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error("{}: {reason}", path.display())]
    Incompatible { path: PathBuf, reason: String },
    #[error("cannot resume from {}: {source}", path.display())]
    Outputs {
        path: PathBuf,
        #[source]
        source: ReopenError,
    },
    /// The run does not fit in the memory available now (a checkpoint may be resumed on
    /// another machine, or beside other work).
    #[error(transparent)]
    Resources(#[from] crate::estimate::ResourceError),
    #[error(transparent)]
    Run(#[from] RunError),
}

impl ResumeError {
    /// Whether this is bad input (a missing, damaged or incompatible checkpoint or
    /// partial output) rather than a run that failed.
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, ResumeError::Run(_))
    }
}

/// What `resume` did.
#[derive(Debug)]
pub enum Resumed {
    /// The run had finished (its `summary.json` is there and no checkpoint is left).
    Finished,
    /// The run was continued from its checkpoint at simulated time `from_t` to its end.
    Completed { from_t: f64, summary: Box<Summary> },
}

/// Continues the run whose output directory is `dir` from its checkpoint. `opts` gives
/// the progress setting and, if set, a new checkpoint interval (else the run's own).
pub fn resume(dir: &Path, opts: &RunOptions) -> Result<Resumed, ResumeError> {
    if !dir.is_dir() {
        return Err(ResumeError::NotADirectory { dir: dir.to_path_buf() });
    }
    let path = dir.join(FILE);
    if !path.exists() {
        return if dir.join("summary.json").is_file() {
            Ok(Resumed::Finished)
        } else {
            Err(ResumeError::NoCheckpoint { dir: dir.to_path_buf() })
        };
    }
    let loaded: Loaded<Header> = file::read(&path)?;
    let h = &loaded.header;
    let incompatible = |reason: String| ResumeError::Incompatible { path: path.clone(), reason };
    if h.program != PROGRAM || h.program_version != env!("CARGO_PKG_VERSION") {
        return Err(incompatible(format!(
            "written by {} {}; this is {PROGRAM} {}",
            h.program,
            h.program_version,
            env!("CARGO_PKG_VERSION")
        )));
    }
    // The scene is validated again, as if read from a file.
    let scene = h.scene.with_overrides(&[]).map_err(|e| incompatible(format!("its scene is not valid: {e}")))?;
    if scene != h.scene {
        return Err(incompatible("its scene changes when validated again".to_string()));
    }
    // Before the engine is built and its state decoded: a run too big for the memory
    // available now is refused in one line, and its checkpoint is left as it is.
    crate::estimate::check::check_memory(&scene, true)?;
    let every = opts.checkpoint_every.or(Some(h.checkpoint_every).filter(|s| s.is_finite() && *s > 0.0));
    let opts = RunOptions { checkpoint_every: every, ..opts.clone() };
    let visitor = ResumedRun { plan: RunPlan { scene: &scene, out: Some(dir), opts: &opts }, loaded: &loaded };
    let summary = with_engine(&scene, visitor).map_err(RunError::from)??;
    Ok(Resumed::Completed { from_t: loaded.header.runner.t, summary: Box::new(summary) })
}

/// A run continued from a checkpoint, once the engine type is known.
struct ResumedRun<'a> {
    plan: RunPlan<'a>,
    loaded: &'a Loaded<Header>,
}

impl EngineVisitor for ResumedRun<'_> {
    type Output = Result<Summary, ResumeError>;

    fn visit<E: Engine>(self, fresh: E) -> Self::Output {
        let (plan, loaded) = (&self.plan, self.loaded);
        let (scene, dir) = (plan.scene, plan.out.expect("resume has a directory"));
        let (h, r) = (&loaded.header, &loaded.header.runner);
        let incompatible = |reason: String| ResumeError::Incompatible { path: loaded.path.clone(), reason };
        if h.engine_type != type_name::<E>() {
            return Err(incompatible(format!(
                "it holds the state of engine {}, but its scene builds {}",
                h.engine_type,
                type_name::<E>()
            )));
        }
        // The fresh engine only told us the type; the checkpoint's state replaces it.
        drop(fresh);
        let engine: E = loaded.engine()?;
        let weak = scene.junctions.bond == BondKind::Weak;
        if r.trace.is_some() != scene.output.trace
            || r.events.is_some() != scene.output.events
            || r.ruptures.is_some() != weak
            || r.grid.stops_done == 0
            || engine.time() != r.t
        {
            return Err(incompatible("its runner state does not match its scene and engine".to_string()));
        }
        // Check the partial outputs before changing anything.
        let outputs = [(TraceWriter::NAME, &r.trace), (EventWriter::NAME, &r.events)];
        for (name, pos) in outputs {
            if let Some(p) = pos {
                CsvFile::check_resume(dir, name, p)
                    .map_err(|source| ResumeError::Outputs { path: loaded.path.clone(), source })?;
            }
        }
        let start = RunStart {
            position: r.grid,
            core: (r.stats.clone(), r.regime.clone()),
            writers: Writers::reopen(dir, r.trace.as_ref(), r.events.as_ref())?,
            ruptures: r.ruptures.clone(),
            wall_seconds: r.wall_seconds,
            checkpoints: r.checkpoints,
            checkpoint_t: Some(r.t),
        };
        Ok(run_from(engine, plan, start)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runner::drive::StopFlag;
    use crate::runner::run::{run_scene, run_scene_with};
    use crate::test_scenes::{fig1_with, summary_without_wall_time};

    #[test]
    fn a_run_stopped_on_request_resumes_to_the_same_files() {
        for overrides in [
            &["junctions.bond=weak", "fixed.dt=0.5"][..],
            &["run.engine=exact", "junctions.force_law=linear", "junctions.bond=weak", "run.t_warmup=20"],
        ] {
            let mut o = vec!["output.events=true"];
            o.extend_from_slice(overrides);
            let scene = fig1_with(&o);
            let whole = tempfile::tempdir().unwrap();
            let expected = run_scene(&scene, Some(whole.path())).unwrap();

            let dir = tempfile::tempdir().unwrap();
            let stop = StopFlag::new();
            stop.request();
            let opts = RunOptions { stop: Some(stop.clone()), ..RunOptions::default() };
            let t = match run_scene_with(&scene, Some(dir.path()), &opts) {
                Err(RunError::Stopped { t, dir: Some(d) }) => {
                    assert_eq!(d, dir.path());
                    t
                }
                other => panic!("{o:?}: expected a stop, got {other:?}"),
            };
            // Stopped after the first grid stop, resumable, nothing complete.
            assert!(t > 0.0 && t <= 1.0 + 1e-9, "{o:?}: stopped at {t}");
            let has = |name: &str| dir.path().join(name).exists();
            assert!(has("checkpoint.bin") && has("trace.csv.part") && has("events.csv.part"), "{o:?}");
            assert!(!has("summary.json") && !has("trace.csv") && !has("events.csv"), "{o:?}");

            match resume(dir.path(), &RunOptions::default()).unwrap() {
                Resumed::Completed { from_t, summary } => {
                    assert_eq!(from_t, t);
                    assert_eq!(summary_without_wall_time(&summary), summary_without_wall_time(&expected), "{o:?}");
                }
                Resumed::Finished => panic!("{o:?}: nothing was resumed"),
            }
            for name in ["trace.csv", "events.csv"] {
                let (a, b) = (std::fs::read(whole.path().join(name)).unwrap(), std::fs::read(dir.path().join(name)));
                assert!(a.len() > 1000 && Ok(a) == b.map_err(|_| ()), "{o:?}: {name} differs");
            }
            assert!(!has("checkpoint.bin"));

            // Without an output directory there is nothing to resume.
            let e = run_scene_with(&scene, None, &opts).unwrap_err();
            assert!(matches!(e, RunError::Stopped { dir: None, .. }), "{e:?}");
            assert_eq!(e.to_string(), format!("the run was stopped on request at t = {t}"));
        }
    }
}
