//! Temperature as a physical input (docs/model.md, "Temperature"; `src/scene/thermal.rs`):
//! - every activation energy and slope 0 gives the model without them bit for bit (outputs
//!   byte-identical, both engines, both laws, strong and weak bonds), and at `T = 1` any
//!   coefficients give the reference model's outputs;
//! - a sweep of `junctions.temperature` (also as the second field of a V-T map) moves every
//!   temperature-dependent parameter together, and the map's figure names both axes;
//! - weak bonds at a kinematic drive, re-forming unstretched, follow the renewal theory
//!   (docs/model.md, "Weak bonds at a kinematic drive: renewal theory") at the Arrhenius
//!   rates, at `T = 0.5`, 1 and 2;
//! - bad coefficients are refused with one line naming the field, exit code 2, nothing
//!   written.
//!
//! Run with `cargo test --release --test suite thermal::`.

use std::path::Path;

use crate::cli_bad_input::expect_bad_scene;
use crate::common;
use crate::renewal::{K0, KAPPA, KON0, REPLICAS, V, V0, check};

use common::renewal::Renewal;
use stickslip::run_scene;
use stickslip::studies::sweep::{Sweep, SweepAxis, SweepSpec, ValueSpec, parse_values};
use stickslip_testkit::scene;

/// A short scene for the byte-for-byte comparisons: Fig. 1's junctions at `T = 1.7`, with
/// `events.csv`.
const SHORT: &str = r#"
[junctions]
n = 40
k0 = 0.3
kon0 = 0.2
temperature = 1.7
initial = "stationary"
[plate]
mass = 10.0
eta = 10.0
k = 20.0
v = 0.7
[run]
t_end = 60.0
t_warmup = 10.0
seed = 7
[fixed]
dt = 0.1
rng = "pcg"
[output]
sample_dt = 0.5
events = true
plot = false
"#;

/// The five coefficients at 0, written out.
const ZEROS: [&str; 5] =
    ["junctions.e_off=0", "junctions.e_on=0.0", "junctions.kappa_slope=0", "plate.k_slope=0.0", "plate.eta_slope=-0.0"];

/// Nonzero coefficients.
const COEFFICIENTS: [&str; 5] = [
    "junctions.e_off=2.5",
    "junctions.e_on=1.5",
    "junctions.kappa_slope=0.3",
    "plate.k_slope=-0.2",
    "plate.eta_slope=0.1",
];

/// Each engine, law and bond kind.
fn configurations() -> Vec<Vec<&'static str>> {
    let mut out = Vec::new();
    for engine in ["run.engine=exact", "run.engine=fixed"] {
        for law in ["junctions.force_law=linear", "junctions.force_law=tilted"] {
            for bond in ["junctions.bond=strong", "junctions.bond=weak"] {
                out.push(vec![engine, law, bond]);
            }
        }
    }
    out
}

/// Runs the short scene with `overrides` into `dir`; returns `summary.json` without its
/// wall time and without `parameters`, and the trace's and events' bytes.
fn outputs(overrides: &[&str], dir: &Path) -> (serde_json::Value, serde_json::Value, Vec<u8>, Vec<u8>) {
    let s = scene(SHORT, overrides);
    run_scene(&s, Some(dir)).unwrap_or_else(|e| panic!("{overrides:?}: {e}"));
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let mut summary: serde_json::Value = serde_json::from_str(&text).unwrap();
    let map = summary.as_object_mut().unwrap();
    map.remove("wall_seconds").expect("wall_seconds");
    let parameters = map.remove("parameters").expect("parameters");
    let read = |name: &str| std::fs::read(dir.join(name)).unwrap();
    (summary, parameters, read("trace.csv"), read("events.csv"))
}

/// Zero coefficients written out give the outputs of the scene that does not mention them,
/// byte for byte, `summary.json`'s parameters included; at `T = 1`, nonzero coefficients
/// give the reference outputs too (every factor is exactly 1); and at `T = 1.7` they do
/// change the run (so the comparison can fail).
#[test]
fn zero_coefficients_are_the_model_without_them_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    for (i, config) in configurations().into_iter().enumerate() {
        let dir = |tag: &str| {
            let d = tmp.path().join(format!("{i}-{tag}"));
            std::fs::create_dir_all(&d).unwrap();
            d
        };
        let base = outputs(&config, &dir("base"));
        let zeros = outputs(&[config.clone(), ZEROS.to_vec()].concat(), &dir("zeros"));
        assert!(!base.2.is_empty() && base.3.len() > 100, "{config:?}: the run writes a trace and events");
        assert_eq!(base.0, zeros.0, "{config:?}: summary.json");
        assert_eq!(base.1, zeros.1, "{config:?}: summary.json's parameters");
        assert!(base.2 == zeros.2, "{config:?}: trace.csv differs");
        assert!(base.3 == zeros.3, "{config:?}: events.csv differs");
        // No reference block without a temperature dependence.
        assert!(base.1.get("reference").is_none(), "{config:?}");

        let at_one = [config.clone(), vec!["junctions.temperature=1"]].concat();
        let reference = outputs(&at_one, &dir("t1"));
        let thermal = outputs(&[at_one.clone(), COEFFICIENTS.to_vec()].concat(), &dir("t1-thermal"));
        assert_eq!(reference.0, thermal.0, "{config:?}: summary.json at T = 1");
        assert!(reference.2 == thermal.2 && reference.3 == thermal.3, "{config:?}: outputs at T = 1");
        assert_eq!(thermal.1["junctions"]["k0"], reference.1["junctions"]["k0"]);
        assert_eq!(thermal.1["reference"]["k0"], reference.1["junctions"]["k0"]);

        let hot = outputs(&[config.clone(), COEFFICIENTS.to_vec()].concat(), &dir("hot"));
        assert!(hot.2 != base.2, "{config:?}: the coefficients change the run at T = 1.7");
    }
}

/// The parameters a scene runs with, by the formulas of docs/model.md, written out here.
fn expected(t: f64) -> [f64; 5] {
    // fig2's reference values: k0 = kon0 = 1, kappa = 0.1, K = 15, eta = 25.
    [
        (-2.5 * (1.0 / t - 1.0)).exp(),
        (-1.5 * (1.0 / t - 1.0)).exp(),
        0.1 * (1.0 + 0.3 * (t - 1.0)),
        15.0 * (1.0 - 0.2 * (t - 1.0)),
        25.0 * (1.0 + 0.1 * (t - 1.0)),
    ]
}

/// A V-T map: every run's summary records the values in force at its temperature (all five
/// moved together) and the reference values, and the map's figure names both axes.
#[test]
fn a_temperature_sweep_moves_every_parameter_together() {
    let fig2 = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/fig2.toml");
    let mut set: Vec<String> = COEFFICIENTS.iter().map(|s| s.to_string()).collect();
    set.extend(["run.t_end=40", "run.t_warmup=10", "output.trace=false", "output.plot=false"].map(String::from));
    let base = stickslip::Scene::from_file(&fig2, &set).unwrap();
    let v = SweepAxis { param: "plate.v".into(), values: parse_values(ValueSpec::List("0.2,1")).unwrap(), log: false };
    let temps = parse_values(ValueSpec::List("0.5,1,2")).unwrap();
    let t = SweepAxis { param: "junctions.temperature".into(), values: temps, log: false };
    let sweep = Sweep::prepare(base, SweepSpec { axes: vec![v, t], replicas: 1, set }).unwrap();
    let mut summaries = Vec::new();
    for run in sweep.runs() {
        let temperature = run.scene.junctions.temperature;
        let sum = run_scene(run.scene, None).unwrap();
        let json = serde_json::to_value(&sum).unwrap();
        let p = &json["parameters"];
        let got = [
            &p["junctions"]["k0"],
            &p["junctions"]["kon0"],
            &p["junctions"]["kappa"],
            &p["plate"]["k"],
            &p["plate"]["eta"],
        ]
        .map(|x| x.as_f64().unwrap());
        for (name, (g, e)) in ["k0", "kon0", "kappa", "K", "eta"].iter().zip(got.iter().zip(expected(temperature))) {
            assert!((g - e).abs() <= 2.0 * f64::EPSILON * e, "T = {temperature}: {name} = {g}, expected {e}");
        }
        if temperature == 1.0 {
            assert_eq!(got, [1.0, 1.0, 0.1, 15.0, 25.0], "T = 1: the reference values exactly");
        }
        let r = &p["reference"];
        assert_eq!(
            [&r["k0"], &r["kon0"], &r["kappa"], &r["k"], &r["eta"]].map(|x| x.as_f64().unwrap()),
            [1.0, 1.0, 0.1, 15.0, 25.0]
        );
        assert_eq!(p["junctions"]["e_off"].as_f64(), Some(2.5));
        summaries.push(sum);
    }
    assert_eq!(summaries.len(), 6);
    // Hot junctions break faster: the attached fraction at V = 0.2 falls from T = 0.5 to 2
    // (e_off > e_on: k0 grows faster than kon0).
    assert!(summaries[0].attached_fraction_mean > summaries[2].attached_fraction_mean + 0.1);
    let outcome = sweep.outcome(summaries).unwrap();
    let out = tempfile::tempdir().unwrap();
    outcome.write(&sweep, out.path()).unwrap();
    let svg = std::fs::read_to_string(out.path().join("sweep.svg")).unwrap();
    assert!(svg.contains("plate.v") && svg.contains("junctions.temperature"), "the map names both axes");
    let csv = std::fs::read_to_string(out.path().join("sweep.csv")).unwrap();
    assert!(csv.starts_with("plate.v,junctions.temperature,"), "{csv}");
}

/// A scene and its file form give each other back: the file holds the reference values
/// (the map is applied once, at validation, never twice), in TOML, JSON and MessagePack.
#[test]
fn a_thermal_scene_round_trips() {
    let mut o = COEFFICIENTS.to_vec();
    o.push("junctions.temperature=1.6");
    let s = stickslip_testkit::fig1_with(&o);
    assert_eq!(s.with_overrides(&[]).unwrap(), s);
    let file = s.to_file();
    assert_eq!((file.junctions.k0, file.plate.k), (Some(0.1), Some(150.0)));
    assert!(s.junctions.k0 > 0.1 && s.plate.k < 150.0);
    let json: stickslip::Scene = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
    assert_eq!(json, s);
    // A scene recorded without the thermal fields (as before they existed) reads as zeros.
    let plain = stickslip_testkit::fig1();
    let mut value = serde_json::to_value(&plain).unwrap();
    for (section, key) in [
        ("junctions", "e_off"),
        ("junctions", "e_on"),
        ("junctions", "kappa_slope"),
        ("plate", "k_slope"),
        ("plate", "eta_slope"),
    ] {
        value[section].as_object_mut().unwrap().remove(key).unwrap();
    }
    assert_eq!(serde_json::from_value::<stickslip::Scene>(value).unwrap(), plain);
}

// ---- renewal theory at Arrhenius rates ------------------------------------------------

const E_OFF: f64 = 2.0;
const E_ON: f64 = 1.0;
const KAPPA_SLOPE: f64 = 0.25;
/// `(attached fraction, bond force per junction)` of `REPLICAS` replicas at `T` of the
/// renewal scene of `tests/suite/renewal.rs` (weak bonds, linear law, kinematic plate at
/// `V = 0.8`, unstretched re-attachment, `N = 1000`, window `[400, 2400]`) with the thermal
/// coefficients.
fn replicas(t: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut n, mut f) = (Vec::new(), Vec::new());
    let temperature = format!("junctions.temperature={t}");
    let (e_off, e_on, slope) = (
        format!("junctions.e_off={E_OFF}"),
        format!("junctions.e_on={E_ON}"),
        format!("junctions.kappa_slope={KAPPA_SLOPE}"),
    );
    for r in 0..REPLICAS {
        let mut s = scene(crate::renewal::SCENE, &[&temperature, &e_off, &e_on, &slope]);
        assert_eq!(
            (s.plate.v, s.junctions.kappa, s.junctions.temperature),
            (V, KAPPA * (1.0 + KAPPA_SLOPE * (t - 1.0)), t)
        );
        s.run.seed = 2000 + r;
        let sum = run_scene(&s, None).unwrap();
        n.push(sum.attached_fraction_mean);
        f.push(sum.bond_force_mean / s.junctions.n as f64);
    }
    (n, f)
}

/// The exact engine (linear law) against the renewal theory with `k0(T)`, `kon0(T)`,
/// `kappa(T)` from the formulas and the force sensitivity `dx / T`; the references differ
/// from one temperature to the next by far more than the tolerances.
#[test]
fn renewal_theory_holds_at_arrhenius_rates() {
    let mut forces = Vec::new();
    for t in [0.5, 1.0, 2.0] {
        let kappa = KAPPA * (1.0 + KAPPA_SLOPE * (t - 1.0));
        let k0 = K0 * (-E_OFF * (1.0 / t - 1.0)).exp();
        let kon = KON0 * (-E_ON * (1.0 / t - 1.0)).exp() * (std::f64::consts::FRAC_PI_2 * V0 / V).sin();
        let tension = move |x: f64| kappa * x.abs();
        let force_x = move |x: f64| kappa * x;
        let theory = Renewal { k0, beta_dx: 1.0 / t, v: V, kon, tension, force_x }.integrals(kappa * V);
        let (n, f) = replicas(t);
        check(&format!("T = {t}: attached fraction"), &n, theory.attached_fraction());
        check(&format!("T = {t}: bond force per junction"), &f, theory.mean_force_x());
        forces.push(theory.mean_force_x().value);
    }
    // The temperatures test different physics: the references differ by more than 20 %.
    for w in forces.windows(2) {
        assert!((w[0] - w[1]).abs() > 0.2 * w[0], "{forces:?}");
    }
}

// ---- bad input ----------------------------------------------------------------------

/// A valid fixed-engine scene with `lines` added to `[junctions]` and `plate` to `[plate]`.
fn bad(junctions: &str, plate: &str) -> String {
    format!(
        "[junctions]\nn = 30\n{junctions}\n[plate]\nmass = 75.0\neta = 75.0\n{plate}\n[run]\nengine = \"fixed\"\nt_end = 10.0\n[fixed]\ndt = 1.0\n"
    )
}

#[test]
fn bad_coefficients_are_refused_with_one_line() {
    expect_bad_scene(&bad("e_off = -0.5", ""), &["junctions.e_off = -0.5", ">= 0", "activation energy"]);
    expect_bad_scene(&bad("e_on = -2", ""), &["junctions.e_on = -2", ">= 0"]);
    expect_bad_scene(&bad("e_on = nan", ""), &["junctions.e_on = NaN", "finite"]);
    expect_bad_scene(&bad("kappa_slope = inf", ""), &["junctions.kappa_slope = inf", "finite"]);
    // 1 + 2 (0.25 - 1) = -0.5 at T = 0.25: kappa would be negative.
    expect_bad_scene(
        &bad("temperature = 0.25\nkappa_slope = 2.0", ""),
        &["junctions.kappa_slope = 2", "junctions.kappa <= 0", "junctions.temperature = 0.25", "-0.5"],
    );
    // 1 - 0.5 (3 - 1) = 0 at T = 3: K would be 0.
    expect_bad_scene(
        &bad("temperature = 3.0", "k_slope = -0.5"),
        &["plate.k_slope = -0.5", "plate.k <= 0", "junctions.temperature = 3"],
    );
    expect_bad_scene(&bad("temperature = 3.0", "eta_slope = -1"), &["plate.eta_slope = -1", "plate.eta <= 0"]);
    // exp(-800 (1/0.5 - 1)) underflows; exp(800 (1 - 1e-9)) overflows.
    expect_bad_scene(&bad("temperature = 0.5\ne_off = 800.0", ""), &["junctions.e_off = 800", "underflows"]);
    expect_bad_scene(&bad("temperature = 1e9\ne_on = 800.0", ""), &["junctions.e_on = 800", "overflows"]);
}
