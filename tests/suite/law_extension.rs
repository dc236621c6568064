//! A force law defined outside the crate, in this one file, runs on both engines through
//! their public generic entry points (`FixedEngine::new`, `ExactDirect::new`): what
//! docs/engines.md, "Adding a force law" promises. Checks:
//!
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
use stickslip::physics::force::check_law;
use stickslip::physics::{Bond, ForceLaw, LawParams, Linear, ParamError, Strong, Weak};
use stickslip::rng::ParkMiller;
use stickslip_testkit::fig1_with;

/// The worked example of docs/engines.md: a junction that yields, `f^x = kappa l0 tanh(x/l0)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct Saturating {
    kappa: f64,
    l0: f64,
}

impl ForceLaw for Saturating {
    const NAME: &'static str = "saturating";
    const STIFFNESS_NOTE: &'static str = "a yielding junction's stiffness never exceeds kappa";

    fn new(p: &LawParams) -> Result<Self, ParamError> {
        Ok(Saturating { kappa: p.kappa, l0: p.l0 })
    }
    fn tension(&self, x: f64) -> f64 {
        self.force_x(x).abs()
    }
    fn force_x(&self, x: f64) -> f64 {
        self.kappa * self.l0 * (x / self.l0).tanh()
    }
    /// `kappa / cosh^2(x/l0)`.
    fn stiffness_x(&self, x: f64) -> f64 {
        let c = (x / self.l0).cosh();
        self.kappa / (c * c)
    }
    /// `|tanh u| <= |u|`.
    fn thinning_slope(&self) -> f64 {
        self.kappa
    }
    fn stiffness_range(&self) -> (f64, f64) {
        (0.0, self.kappa)
    }
}

/// The linear law, written outside the crate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct Hooke {
    kappa: f64,
}

impl ForceLaw for Hooke {
    const NAME: &'static str = "hooke";
    const IS_LINEAR: bool = true;
    const STIFFNESS_NOTE: &'static str = "each junction adds kappa";

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
