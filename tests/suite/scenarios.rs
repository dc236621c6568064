//! NEEDS THE ENGINES. Every bundled scene in `scenarios/` runs briefly through
//! `stickslip::run_scene` and gives a finite summary and well-formed output files, and the
//! README's command (`stickslip run scenarios/fig1.toml`) works end to end.
//!
//! Scenes with `run.engine = "fixed"` need the fixed-step engine and scenes with
//! `run.engine = "exact"` need the exact engine; until an engine is built these tests fail
//! with "the ... engine cannot run this scene". Everything that needs no engine (reading,
//! validation, the command line's errors) is tested in `validate_scenarios.rs`,
//! `cli_bad_input.rs` and `scene_fuzz.rs`.

use std::path::{Path, PathBuf};
use std::process::Command;

use stickslip::Scene;
use stickslip::output::Summary;
use stickslip::output::csv::TraceWriter;
use stickslip::scene::EngineKind;

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

/// Junctions and simulated time of the brief runs.
const BRIEF_N: usize = 30;
const BRIEF_T_END: f64 = 20.0;

fn scenarios_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios")
}

/// Every `*.toml` file in `scenarios/`, sorted.
fn scenario_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(scenarios_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(!files.is_empty());
    files
}

/// The scene shortened to `BRIEF_T_END` (warm-up scaled with it) and `BRIEF_N` junctions.
fn brief(path: &Path) -> Scene {
    let full = Scene::from_file(path, &[]).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let t_end = full.run.t_end.min(BRIEF_T_END);
    let t_warmup = if full.run.t_warmup > 0.0 { (t_end / 4.0).floor() } else { 0.0 };
    let n = full.junctions.n.min(BRIEF_N);
    full.with_overrides(&[
        format!("run.t_end={t_end:?}"),
        format!("run.t_warmup={t_warmup:?}"),
        format!("junctions.n={n}"),
    ])
    .unwrap_or_else(|e| panic!("{}: shortened scene refused: {e}", path.display()))
}

/// Rows of `trace.csv` (header checked), as numbers.
fn read_trace(dir: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(dir.join("trace.csv")).expect("trace.csv is written");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(TraceWriter::HEADER));
    lines
        .map(|l| {
            let row: Vec<f64> =
                l.split(',').map(|v| v.parse().unwrap_or_else(|_| panic!("bad number in {l:?}"))).collect();
            assert_eq!(row.len(), 6, "{l:?}");
            assert!(row.iter().all(|v| v.is_finite()), "non-finite value in trace row {l:?}");
            row
        })
        .collect()
}

fn check_summary(name: &str, scene: &Scene, s: &Summary) {
    for (what, v) in [
        ("friction_mean", s.friction_mean),
        ("friction_std", s.friction_std),
        ("friction_per_junction", s.friction_per_junction),
        ("bond_force_mean", s.bond_force_mean),
        ("viscous_force_mean", s.viscous_force_mean),
        ("attached_fraction_mean", s.attached_fraction_mean),
        ("wall_seconds", s.wall_seconds),
    ] {
        assert!(v.is_finite(), "{name}: {what} = {v}");
    }
    assert!(s.friction_std >= 0.0, "{name}");
    assert!((0.0..=1.0).contains(&s.attached_fraction_mean), "{name}: {}", s.attached_fraction_mean);
    assert_eq!(
        (s.n, s.t_end, s.t_warmup, s.seed),
        (scene.junctions.n as u64, scene.run.t_end, scene.run.t_warmup, scene.run.seed)
    );
    assert_eq!(s.engine, scene.run.engine, "{name}");
    assert_eq!(&s.parameters, scene, "{name}: summary parameters");
    let rel = (s.friction_per_junction - s.friction_mean / s.n as f64).abs();
    assert!(rel <= 1e-12 * (1.0 + s.friction_per_junction.abs()), "{name}");
    match scene.run.engine {
        EngineKind::Fixed => {
            assert_eq!(s.counters.steps, Some(scene.fixed.steps_for(scene.run.t_end)), "{name}: steps");
        }
        EngineKind::Exact => {
            assert_eq!(s.counters.events, Some(s.counters.ruptures + s.counters.formations), "{name}: events");
        }
    }
}

/// Needs the fixed-step engine: every bundled scene with `run.engine = "fixed"`.
#[test]
fn fixed_engine_scenes_run_briefly_to_a_finite_summary() {
    run_briefly(EngineKind::Fixed);
}

/// Needs the exact engine: every bundled scene with `run.engine = "exact"`.
#[test]
fn exact_engine_scenes_run_briefly_to_a_finite_summary() {
    run_briefly(EngineKind::Exact);
}

/// Runs every bundled scene of `engine` briefly and checks its summary and files.
fn run_briefly(engine: EngineKind) {
    for path in scenario_files() {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let scene = brief(&path);
        if scene.run.engine != engine {
            continue;
        }
        let dir = tempfile::tempdir().unwrap();
        let summary = stickslip::run_scene(&scene, Some(dir.path())).unwrap_or_else(|e| panic!("{name}: {e}"));
        check_summary(&name, &scene, &summary);

        // summary.json holds the same summary.
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap()).unwrap();
        assert_eq!(json["scene"], scene.name.as_str(), "{name}");
        assert_eq!(json["n"], scene.junctions.n as u64, "{name}");
        for key in ["friction_mean", "friction_std", "bond_force_mean", "viscous_force_mean", "attached_fraction_mean"]
        {
            assert!(json[key].as_f64().is_some_and(f64::is_finite), "{name}: summary.json {key} = {}", json[key]);
        }

        // No temporary files are left; trace.csv and events.csv exist exactly as asked.
        for entry in std::fs::read_dir(dir.path()).unwrap() {
            let p = entry.unwrap().path();
            assert!(!p.to_string_lossy().ends_with(".part"), "{name}: left {}", p.display());
        }
        assert_eq!(dir.path().join("trace.csv").exists(), scene.output.trace, "{name}");
        assert_eq!(dir.path().join("events.csv").exists(), scene.output.events, "{name}");
        if scene.output.trace {
            let rows = read_trace(dir.path());
            assert_eq!(rows.first().map(|r| r[0]), Some(0.0), "{name}: trace starts at t = 0");
            assert_eq!(rows.last().map(|r| r[0]), Some(scene.run.t_end), "{name}: trace ends at t_end");
            assert!(rows.windows(2).all(|w| w[1][0] > w[0][0]), "{name}: trace times increase");
            for r in &rows {
                // A kinematic plate reports the bond force as its friction. Otherwise
                // `K (V t - X)` recomputed from the written `X` carries the rounding of `X`
                // and `V t`, `K eps (|V t| + |X|)`, beyond the engine's own (a stiff plate:
                // K = 1e9, X ~ 1 gives ~1e-7 on a friction of ~50).
                let (expected, rounding) = if scene.plate.kinematic {
                    (r[4], 0.0)
                } else {
                    let vt = scene.plate.v * r[0];
                    (scene.plate.k * (vt - r[1]), 2.0 * scene.plate.k * f64::EPSILON * (vt.abs() + r[1].abs()))
                };
                assert!(
                    (r[3] - expected).abs() <= 1e-9 * (1.0 + expected.abs()) + rounding,
                    "{name}: friction != K (V t - X) (or F_b, kinematic) at {r:?}"
                );
                assert!((0.0..=1.0).contains(&r[5]), "{name}: attached fraction {r:?}");
            }
            // Exact engine: <F> = <F_b> + <eta Xd> + M (Xd(t_end) - Xd(t_warmup)) / (t_end - t_warmup).
            // (Checked when the trace has a row at t_warmup.)
            let start = match scene.run.engine {
                EngineKind::Exact => rows.iter().find(|r| r[0] == scene.run.t_warmup),
                EngineKind::Fixed => None,
            };
            if let Some(start) = start {
                let end = rows.last().unwrap();
                let window = scene.run.t_end - scene.run.t_warmup;
                let inertia = scene.plate.mass * (end[2] - start[2]) / window;
                let rhs = summary.bond_force_mean + summary.viscous_force_mean + inertia;
                let scale = 1.0 + summary.friction_mean.abs() + summary.bond_force_mean.abs() + inertia.abs();
                assert!(
                    (summary.friction_mean - rhs).abs() <= 1e-6 * scale,
                    "{name}: <F> = {} but <F_b> + <eta Xd> + M dXd/T = {rhs}",
                    summary.friction_mean
                );
            }
        }
    }
}

/// Needs the fixed-step engine. The README's first command, through the binary: the full
/// Fig. 1 run (150 steps, N = 300) into the default output directory.
#[test]
fn readme_command_runs_fig1() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scenarios_dir().join("fig1.toml");
    let out = Command::new(BIN).arg("run").arg(&scene).current_dir(dir.path()).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "stickslip run scenarios/fig1.toml failed: {stderr}");
    // Default output directory: out/<scene file stem>/ under the working directory.
    let results = dir.path().join("out").join("fig1");
    assert!(results.join("summary.json").is_file());
    let rows = read_trace(&results);
    assert_eq!(rows.len(), 151, "150 steps of dt = 1 sampled every step, plus t = 0");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("150 steps"), "{stdout}");
}
