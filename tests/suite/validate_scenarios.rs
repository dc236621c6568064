//! The bundled scenes in `scenarios/`: each one validates, `stickslip validate` prints its
//! resolved parameters (which read back to the same scene), and the Fig. 1 scenes hold the
//! letter's parameters. New scene files are picked up automatically. No engine is needed.

use std::path::{Path, PathBuf};
use std::process::Command;

use stickslip::Scene;
use stickslip::scene::{EngineKind, ForceLawKind};
use stickslip_testkit as testkit;

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

/// Every `*.toml` file in `scenarios/`, sorted.
fn scenario_files() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no scenes in {}", dir.display());
    files
}

fn scenario(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios").join(name);
    Scene::from_file(&path, &[]).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn every_bundled_scene_validates_and_prints_its_resolved_parameters() {
    for path in scenario_files() {
        let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
        let out = Command::new(BIN).arg("validate").arg(&path).output().expect("the binary runs");
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{}: {stderr}", path.display());
        assert!(stderr.is_empty(), "{}: {stderr}", path.display());
        assert!(stdout.starts_with(&format!("# scene {stem} is valid")), "{stdout}");
        for section in ["[junctions]", "[plate]", "[run]", "[fixed]", "[exact]", "[output]"] {
            assert!(stdout.lines().any(|l| l == section), "{}: no {section} in\n{stdout}", path.display());
        }
        // The printed parameters are a complete scene file that reads back to the same scene.
        let from_file = Scene::from_file(&path, &[]).unwrap();
        let printed = Scene::from_toml_str(&stdout, "validate output", &stem, &[])
            .unwrap_or_else(|e| panic!("{}: printed parameters do not read back: {e}", path.display()));
        assert_eq!(printed, from_file, "{}", path.display());
    }
}

/// Huge and tiny values are printed in exponent form (not hundreds of digits), and the
/// printed parameters still read back to the same scene.
#[test]
fn long_numbers_are_printed_short_and_read_back() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios").join("fig1.toml");
    let sets = ["plate.k_slope=1e300", "plate.k=1e250", "junctions.kon0=1e-30", "exact.atol=2.5e-300"];
    let mut cmd = Command::new(BIN);
    cmd.arg("validate").arg(&path);
    for s in sets {
        cmd.args(["--set", s]);
    }
    let out = cmd.output().expect("the binary runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for line in ["k_slope = 1e300", "k = 1e250", "kon0 = 1e-30", "atol = 2.5e-300"] {
        assert!(stdout.lines().any(|l| l == line), "no line {line:?} in\n{stdout}");
    }
    assert!(stdout.lines().all(|l| l.len() < 200), "a long line in\n{stdout}");
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let from_file = Scene::from_file(&path, &sets).unwrap();
    let printed = Scene::from_toml_str(&stdout, "validate output", "fig1", &[])
        .unwrap_or_else(|e| panic!("printed parameters do not read back: {e}\n{stdout}"));
    assert_eq!(printed, from_file);
}

#[test]
fn fig1_is_the_letters_figure_1() {
    let s = scenario("fig1.toml");
    assert_eq!(s, testkit::fig1(), "scenarios/fig1.toml differs from the test kit's Fig. 1");
    let (j, p) = (&s.junctions, &s.plate);
    assert_eq!((j.n, j.kappa, j.lambda, j.l0, j.alpha, j.dx), (300, 0.1, 0.1, 1.0, 1.0, 1.0));
    assert_eq!((j.k0, j.kon0, j.tau0), (0.1, 0.1, 2.0));
    assert_eq!((p.v, p.k, p.mass, p.eta), (0.5, 150.0, 75.0, 75.0));
    assert_eq!(j.force_law, ForceLawKind::Tilted);
    assert_eq!(s.run.engine, EngineKind::Fixed);
    assert_eq!((s.fixed.dt, s.fixed.steps_for(s.run.t_end)), (1.0, 150));
    assert_eq!((s.run.seed, s.output.sample_dt, s.output.trace), (1, 1.0, true));
}

#[test]
fn fig1_variants_differ_from_fig1_only_where_they_say() {
    let mut linear = scenario("fig1-linear.toml");
    linear.name = "fig1".into();
    assert_eq!(linear, testkit::fig1_with(&["junctions.force_law=linear"]));

    let mut exact = scenario("fig1-exact.toml");
    exact.name = "fig1".into();
    assert_eq!(exact, testkit::fig1_with(&["run.engine=exact", "run.t_end=1000", "run.t_warmup=100"]));
}

/// The ```toml examples in the documentation are valid scenes.
#[test]
fn documented_scene_examples_validate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut checked = 0;
    for doc in ["docs/scenes.md", "README.md"] {
        let text = std::fs::read_to_string(root.join(doc)).unwrap_or_else(|e| panic!("{doc}: {e}"));
        let mut rest = text.as_str();
        while let Some(start) = rest.find("```toml\n") {
            let body = &rest[start + "```toml\n".len()..];
            let end = body.find("```").unwrap_or_else(|| panic!("{doc}: unterminated ```toml block"));
            Scene::from_toml_str(&body[..end], doc, "example", &[])
                .unwrap_or_else(|e| panic!("{doc}: example scene refused: {e}\n{}", &body[..end]));
            checked += 1;
            rest = &body[end..];
        }
    }
    assert!(checked >= 1, "no ```toml example found in the docs");
}
