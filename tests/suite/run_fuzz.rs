//! Property test: random scene texts and random `--set` values, through validation, the
//! estimates and a short run. Every case ends in a result or a one-line error: never a
//! panic (proptest reports one as a failure), an abort (the test binary would die) or a
//! NaN or infinity in an output file or the summary.
//!
//! Scenes are the shipped scenarios with random overrides of their numeric and choice
//! fields (values from tiny to huge, zero, negative, non-finite); a valid scene is run when
//! its work is small (bounded by its events, steps and samples), with its size cut down
//! first by `--set` values that are themselves checked.

use std::path::Path;

use proptest::prelude::*;
use stickslip::Scene;
use stickslip::estimate::Estimate;

const SCENES: &[&str] =
    &["fig1.toml", "fig1-exact.toml", "fig1-linear.toml", "weak.toml", "kinematic.toml", "creep.toml"];

const FIELDS: &[&str] = &[
    "junctions.n",
    "junctions.kappa",
    "junctions.l0",
    "junctions.lambda",
    "junctions.k0",
    "junctions.kon0",
    "junctions.tau0",
    "junctions.alpha",
    "junctions.dx",
    "junctions.temperature",
    "plate.mass",
    "plate.eta",
    "plate.k",
    "plate.v",
    "run.t_end",
    "run.t_warmup",
    "run.seed",
    "fixed.dt",
    "exact.rtol",
    "exact.atol",
    "output.sample_dt",
];

const CHOICES: &[&str] = &[
    "run.engine=exact",
    "run.engine=fixed",
    "junctions.bond=weak",
    "junctions.bond=strong",
    "junctions.force_law=linear",
    "junctions.force_law=tilted",
    "junctions.initial=attached",
    "junctions.initial=stationary",
    "junctions.reattach=unstretched",
    "plate.kinematic=true",
    "plate.kinematic=false",
    "fixed.rng=pcg",
    "fixed.flip=exponential",
    "fixed.flip=as-printed",
    "fixed.integrator=velocity-verlet",
    "fixed.integrator=explicit-euler",
    "exact.tilted=direct",
    "output.events=true",
    "output.plot=true",
];

/// A number from tiny to huge, of either sign, or a special value.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (-12i32..12, 1u32..10).prop_map(|(e, m)| format!("{m}e{e}")),
        1 => (-320i32..309).prop_map(|e| format!("1e{e}")),
        1 => (-300i32..300).prop_map(|e| format!("-1e{e}")),
        1 => prop::sample::select(&["0", "-0.0", "nan", "inf", "-inf", "4294967295", "4294967296", "1.5"][..])
            .prop_map(str::to_string),
    ]
}

fn assignment() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => (prop::sample::select(FIELDS), number()).prop_map(|(f, v)| format!("{f}={v}")),
        1 => prop::sample::select(CHOICES).prop_map(str::to_string),
    ]
}

/// Whether `scene` is small enough to run here: few junctions, steps, events and samples.
fn small(scene: &Scene) -> bool {
    let est = Estimate::of(scene, false);
    let j = &scene.junctions;
    let n = j.n as f64;
    // Each junction forms at most at kon0 and ruptures once per formation, plus once at first.
    let events_bound = n * (1.0 + 2.0 * j.kon0 * scene.run.t_end);
    n <= 2000.0
        && est.work.steps.is_none_or(|s| (s as f64) * n <= 2e6)
        && events_bound <= 2e5
        && est.work.samples <= 20_000
        && scene.run.t_end <= 1e4
}

fn no_nan(path: &Path) -> Result<(), TestCaseError> {
    if let Ok(text) = std::fs::read_to_string(path) {
        for bad in ["NaN", "inf", "null"] {
            prop_assert!(!text.contains(bad), "{} holds {bad}", path.display());
        }
    }
    Ok(())
}

fn one_line(msg: &str) -> Result<(), TestCaseError> {
    prop_assert!(!msg.is_empty() && !msg.contains(['\n', '\r']), "not one line: {msg:?}");
    Ok(())
}

fn check(scene_file: &str, sets: &[String]) -> Result<(), TestCaseError> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios").join(scene_file);
    let scene = match Scene::from_file(&path, sets) {
        Ok(s) => s,
        Err(e) => return one_line(&e.to_string()),
    };
    // The estimates and what `validate` prints of them, for any valid scene.
    let est = Estimate::of(&scene, true);
    prop_assert!(est.work.events.is_finite() && est.work.events >= 0.0, "events {}", est.work.events);
    for line in est.report(Path::new("out/fuzz")) {
        one_line(&line)?;
    }
    if let Err(e) = stickslip::estimate::check_run(&scene, Path::new("out/fuzz"), false) {
        return one_line(&e.to_string());
    }
    // A short run: cut N and t_end down when the scene is too big to run here.
    let scene = if small(&scene) {
        scene
    } else {
        let t = scene.run.t_end.min(20.0);
        let cut = [format!("junctions.n={}", scene.junctions.n.min(50)), format!("run.t_end={t}")];
        match scene.with_overrides(&cut) {
            Ok(s) if small(&s) => s,
            Ok(_) => return Ok(()),
            Err(e) => return one_line(&e.to_string()),
        }
    };
    let dir = tempfile::tempdir().unwrap();
    match stickslip::runner::run_scene(&scene, Some(dir.path())) {
        Ok(summary) => {
            let json = serde_json::to_string(&summary).unwrap();
            prop_assert!(!json.contains("null"), "a number in the summary is not finite: {json}");
            for f in ["trace.csv", "events.csv", "summary.json"] {
                no_nan(&dir.path().join(f))?;
            }
        }
        Err(e) => one_line(&e.to_string())?,
    }
    Ok(())
}

proptest! {
    // 256 cases by default (each may run a scene); PROPTEST_CASES for a longer hunt.
    #![proptest_config(crate::scene_fuzz::fuzz_config(256, 20261125))]

    #[test]
    fn random_overrides_validate_and_run_cleanly(
        scene in prop::sample::select(SCENES),
        sets in prop::collection::vec(assignment(), 0..6),
    ) {
        check(scene, &sets)?;
    }

    #[test]
    fn random_scene_texts_validate_and_run_cleanly(text in crate::scene_fuzz::scene_like(), sets in prop::collection::vec(assignment(), 0..3)) {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("fuzz.toml");
        std::fs::write(&file, &text).unwrap();
        check_text(&file, &sets)?;
    }
}

/// [`check`] for a scene file outside `scenarios/`.
fn check_text(file: &Path, sets: &[String]) -> Result<(), TestCaseError> {
    check(file.to_str().unwrap(), sets)
}
