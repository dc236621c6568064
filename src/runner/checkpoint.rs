//! Checkpoints of a run, and `resume`.
//!
//! A checkpoint ([`crate::output::checkpoint`] for the file format) is taken at an
//! output-grid stop, where the engine is between two advances. It records
//! - the resolved scene and the checkpoint interval;
//! - the engine's whole state (its random generator included), tagged with the engine's
//!   concrete type;
//! - the runner's state: position on the output grid, window statistics, regime detector,
//!   rupture-force statistics, wall time so far, checkpoints written;
//! - how far `trace.csv.part` and `events.csv.part` are written (bytes, rows, last bytes),
//!   after flushing and syncing them.
//!
//! [`resume`] reads it, rebuilds the engine of the same concrete type through the engine
//! dispatch ([`with_engine`] on the checkpointed scene, then the state is decoded into that
//! type), cuts the partial outputs back to the recorded lengths and continues the run.
//! Everything is checked before any file is touched: a bad checkpoint changes nothing.

use std::any::type_name;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::error::{RunError, output_error};
use super::grid::GridPosition;
use super::observers::{EventObservers, RunObservers, Writers};
use super::run::{RunOptions, RunPlan, RunStart, run_from};
use crate::engine::{Engine, EngineVisitor, with_engine};
use crate::observe::regime::RegimeDetector;
use crate::observe::stats::{RuptureForces, WindowStats};
use crate::output::Summary;
use crate::output::atomic::ReopenError;
use crate::output::checkpoint::{self as file, CheckpointError, FILE, Loaded};
use crate::output::csv::{CsvFile, EventWriter, FilePos, TraceWriter};
use crate::scene::{BondKind, Scene};

const PROGRAM: &str = "stickslip";

/// The checkpoint's header: everything but the engine state.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct Header {
    program: String,
    program_version: String,
    /// The engine's concrete type (`std::any::type_name`), checked on resume.
    engine_type: String,
    /// `--checkpoint-every` of the run (seconds), reused by `resume`.
    checkpoint_every: f64,
    scene: Scene,
    runner: RunnerState,
}

/// The runner's part of a checkpoint.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct RunnerState {
    /// Simulated time of the checkpoint.
    t: f64,
    grid: GridPosition,
    /// Wall time of the run up to the checkpoint (all processes).
    wall_seconds: f64,
    /// Checkpoints written, this one included.
    checkpoints: u64,
    stats: WindowStats,
    regime: RegimeDetector,
    ruptures: Option<RuptureForces>,
    trace: Option<FilePos>,
    events: Option<FilePos>,
}

/// Removes `checkpoint.bin` (and a temporary one) from `dir`, if there.
pub(crate) fn remove(dir: &Path) -> Result<(), RunError> {
    remove_files(dir, &[FILE.to_string(), format!("{FILE}.part")])
}

/// Removes what an earlier run killed in `dir` left: its checkpoint and partial outputs
/// (a new run would overwrite them; a checkpoint must never outlive the files it describes).
pub(crate) fn remove_stale(dir: &Path) -> Result<(), RunError> {
    let parts = [TraceWriter::NAME, EventWriter::NAME].map(|n| format!("{n}.part"));
    remove(dir)?;
    remove_files(dir, &parts)
}

fn remove_files(dir: &Path, names: &[String]) -> Result<(), RunError> {
    for name in names {
        match std::fs::remove_file(dir.join(name)) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(output_error(dir, name)(e)),
        }
    }
    Ok(())
}

/// Writes a checkpoint of the run into `dir`: the outputs are flushed and synced first,
/// so the checkpoint never refers to bytes that are not on disk.
pub(super) fn save<E: Engine, X: EventObservers>(
    dir: &Path,
    plan: &RunPlan,
    engine: &E,
    obs: &mut RunObservers<X>,
    pos: &GridPosition,
    wall_seconds: f64,
    checkpoints: u64,
) -> Result<u64, RunError> {
    let (trace, events) = obs.file_positions(dir)?;
    let (stats, regime) = &obs.core;
    let header = Header {
        program: PROGRAM.to_string(),
        program_version: env!("CARGO_PKG_VERSION").to_string(),
        engine_type: type_name::<E>().to_string(),
        checkpoint_every: plan.opts.checkpoint_every.unwrap_or(f64::INFINITY),
        scene: plan.scene.clone(),
        runner: RunnerState {
            t: engine.time(),
            grid: *pos,
            wall_seconds,
            checkpoints,
            stats: stats.clone(),
            regime: regime.clone(),
            ruptures: obs.events.rupture_forces().cloned(),
            trace,
            events,
        },
    };
    file::write(dir, &header, engine).map_err(output_error(dir, FILE))
}

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
    use crate::observe::Recorder;
    use crate::runner::{OutputGrid, drive_walk};
    use crate::test_scenes::fig1_with;

    /// Everything a recorder saw, with every bit of every number.
    fn seen(r: &Recorder) -> String {
        format!("{:?}", (&r.events, &r.segments, &r.samples))
    }

    fn state_bytes<E: Engine>(e: &E) -> Vec<u8> {
        let mut v = Vec::new();
        crate::output::state_codec::encode(&mut v, e).unwrap();
        v
    }

    /// Advances to `t_mid`, writes a checkpoint file with the engine state, reads it back
    /// into a second engine, and checks that both go on identically to `t_end`.
    struct RoundTrip {
        t_mid: f64,
        t_end: f64,
    }

    impl EngineVisitor for RoundTrip {
        type Output = String;
        fn visit<E: Engine>(self, mut e: E) -> String {
            e.advance(self.t_mid, &mut Recorder::default()).unwrap();
            let dir = tempfile::tempdir().unwrap();
            file::write(dir.path(), &"header".to_string(), &e).unwrap();
            let loaded: Loaded<String> = file::read(&dir.path().join(FILE)).unwrap();
            assert_eq!(loaded.header, "header");
            let mut copy: E = loaded.engine().unwrap();
            assert_eq!(state_bytes(&e), state_bytes(&copy), "{}", type_name::<E>());
            let (mut a, mut b) = (Recorder::default(), Recorder::default());
            e.advance(self.t_end, &mut a).unwrap();
            copy.advance(self.t_end, &mut b).unwrap();
            assert!(a.events.len() > 10, "{}: too few events to test anything", type_name::<E>());
            assert_eq!(seen(&a), seen(&b), "{}", type_name::<E>());
            assert_eq!(format!("{:?}", e.sample()), format!("{:?}", copy.sample()));
            assert_eq!(e.counters(), copy.counters());
            assert_eq!(state_bytes(&e), state_bytes(&copy), "{}", type_name::<E>());
            type_name::<E>().to_string()
        }
    }

    fn round_trip(overrides: &[&str]) -> String {
        let scene = fig1_with(overrides);
        with_engine(&scene, RoundTrip { t_mid: 40.0, t_end: 100.0 }).unwrap()
    }

    #[test]
    fn fixed_engines_continue_identically_after_a_round_trip() {
        let mut types = vec![
            round_trip(&[]),
            round_trip(&[
                "junctions.force_law=linear",
                "junctions.bond=weak",
                "fixed.rng=pcg",
                "fixed.flip=exponential",
                "fixed.integrator=velocity-verlet",
                "fixed.dt=0.5",
            ]),
            round_trip(&["fixed.flip=as-printed", "fixed.integrator=explicit-euler", "fixed.dt=0.1"]),
            round_trip(&[
                "junctions.bond=weak",
                "plate.mass=0",
                "junctions.initial=stationary",
                "junctions.reattach=unstretched",
            ]),
        ];
        types.sort();
        types.dedup();
        assert_eq!(types.len(), 4, "{types:?}");
    }

    #[test]
    fn exact_engines_continue_identically_after_a_round_trip() {
        let exact = ["run.engine=exact"];
        let with = |more: &[&str]| round_trip(&[&exact[..], more].concat());
        let types = [
            with(&["junctions.force_law=linear"]),
            with(&["junctions.force_law=linear", "junctions.bond=weak", "junctions.initial=stationary"]),
            with(&[]),
            with(&["junctions.bond=weak"]),
            with(&["plate.mass=0", "junctions.reattach=unstretched"]),
        ];
        // Linear strong, linear weak, tilted strong, tilted weak: four engine types.
        let mut distinct = types.to_vec();
        distinct.sort();
        distinct.dedup();
        assert_eq!(distinct.len(), 4, "{types:?}");
    }

    /// Drives a scene through the grid, and from every stop a copy of the engine, the
    /// observers and the grid position; every copy must end exactly where the whole run did.
    struct SplitAnywhere<'a>(&'a Scene);

    impl EngineVisitor for SplitAnywhere<'_> {
        type Output = usize;
        fn visit<E: Engine>(self, e: E) -> usize {
            let grid = OutputGrid::new(self.0, e.time_step());
            let mut whole = e;
            let (mut rec, mut walk) = (Recorder::default(), grid.walk_from(GridPosition::default()));
            let mut copies = Vec::new();
            drive_walk(&mut whole, &mut walk, &mut rec, None, |e, r, p| {
                let copy: E = crate::output::state_codec::decode(&state_bytes(e)).unwrap();
                copies.push((copy, r.clone(), *p));
                Ok::<(), RunError>(())
            })
            .unwrap();
            let n = copies.len();
            for (mut e, mut r, p) in copies {
                let mut w = grid.walk_from(p);
                drive_walk(&mut e, &mut w, &mut r, None, |_, _, _| Ok::<(), RunError>(())).unwrap();
                assert_eq!(seen(&r), seen(&rec));
                assert_eq!(w.position(), walk.position());
            }
            n
        }
    }

    #[test]
    fn a_run_continues_from_any_stop() {
        // The fixed engine with a grid that is not a multiple of dt and a warm-up stop
        // between samples; the exact engine with the same grid.
        let fixed = fig1_with(&["run.t_end=12", "run.t_warmup=2.5", "output.sample_dt=1", "fixed.dt=0.75"]);
        assert!(with_engine(&fixed, SplitAnywhere(&fixed)).unwrap() >= 12);
        let exact = fig1_with(&["run.engine=exact", "run.t_end=12", "run.t_warmup=2.5", "output.sample_dt=1"]);
        assert!(with_engine(&exact, SplitAnywhere(&exact)).unwrap() >= 12);
    }
}
