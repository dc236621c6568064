//! The verdict `unstable` (docs/stability.md, "Unstable runs"): a fixed-step run whose plate
//! step fails is given no physical regime, on both sides of the stability limit; the
//! README's first command says so and draws its picture; `sweep` and `compare` use the
//! same verdict; the exact engine is never unstable.

use std::path::Path;
use std::process::Command;

use stickslip::engine::fixed::stability::analyse;
use stickslip::observe::regime::Regime;
use stickslip::observe::regime::numerics::Cause;
use stickslip::output::Summary;
use stickslip::run_scene;
use stickslip_testkit::fig1_with;

use crate::common::svg::assert_well_formed_svg;

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

fn stickslip(args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(BIN).args(args).current_dir(dir).output().expect("the binary runs")
}

fn scenario(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios").join(name).to_string_lossy().into_owned()
}

/// Fig. 1 at step `dt` (sampled every step) for `t_end`, seed `seed`, with `extra` overrides.
fn fig1_at(dt: f64, t_end: f64, seed: u64, extra: &[&str]) -> Summary {
    let (dt, t_end, seed) = (format!("fixed.dt={dt}"), format!("run.t_end={t_end}"), format!("run.seed={seed}"));
    let sample = dt.replace("fixed.dt", "output.sample_dt");
    let mut o = vec![dt.as_str(), sample.as_str(), t_end.as_str(), seed.as_str(), "output.trace=false"];
    o.extend_from_slice(extra);
    run_scene(&fig1_with(&o), None).unwrap_or_else(|e| panic!("{o:?}: {e}"))
}

fn cause(s: &Summary) -> Option<Cause> {
    s.stability.as_ref().expect("a fixed-step run reports its stability").unstable
}

/// Fig. 1's plate step (semi-implicit Euler) is stable for every attached count below
/// `dt_s = 0.9399` (all attached) and at or beyond the limit for all from `dt_u = 1` (none
/// attached). Below `dt_s` a run keeps its physical regime; from `dt_u` on it is unstable
/// by prediction; in between the run decides: it is stable up to about 0.975 and blows up
/// into a sustained period-2 oscillation from about 0.977 (docs/stability.md).
#[test]
fn fig1_steps_are_unstable_exactly_beyond_the_limit() {
    let r = *analyse(&fig1_with(&[])).selected();
    let (dt_s, dt_u) = (r.dt_stable, r.dt_unstable);
    assert!((dt_s - 300.0 / (75.0 + 59625f64.sqrt())).abs() < 1e-12 && (dt_u - 1.0).abs() < 1e-12);
    for seed in 1..=3 {
        for t_end in [150.0, 3000.0] {
            // Stable: below the limit for every attached count, and inside the open range
            // with a clear margin (the period-2 mode decays by more than 2 % per step).
            for dt in [0.5, 0.999 * dt_s, 1.001 * dt_s, 0.95, 0.97] {
                let s = fig1_at(dt, t_end, seed, &[]);
                assert_ne!(s.regime, Regime::Unstable, "dt = {dt}, seed {seed}, t_end {t_end}: {:?}", s.stability);
                assert_eq!(cause(&s), None);
                let n = s.stability.as_ref().unwrap();
                assert!(n.locked_amplitude.unwrap() < 8.0 * s.oscillation.junction_noise, "dt = {dt}: {n:?}");
            }
            // Seen: the scheme's own oscillation grows and stays.
            for dt in [0.98, 0.99, 0.999 * dt_u] {
                let s = fig1_at(dt, t_end, seed, &[]);
                assert_eq!((s.regime, cause(&s)), (Regime::Unstable, Some(Cause::Seen)), "dt = {dt}, seed {seed}");
                assert_eq!(s.stick_slip_cycles, 0);
            }
            // Predicted: at and beyond the limit.
            for dt in [dt_u, 1.001 * dt_u, 1.05] {
                let s = fig1_at(dt, t_end.min(300.0), seed, &[]);
                assert_eq!((s.regime, cause(&s)), (Regime::Unstable, Some(Cause::Predicted)), "dt = {dt}");
                let n = s.stability.unwrap();
                assert!(n.growth_factor > Some(1.0) && (n.largest_stable_dt.unwrap() - dt_s).abs() < 1e-15, "{n:?}");
            }
        }
    }
}

/// Where the attached count barely changes the plate (`kappa N = 0.03` against `K = 150`),
/// the limit is sharp: just below it a run keeps its regime, just above it is unstable. The
/// same for the overdamped plate (`M = 0`) and velocity Verlet, each at its own limit.
#[test]
fn sharp_limits_separate_stable_and_unstable_steps() {
    let cases: [&[&str]; 3] = [
        &["junctions.kappa=1e-4"],
        &["junctions.kappa=1e-4", "plate.mass=0"],
        &["junctions.kappa=1e-4", "fixed.integrator=velocity-verlet"],
    ];
    for extra in cases {
        let r = *analyse(&fig1_with(extra)).selected();
        assert!(r.dt_unstable / r.dt_stable - 1.0 < 1e-3, "{extra:?}: {r:?}");
        for seed in 1..=2 {
            let below = fig1_at(0.99 * r.dt_stable, 300.0, seed, extra);
            assert_ne!(below.regime, Regime::Unstable, "{extra:?}");
            assert_eq!(cause(&below), None, "{extra:?}");
            let above = fig1_at(1.01 * r.dt_unstable, 300.0, seed, extra);
            assert_eq!((above.regime, cause(&above)), (Regime::Unstable, Some(Cause::Predicted)), "{extra:?}");
            let n = above.stability.unwrap();
            assert_eq!(n.largest_stable_dt, Some(r.dt_stable));
            assert!(n.growth_factor > Some(1.0), "{n:?}");
        }
    }
}

/// The exact engine has no step: on Fig. 1 (whose fixed step at `dt = 1` is unstable) and on
/// a scene whose fixed step would blow up at once, it reports a physical regime and no
/// stability block.
#[test]
fn the_exact_engine_is_never_unstable() {
    for extra in [&[][..], &["fixed.dt=5"][..]] {
        let mut o = vec!["run.engine=exact", "run.t_end=300", "run.t_warmup=50", "output.trace=false"];
        o.extend_from_slice(extra);
        let s = run_scene(&fig1_with(&o), None).unwrap();
        assert_ne!(s.regime, Regime::Unstable);
        assert!(s.stability.is_none());
    }
    // A kinematic plate has no plate step to fail either.
    let s = run_scene(&fig1_with(&["plate.kinematic=true", "output.trace=false"]), None).unwrap();
    assert!(s.stability.is_none() && s.regime != Regime::Unstable);
}

/// A fixed-step plate without stiffness (`K + kappa N = 0`) and without mass is stable at
/// every step: its `largest_stable_dt` is infinite, and `summary.json`, which holds finite
/// numbers only, leaves it out (`null` would not read back into a summary, and a sweep of
/// such a scene could not journal its runs). So does a subnormal mass, whose growth factor
/// is not a number. (Forces near `1e200`, whose period-2 component's squares would overflow,
/// stop the run as a divergence first: `a_force_beyond_the_divergence_limit_stops_the_run`.)
#[test]
fn summary_json_leaves_out_stability_numbers_that_are_not_finite() {
    let no_stiffness = ["plate.k=0", "junctions.kappa=0"];
    for (extra, dt_absent, growth_absent, amplitude_absent) in [
        (&[&no_stiffness[..], &["plate.mass=0"]].concat(), true, false, false),
        (&[&no_stiffness[..], &["plate.eta=0"]].concat(), true, false, false),
        (&[&no_stiffness[..], &["plate.mass=1e-310"]].concat(), false, true, false),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let summary = run_scene(&fig1_with(extra), Some(dir.path())).unwrap_or_else(|e| panic!("{extra:?}: {e}"));
        let text = std::fs::read_to_string(dir.path().join("summary.json")).unwrap();
        assert!(!text.contains("null"), "{extra:?}: {text}");
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        let st = &json["stability"];
        assert_eq!(st.get("largest_stable_dt").is_none(), dt_absent, "{extra:?}: {st}");
        assert_eq!(st.get("growth_factor").is_none(), growth_absent, "{extra:?}: {st}");
        assert_eq!(st.get("locked_amplitude").is_none(), amplitude_absent, "{extra:?}: {st}");
        let back: Summary = serde_json::from_str(&text).unwrap();
        assert_eq!(back, summary, "{extra:?}: summary.json reads back as it was");
    }
    // A sweep journals such runs.
    let dir = tempfile::tempdir().unwrap();
    let o = stickslip(
        &[
            "sweep",
            &scenario("fig1.toml"),
            "--param",
            "plate.v",
            "--values",
            "0.5,1",
            "--set",
            "plate.k=0",
            "--set",
            "junctions.kappa=0",
            "--set",
            "plate.mass=0",
            "--out",
            "sw",
        ],
        dir.path(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.path().join("sw/sweep.csv").is_file());
}

/// The README's first command: summary.json says unstable, with the growth factor and the
/// largest stable step, so does the summary line, and trace.svg is drawn.
#[test]
fn the_first_command_is_unstable_and_draws_its_trace() {
    let dir = tempfile::tempdir().unwrap();
    let o = stickslip(&["run", &scenario("fig1.toml")], dir.path());
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.starts_with("warning: fixed.dt = 1 is at the stability limit"), "{stderr}");
    assert!(
        stdout.contains(
            "regime unstable (predicted: the plate step grows x1.4 per step with every junction attached; \
             largest stable dt 0.939902"
        ),
        "{stdout}"
    );
    let out = dir.path().join("out/fig1");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["regime"], "unstable");
    assert_eq!(summary["stick_slip_cycles"], 0);
    let st = &summary["stability"];
    assert_eq!(st["unstable"], "predicted");
    assert!((st["growth_factor"].as_f64().unwrap() - 1.4).abs() < 1e-12, "{st}");
    assert!((st["largest_stable_dt"].as_f64().unwrap() - 300.0 / (75.0 + 59625f64.sqrt())).abs() < 1e-12, "{st}");
    // The scheme's period-2 oscillation is seen too: locked over the whole run.
    assert!(st["locked_steps"].as_u64().unwrap() >= 140, "{st}");
    assert!(out.join("trace.csv").is_file());
    let svg = std::fs::read_to_string(out.join("trace.svg")).expect("trace.svg is drawn");
    assert_well_formed_svg(&svg);
    assert!(svg.contains("fig1"), "the plot names its scene");

    // The exact engine's command: a physical regime, its picture too.
    let o = stickslip(&["run", &scenario("fig1-exact.toml"), "--set", "run.t_end=300"], dir.path());
    assert!(o.status.success() && o.stderr.is_empty(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("regime smooth"));
    assert_well_formed_svg(&std::fs::read_to_string(dir.path().join("out/fig1-exact/trace.svg")).unwrap());
    // Without a trace there is no picture, and no refusal.
    let o = stickslip(&["run", &scenario("fig1.toml"), "--set", "output.trace=false", "--out", "bare"], dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!dir.path().join("bare/trace.svg").exists() && dir.path().join("bare/summary.json").exists());
}

/// `sweep.csv` and `runs.csv` say `unstable` for such steps, the other steps keep their
/// regime; both plots mark them.
#[test]
fn sweeps_mark_unstable_steps() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scenario("fig1.toml");
    let o = stickslip(
        &["sweep", &scene, "--param", "fixed.dt", "--values", "0.5,0.99,1", "--replicas", "2", "--out", "one"],
        dir.path(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let regimes = |file: &str| -> Vec<(String, String)> {
        let text = std::fs::read_to_string(dir.path().join("one").join(file)).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = header.iter().position(|h| *h == "regime").unwrap();
        lines.map(|l| l.split(',').collect::<Vec<_>>()).map(|r| (r[0].to_string(), r[col].to_string())).collect()
    };
    let rows = regimes("sweep.csv");
    assert_eq!(rows.len(), 3);
    assert_ne!(rows[0].1, "unstable", "{rows:?}");
    assert_eq!((rows[1].1.as_str(), rows[2].1.as_str()), ("unstable", "unstable"), "{rows:?}");
    let runs = regimes("runs.csv");
    assert_eq!(runs.iter().filter(|r| r.1 == "unstable").count(), 4, "{runs:?}");
    let svg = std::fs::read_to_string(dir.path().join("one/sweep.svg")).unwrap();
    assert_well_formed_svg(&svg);
    assert!(svg.contains("\nUN\n</text>"), "the unstable band is labelled");

    let o = stickslip(
        &[
            "sweep",
            &scene,
            "--param",
            "fixed.dt",
            "--values",
            "0.5,1",
            "--param",
            "plate.v",
            "--values",
            "0.5,1",
            "--replicas",
            "1",
            "--out",
            "map",
        ],
        dir.path(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let svg = std::fs::read_to_string(dir.path().join("map/sweep.svg")).unwrap();
    assert_well_formed_svg(&svg);
    assert_eq!(svg.matches("\nUN\n</text>").count(), 2, "two unstable cells");
}

/// `compare` calls a step unstable exactly when its runs are: the letter's step, not the
/// stable one.
#[test]
fn compare_uses_the_run_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let o = stickslip(
        &[
            "compare",
            &scenario("fig1.toml"),
            "--dts",
            "1,0.5",
            "--replicas",
            "2",
            "--ref-replicas",
            "2",
            "--set",
            "run.t_end=60",
            "--out",
            "c",
        ],
        dir.path(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(dir.path().join("c/compare.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let (dt, status) =
        (header.iter().position(|h| *h == "dt").unwrap(), header.iter().position(|h| *h == "status").unwrap());
    let fixed: Vec<(String, String)> = lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|r| r[0] == "fixed")
        .map(|r| (r[dt].to_string(), r[status].to_string()))
        .collect();
    assert_eq!(fixed, [("1.0".to_string(), "unstable".to_string()), ("0.5".into(), "ok".into())], "{text}");
}
