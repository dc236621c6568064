//! Weak bonds at a kinematic drive against their renewal theory (docs/model.md, "Weak bonds
//! at a kinematic drive: renewal theory"; reference in `tests/suite/common/renewal.rs`).
//!
//! Each engine run is one replica; `R` replicas with independent seeds give a Student-t
//! interval at level `1 - ALPHA` for the time averages of `summary.json`
//! (`attached_fraction_mean`, and `bond_force_mean / N`, the time average of `q f^x` per
//! junction, which for the `linear` law at `V > 0` is also the mean tension). A test passes
//! when the reference lies within the interval's half-width plus the reference's own error
//! bound. Run with `cargo test --release --test suite renewal::`.
//!
//! The start (all detached, `x = 0`) is a renewal point of every junction, and the window
//! starts after `T_WARMUP = 400`, more than 20 mean cycles: the transient of the expectation
//! decays at least like the detached phase's `exp(-kon t)` mixing (`kon t_w > 30` here), far
//! below the statistical resolution.

use crate::common;

use common::renewal::{Bounded, Renewal, linear_closed_form};
use common::*;
use stickslip::run_scene;
use stickslip_testkit::scene;

pub(crate) const KAPPA: f64 = 0.1;
pub(crate) const K0: f64 = 0.1;
pub(crate) const KON0: f64 = 0.1;
/// Above `V0 = alpha / tau0 = 0.5`, so formation runs at `kon0 g(V)`, `g < 1`.
pub(crate) const V: f64 = 0.8;
pub(crate) const V0: f64 = 0.5;
const L0: f64 = 1.0;
const T_WARMUP: f64 = 400.0;
const T_END: f64 = 2400.0;
pub(crate) const REPLICAS: u64 = 10;

pub(crate) const SCENE: &str = r#"
[junctions]
n = 1000
bond = "weak"
force_law = "linear"
kappa = 0.1
k0 = 0.1
kon0 = 0.1
dx = 1.0
l0 = 1.0
temperature = 1.0
initial = "detached"
reattach = "unstretched"
tau0 = 2.0
alpha = 1.0
[plate]
kinematic = true
v = 0.8
[run]
engine = "exact"
t_warmup = 400.0
t_end = 2400.0
[fixed]
rng = "pcg"
[output]
trace = false
"#;

fn kon() -> f64 {
    KON0 * (std::f64::consts::FRAC_PI_2 * V0 / V).sin()
}

fn linear_tension(x: f64) -> f64 {
    KAPPA * x.abs()
}
fn linear_force_x(x: f64) -> f64 {
    KAPPA * x
}
fn tilted_tension(x: f64) -> f64 {
    KAPPA * (x.hypot(L0) - L0)
}
fn tilted_force_x(x: f64) -> f64 {
    tilted_tension(x) * x / x.hypot(L0)
}

/// A force law's `(f, f^x)` as plain functions.
type Law = Renewal<fn(f64) -> f64, fn(f64) -> f64>;

fn linear() -> Law {
    Renewal { k0: K0, beta_dx: 1.0, v: V, kon: kon(), tension: linear_tension, force_x: linear_force_x }
}
fn tilted() -> Law {
    Renewal { k0: K0, beta_dx: 1.0, v: V, kon: kon(), tension: tilted_tension, force_x: tilted_force_x }
}

/// `(attached fraction, bond force per junction)` of `R` replicas of the scene.
fn replicas(overrides: &[&str]) -> (Vec<f64>, Vec<f64>) {
    let (mut n, mut f) = (Vec::new(), Vec::new());
    for r in 0..REPLICAS {
        let mut s = scene(SCENE, overrides);
        assert_eq!((s.run.t_warmup, s.run.t_end), (T_WARMUP, T_END));
        s.run.seed = 1000 + r;
        let sum = run_scene(&s, None).unwrap_or_else(|e| panic!("{overrides:?}: {e}"));
        let rel = (sum.friction_mean - sum.bond_force_mean).abs() / sum.bond_force_mean.abs();
        assert!(rel < 1e-12, "kinematic: friction is F_b ({} vs {})", sum.friction_mean, sum.bond_force_mean);
        assert_eq!(sum.viscous_force_mean, 0.0);
        n.push(sum.attached_fraction_mean);
        f.push(sum.bond_force_mean / s.junctions.n as f64);
    }
    (n, f)
}

/// `|mean - reference| <= t half-width + reference error`.
pub(crate) fn check(what: &str, x: &[f64], reference: Bounded) {
    let (m, hw) = mean_ci(x, ALPHA);
    let tol = hw + reference.error;
    eprintln!("{what}: replicas {m:.6} +- {hw:.2e}, reference {:.6} +- {:.2e}", reference.value, reference.error);
    assert!(
        (m - reference.value).abs() <= tol,
        "{what}: replicas {m:.6} +- {hw:.2e}, reference {:.6} +- {:.2e}",
        reference.value,
        reference.error
    );
    // The test must be able to fail: its tolerance is a small fraction of the value.
    assert!(tol < 0.02 * reference.value.abs(), "{what}: tolerance {tol:.2e} too wide to test anything");
}

#[test]
fn quadrature_matches_the_gompertz_closed_forms() {
    for (k0, v) in [(K0, V), (0.05, 0.5), (0.3, 2.0)] {
        let r = Renewal { k0, v, ..linear() };
        let q = r.integrals(KAPPA * v);
        let (ta, f) = linear_closed_form(k0, 1.0, KAPPA, v);
        // The closed forms carry ~1e-13 relative round-off (series with cancellation).
        for (name, got, want) in [("E[T_a]", q.ta, ta), ("int f S", q.f, f)] {
            let err = (got.value - want).abs();
            assert!(
                err <= got.error + 1e-12 * want,
                "k0 = {k0}, V = {v}: {name} {} vs {want} (bound {:.1e})",
                got.value,
                got.error
            );
            assert!(got.error < 1e-9 * want, "{name}: bound {:.1e} not useful", got.error);
        }
        // Linear law at V > 0: f^x = f.
        assert_eq!(q.f.value, q.fx.value);
    }
    // Known values: E_1(1) = 0.21938393439552029 (Abramowitz & Stegun 5.1).
    assert!((common::renewal::exp_int_e1(1.0) - 0.219_383_934_395_520_3).abs() < 1e-14);
}

#[test]
fn tilted_quadrature_has_a_small_bound_and_is_below_the_linear_tension() {
    let t = tilted().integrals(KAPPA * V);
    let l = linear().integrals(KAPPA * V);
    for b in [t.ta, t.f, t.fx] {
        assert!(b.error < 1e-9 * b.value, "{b:?}");
    }
    // f_tilted < f_linear: bonds live longer, and f^x < f.
    assert!(t.ta.value > l.ta.value);
    assert!(t.fx.value < t.f.value);
}

#[test]
fn fixed_step_reference_converges_to_the_continuous_one_at_first_order() {
    let rule = |p: f64| p.min(1.0);
    for (name, theory) in [("linear", linear().integrals(KAPPA * V)), ("tilted", tilted().integrals(KAPPA * V))] {
        let errors: Vec<[f64; 3]> = [0.1, 0.05, 0.025]
            .iter()
            .map(|&dt| {
                let d = if name == "linear" { linear().discrete(dt, rule) } else { tilted().discrete(dt, rule) };
                [
                    d.attached_fraction - theory.attached_fraction().value,
                    d.mean_tension - theory.mean_tension().value,
                    d.mean_force_x - theory.mean_force_x().value,
                ]
            })
            .collect();
        for q in 0..3 {
            // First order: halving dt halves the bias, up to O(dt^2).
            for w in errors.windows(2) {
                let ratio = w[1][q] / w[0][q];
                assert!((0.4..0.6).contains(&ratio), "{name}, quantity {q}: bias ratio {ratio} ({errors:?})");
            }
        }
    }
}

#[test]
fn exact_linear_engine_matches_renewal_theory() {
    let theory = linear().integrals(KAPPA * V);
    let (n, f) = replicas(&[]);
    check("attached fraction", &n, theory.attached_fraction());
    check("mean tension (= bond force, linear law)", &f, theory.mean_tension());
}

/// The tilted law's kinematic plate runs on the series engine. `N = 300` rather than
/// 1000: that engine re-bases its series every `l0/4` of plate travel at `O(N)` each, so a
/// kinematic run costs `O(N V t / l0)` beyond its events.
#[test]
fn exact_tilted_engine_matches_renewal_theory() {
    let theory = tilted().integrals(KAPPA * V);
    let (n, f) = replicas(&["junctions.force_law=tilted", "junctions.n=300"]);
    check("attached fraction", &n, theory.attached_fraction());
    check("mean bond force f^x", &f, theory.mean_force_x());
}

/// The fixed-step engine against its own discrete renewal theory (exact for the scheme at
/// this `dt`, so no bias), both laws; the distance of that reference from the continuous
/// one is the scheme's O(dt) bias, tested in
/// `fixed_step_reference_converges_to_the_continuous_one_at_first_order`.
#[test]
fn fixed_engine_matches_its_discrete_renewal_theory() {
    let dt = 0.1;
    let rule = |p: f64| p.min(1.0);
    for (law, d) in [("linear", linear().discrete(dt, rule)), ("tilted", tilted().discrete(dt, rule))] {
        let law_o = format!("junctions.force_law={law}");
        let (n, f) = replicas(&["run.engine=fixed", "fixed.dt=0.1", &law_o]);
        let exact = |v: f64| Bounded { value: v, error: 1e-12 * v.abs() };
        check(&format!("fixed {law}: attached fraction"), &n, exact(d.attached_fraction));
        check(&format!("fixed {law}: bond force"), &f, exact(d.mean_force_x));
    }
}
