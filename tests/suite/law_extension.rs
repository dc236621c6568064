//! A force law defined outside the crate runs on both engines through their public generic
//! entry points (`FixedEngine::new`, `ExactDirect::new`): what docs/engines.md, "Adding a
//! force law" promises. Checks:
//!
//! - the worked example's file is `law_extension/saturating.rs` word for word, and its table
//!   line is the crate's law table plus one line of the same form; an ignored test
//!   (`a_newcomer_adds_the_worked_example`) takes those two steps on a copy of the crate and
//!   runs a `force_law = "saturating"` scene on both engines through the command line;
//! - `Saturating` (`f^x = kappa l0 tanh(x / l0)`, the worked example) passes the crate's law
//!   checks (`physics::force::check_law`) and tends to the linear law as `l0 -> inf`;
//! - `Hooke`, a copy of the linear law written here, gives on the fixed engine bit for bit the
//!   trajectory of the crate's own `Linear`, strong and weak bonds;
//! - on the exact engine's direct method (DOP853 on the summed force) `Hooke` gives the
//!   crate's `Linear` trajectory bit for bit, and agrees in distribution with the
//!   closed-form linear engine (Welch's test on the window-mean friction over seeds);
//! - with strong bonds and `g = 1` (`V0` beyond any speed) every junction is an independent
//!   two-state chain, so from a stationary start the attached count at any time is
//!   Binomial(N, kon0/(kon0+k0)) whatever the law: `Saturating` on both engines, pooled over
//!   seeds, within the binomial's 99.99% two-sided normal interval.

use crate::common;

use serde::{Deserialize, Serialize};
use stickslip::Scene;
use stickslip::engine::Engine;
use stickslip::engine::exact::ExactDirect;
use stickslip::engine::fixed::{FixedEngine, LinearFlip};
use stickslip::observe::{EventKind, Nothing, Recorder, Sample};
use stickslip::physics::force::{check_kappa, check_law};
use stickslip::physics::{Bond, Direct, ForceLaw, LawParams, Linear, ParamError, Strong, Weak};
use stickslip::rng::ParkMiller;
use stickslip_testkit::fig1_with;

/// The worked example of docs/engines.md, "Adding a force law": the file a newcomer writes,
/// word for word (`the_worked_example_is_this_file` checks it against the doc).
mod saturating;

use saturating::Saturating;

/// The linear law, written outside the crate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct Hooke {
    kappa: f64,
}

impl ForceLaw for Hooke {
    const NAME: &'static str = "hooke";
    const IS_LINEAR: bool = true;
    const STIFFNESS_NOTE: &'static str = "each junction adds kappa";
    type Exact = Direct;

    fn new(p: &LawParams) -> Result<Self, ParamError> {
        Ok(Hooke { kappa: p.kappa })
    }
    fn tension(&self, x: f64) -> f64 {
        self.kappa * x.abs()
    }
    fn force_x(&self, x: f64) -> f64 {
        self.kappa * x
    }
    fn stiffness_x(&self, _x: f64) -> f64 {
        self.kappa
    }
    fn thinning_slope(&self) -> f64 {
        self.kappa
    }
    fn stiffness_range(&self) -> (f64, f64) {
        (self.kappa, self.kappa)
    }
}

fn scene(overrides: &[&str]) -> Scene {
    fig1_with(overrides)
}

/// The engine's samples at `t = 1, 2, ..., t_end` and every event on the way.
fn drive<E: Engine>(mut e: E, t_end: f64) -> (Vec<Sample>, Recorder) {
    let mut rec = Recorder::default();
    let mut samples = vec![e.sample()];
    let mut t = 1.0;
    while t <= t_end {
        e.advance(t, &mut rec).unwrap_or_else(|err| panic!("{}: {err}", std::any::type_name::<E>()));
        samples.push(e.sample());
        t += 1.0;
    }
    (samples, rec)
}

#[test]
fn saturating_law_passes_the_law_checks() {
    let xs: Vec<f64> = (-40..=40).map(|i| 0.37 * i as f64).chain([1e-9, -1e-12, 300.0]).collect();
    for l0 in [0.5, 1.0, 7.0] {
        check_law(&Saturating { kappa: 0.1, l0 }, &xs).unwrap();
    }
    check_law(&Hooke { kappa: 0.1 }, &xs).unwrap();
    // l0 -> inf: kappa l0 tanh(x/l0) = kappa x (1 - (x/l0)^2/3 + ...).
    let big = Saturating { kappa: 0.1, l0: 1e4 };
    for &x in &xs[..81] {
        let rel = (big.force_x(x) - 0.1 * x).abs() / (0.1 * x.abs()).max(1e-300);
        assert!(rel <= (x / 1e4).powi(2) / 3.0 + 1e-15, "x = {x}: relative gap {rel}");
    }
}

/// `Hooke` on the fixed engine: the crate's `Linear` trajectory bit for bit (same code path,
/// `IS_LINEAR`), strong and weak bonds.
#[test]
fn fixed_engine_runs_an_outside_law_like_the_crates_own() {
    for bond in ["strong", "weak"] {
        let s = scene(&["junctions.force_law=linear", &format!("junctions.bond={bond}"), "run.t_end=60"]);
        let kappa = s.junctions.kappa;
        let run = |law_is_ours: bool| {
            let rng = ParkMiller::new(s.run.seed).unwrap();
            let (weak, strong) = (Weak::from_scene(&s), Strong::from_scene(&s));
            match (law_is_ours, bond == "weak") {
                (true, true) => drive(FixedEngine::new(&s, Hooke { kappa }, weak, rng, LinearFlip), 60.0),
                (true, false) => drive(FixedEngine::new(&s, Hooke { kappa }, strong, rng, LinearFlip), 60.0),
                (false, true) => drive(FixedEngine::new(&s, Linear { kappa }, weak, rng, LinearFlip), 60.0),
                (false, false) => drive(FixedEngine::new(&s, Linear { kappa }, strong, rng, LinearFlip), 60.0),
            }
        };
        let (ours, ours_rec) = run(true);
        let (crate_law, crate_rec) = run(false);
        assert_eq!(ours, crate_law, "{bond}");
        assert_eq!(ours_rec.events, crate_rec.events, "{bond}");
        assert!(ours_rec.events.len() > 100, "{bond}: too few events to test anything");
    }
}

/// `Hooke` and the crate's `Linear` on the direct exact engine: the same trajectory bit for
/// bit (the engine sees a law only through the trait), weak bonds (hazard integration).
#[test]
fn direct_exact_engine_runs_an_outside_law_like_the_crates_own() {
    let s = scene(&["run.engine=exact", "junctions.force_law=linear", "junctions.bond=weak", "run.t_end=30"]);
    let kappa = s.junctions.kappa;
    let (ours, ours_rec) = drive(ExactDirect::new(&s, Hooke { kappa }, Weak::from_scene(&s)).unwrap(), 30.0);
    let (theirs, theirs_rec) = drive(ExactDirect::new(&s, Linear { kappa }, Weak::from_scene(&s)).unwrap(), 30.0);
    assert_eq!(ours, theirs);
    assert_eq!(ours_rec.events, theirs_rec.events);
    assert!(ours_rec.events.len() > 100, "too few events to test anything");
}

/// Time average of the friction over `[t_lo, t_end]` on a grid of `h` (trapezoid rule): the
/// same estimator for both engines, so equal expectations when the processes agree.
fn mean_friction<E: Engine>(mut e: E, t_lo: f64, t_end: f64, h: f64) -> f64 {
    let steps = ((t_end - t_lo) / h).round() as usize;
    e.advance(t_lo, &mut Nothing).unwrap();
    let mut last = e.sample().friction;
    let mut sum = 0.0;
    for i in 1..=steps {
        e.advance(t_lo + i as f64 * h, &mut Nothing).unwrap();
        let f = e.sample().friction;
        sum += 0.5 * (last + f);
        last = f;
    }
    sum / steps as f64
}

/// `Hooke` on the direct engine (DOP853 on the summed force, the engine every new law gets)
/// against the closed-form engine the scene selects for the linear law: the same process, so
/// the replica means of the window-averaged friction agree. Welch's test at `alpha = 1e-3`,
/// 40 independent seeds per engine; the test must be able to see a 5% difference.
#[test]
fn direct_exact_engine_on_an_outside_law_agrees_with_the_closed_form_engine() {
    let (n, t_lo, t_end) = (150, 20.0, 220.0);
    let base = |seed: u64| {
        scene(&[
            "run.engine=exact",
            "junctions.force_law=linear",
            "junctions.initial=stationary",
            &format!("junctions.n={n}"),
            &format!("plate.k={}", 0.5 * n as f64),
            &format!("plate.mass={}", 0.25 * n as f64),
            &format!("plate.eta={}", 0.25 * n as f64),
            &format!("run.t_end={t_end}"),
            &format!("run.seed={seed}"),
        ])
    };
    let (mut direct, mut closed) = (Vec::new(), Vec::new());
    for seed in 1..=40u64 {
        let s = base(seed);
        let e = ExactDirect::new(&s, Hooke { kappa: s.junctions.kappa }, Strong::from_scene(&s)).unwrap();
        direct.push(mean_friction(e, t_lo, t_end, 0.5));
        // A seed range of its own: the two samples are independent.
        let s = base(1000 + seed);
        let e = stickslip::engine::exact::strong_linear::<stickslip::engine::exact::DefaultQueue>(&s);
        closed.push(mean_friction(e, t_lo, t_end, 0.5));
    }
    let w = common::welch(&direct, &closed, 1e-3);
    let mean = closed.iter().sum::<f64>() / closed.len() as f64;
    eprintln!("direct - closed form = {} (se {}), mean {mean}, detectable {}", w.diff, w.se, w.detectable(0.9));
    assert!(!w.rejects(), "direct {} vs closed form {}: diff {} > {} se", mean + w.diff, mean, w.diff, w.critical);
    assert!(w.detectable(0.9) < 0.05 * mean.abs(), "too weak: detects only {} of {mean}", w.detectable(0.9));
}

/// Attached count at `t_end` of `runs` independent runs, pooled: Binomial(N runs, p) with
/// `p = kon0 / (kon0 + k0)` for any law when rates do not depend on the plate.
fn pooled_attached(runs: u64, engine: &str) -> (u64, u64, f64) {
    let mut attached = 0;
    let mut trials = 0;
    let mut p = 0.0;
    for seed in 1..=runs {
        let s = scene(&[
            &format!("run.engine={engine}"),
            "junctions.initial=stationary",
            "junctions.alpha=1e6",
            "junctions.n=100",
            "junctions.kon0=0.3",
            "run.t_end=15",
            "fixed.rng=pcg",
            "fixed.dt=0.25",
            &format!("run.seed={seed}"),
        ]);
        let j = &s.junctions;
        p = j.kon0 / (j.kon0 + j.k0);
        let law = Saturating::new(&LawParams { kappa: j.kappa, l0: j.l0 }).unwrap();
        let bond = Strong::new(&stickslip::scene::laws::bond_params(j)).unwrap();
        let last = if engine == "fixed" {
            let rng = stickslip::rng::pcg(s.run.seed);
            let mut e = FixedEngine::new(&s, law, bond, rng, LinearFlip);
            e.advance(s.run.t_end, &mut Nothing).unwrap();
            e.sample()
        } else {
            let mut e = ExactDirect::new(&s, law, bond).unwrap();
            e.advance(s.run.t_end, &mut Nothing).unwrap();
            e.sample()
        };
        attached += last.attached;
        trials += last.n;
    }
    (attached, trials, p)
}

/// Strong bonds with `g = 1`: junctions are independent two-state chains (continuous time on
/// the exact engine; on the fixed engine a chain with flip probabilities `kon0 dt`, `k0 dt`,
/// whose stationary law is the same `p`), started stationary: the pooled count is
/// Binomial(trials, p). Two-sided 99.99% normal interval, `z = 3.8906`.
#[test]
fn stationary_attachment_is_binomial_for_an_outside_law_on_both_engines() {
    for (engine, runs) in [("fixed", 60), ("exact", 40)] {
        let (k, n, p) = pooled_attached(runs, engine);
        let mean = n as f64 * p;
        let sd = (n as f64 * p * (1.0 - p)).sqrt();
        let z = (k as f64 - mean) / sd;
        assert!(z.abs() <= 3.8906, "{engine}: {k} attached of {n}, expected {mean:.1} +- {sd:.1} (z = {z:.2})");
    }
}

/// The event records carry the law's own tension: a rupture's tension is `f(x)` of the
/// `Saturating` law at its extension.
#[test]
fn events_report_the_outside_laws_tension() {
    let s = scene(&["run.engine=exact", "run.t_end=30"]);
    let law = Saturating { kappa: s.junctions.kappa, l0: s.junctions.l0 };
    let e = ExactDirect::new(&s, law, Strong::from_scene(&s)).unwrap();
    let (_, rec) = drive(e, 30.0);
    let ruptures: Vec<_> = rec.events.iter().filter(|e| e.kind == EventKind::Rupture).collect();
    assert!(ruptures.len() > 50, "too few ruptures to test anything");
    for r in ruptures {
        assert_eq!(r.tension, law.tension(r.extension), "{r:?}");
    }
}

// ---------------------------------------------------------------------------------------
// The worked example of docs/engines.md, step by step.

/// The repository root.
fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The `n`-th fenced rust block of docs/engines.md after `marker`.
fn doc_block(marker: &str, n: usize) -> String {
    let doc = read("docs/engines.md");
    let mut at = doc.find(marker).unwrap_or_else(|| panic!("docs/engines.md: no {marker:?}"));
    let mut block = String::new();
    for _ in 0..=n {
        let start = doc[at..].find("```rust\n").expect("a rust block") + at + "```rust\n".len();
        let end = doc[start..].find("```\n").expect("its end") + start;
        block = doc[start..end].to_string();
        at = end + 4;
    }
    block
}

const STEPS: &str = "### Adding a force law";

/// Step 1, the law's file: the doc's block is `law_extension/saturating.rs`, which the tests
/// of this module compile and run.
#[test]
fn the_worked_example_is_this_file() {
    assert_eq!(doc_block(STEPS, 0), read("tests/suite/law_extension/saturating.rs"));
}

/// The crate's law table (the `force_laws!` invocation of src/physics/force/mod.rs).
fn crate_table() -> String {
    let src = read("src/physics/force/mod.rs");
    let start = src.find("\nforce_laws! {\n").expect("the law table") + 1;
    let end = src[start..].find("\n}\n").expect("its end") + start + 3;
    src[start..end].to_string()
}

/// Step 2, the table line: the doc's table is the crate's with the new line (and its doc
/// comment) added before the closing brace, in the table's form `Variant => file::Type,`.
fn table_with_the_new_line() -> (String, String) {
    let table = crate_table();
    let doc = doc_block(STEPS, 1);
    let added: Vec<&str> = doc.lines().filter(|l| !table.lines().any(|t| t == *l)).collect();
    assert_eq!(added.len(), 2, "the doc's table adds {added:?} to the crate's");
    assert_eq!(added[1].trim(), "Saturating => saturating::Saturating,   // the new line");
    let line = added[1].split("//").next().unwrap().trim_end().to_string();
    let expected = table.replacen("\n}", &format!("\n{}\n{line}\n}}", added[0]), 1);
    let doc_without_comment = doc.replace("   // the new line", "");
    assert_eq!(doc_without_comment, expected, "the doc's table is not the crate's plus one line");
    (expected, doc_without_comment)
}

#[test]
fn the_worked_example_adds_one_line_to_the_crates_table() {
    table_with_the_new_line();
}

/// Copies what `cargo` needs to build the crate (no `target/`, no `.git`).
fn copy_crate(from: &std::path::Path, to: &std::path::Path) {
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if name == "target" || name.starts_with('.') {
            continue;
        }
        let (src, dst) = (entry.path(), to.join(&*name));
        if entry.file_type().unwrap().is_dir() {
            std::fs::create_dir_all(&dst).unwrap();
            copy_crate(&src, &dst);
        } else {
            std::fs::copy(&src, &dst).unwrap();
        }
    }
}

/// The two steps of the worked example on a copy of the crate, then a `saturating` scene
/// through `stickslip validate`, `stickslip stability` and `stickslip run` on both engines.
/// Builds the copy (some minutes on two cores; in `CARGO_TARGET_DIR` if set, sharing its
/// built dependencies): `cargo test --profile quick --test suite
/// law_extension::a_newcomer -- --ignored`.
#[test]
#[ignore]
fn a_newcomer_adds_the_worked_example() {
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path();
    copy_crate(&root(), copy);
    // The new file (named in two parts: it exists only in the copy).
    std::fs::write(copy.join("src/physics/force").join("saturating.rs"), doc_block(STEPS, 0)).unwrap();
    let (table, _) = table_with_the_new_line();
    let force = copy.join("src/physics/force/mod.rs");
    let src = std::fs::read_to_string(&force).unwrap().replacen(&crate_table(), &table, 1);
    std::fs::write(&force, src).unwrap();
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| copy.join("target"), Into::into);
    let stickslip = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO"))
            .current_dir(copy)
            .env("CARGO_TARGET_DIR", &target)
            .args(["run", "--quiet", "--profile", "quick", "--offline", "--"])
            .args(args)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(out.status.success(), "stickslip {args:?} failed: {}{text}", String::from_utf8_lossy(&out.stderr));
        text
    };
    let law = ["--set", "junctions.force_law=saturating"];
    let validated = stickslip(&[&["validate", "scenarios/fig1.toml"][..], &law].concat());
    assert!(validated.contains("saturating"), "validate does not name the law: {validated}");
    let table = stickslip(&[&["stability", "scenarios/fig1.toml"][..], &law].concat());
    assert!(table.contains("a yielding junction's stiffness never exceeds kappa"), "{table}");
    for engine in ["fixed", "exact"] {
        let out = copy.join(format!("out-{engine}"));
        let engine_set = format!("run.engine={engine}");
        let args = [&["run", "scenarios/fig1.toml"][..], &law, &["--set", &engine_set, "--set", "run.t_end=40"]];
        stickslip(&[&args.concat()[..], &["--out", out.to_str().unwrap()]].concat());
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
        let ruptures = summary["ruptures"].as_u64();
        assert!(ruptures.is_some_and(|r| r > 10), "{engine}: {summary}");
    }
}
