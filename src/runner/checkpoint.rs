//! Checkpoints of a run: writing and removing them ([`super::resume()`] reads them), and
//! removing an earlier run's files when a new run starts.
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

use std::any::type_name;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::error::{RunError, output_error};
use super::grid::GridPosition;
use super::observers::{EventObservers, RunObservers};
use super::plan::RunPlan;
use crate::engine::Engine;
use crate::observe::regime::RegimeDetector;
use crate::observe::stats::{RuptureForces, WindowStats};
use crate::output::RUN_FILES;
use crate::output::checkpoint::{self as file, FILE};
use crate::output::csv::FilePos;
use crate::scene::Scene;

pub(super) const PROGRAM: &str = "stickslip";

/// The checkpoint's header: everything but the engine state.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct Header {
    pub(super) program: String,
    pub(super) program_version: String,
    /// The engine's concrete type (`std::any::type_name`), checked on resume.
    pub(super) engine_type: String,
    /// `--checkpoint-every` of the run (seconds), reused by `resume`.
    pub(super) checkpoint_every: f64,
    pub(super) scene: Scene,
    pub(super) runner: RunnerState,
}

/// The runner's part of a checkpoint.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct RunnerState {
    /// Simulated time of the checkpoint.
    pub(super) t: f64,
    pub(super) grid: GridPosition,
    /// Wall time of the run up to the checkpoint (all processes).
    pub(super) wall_seconds: f64,
    /// Checkpoints written, this one included.
    pub(super) checkpoints: u64,
    pub(super) stats: WindowStats,
    pub(super) regime: RegimeDetector,
    pub(super) ruptures: Option<RuptureForces>,
    pub(super) trace: Option<FilePos>,
    pub(super) events: Option<FilePos>,
}

/// Removes `checkpoint.bin` (and a temporary one) from `dir`, if there.
pub(crate) fn remove(dir: &Path) -> Result<(), RunError> {
    remove_files(dir, &[FILE.to_string(), format!("{FILE}.part")])
}

/// Removes every file an earlier run left in `dir`, finished or partial ([`RUN_FILES`] and
/// their `.part` files; `summary.json` first), and nothing else: a new run that fails or is
/// killed then leaves nothing that looks complete, and no checkpoint of files it replaced.
pub(crate) fn remove_stale(dir: &Path) -> Result<(), RunError> {
    let names: Vec<String> = RUN_FILES.iter().flat_map(|n| [n.to_string(), format!("{n}.part")]).collect();
    remove_files(dir, &names)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{EngineVisitor, with_engine};
    use crate::observe::Recorder;
    use crate::output::checkpoint::Loaded;
    use crate::runner::drive::drive_walk;
    use crate::runner::grid::OutputGrid;
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
