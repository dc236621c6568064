//! The kinematic plate (`plate.kinematic = true`, `X = V t`) in the exact linear engine and
//! the fixed-step engine: the output convention, the single weak bond's exact survival, and
//! the strong-bond mean field of a plate moving at exactly `V` (docs/model.md, "Exact facts
//! used as checks"). Fixed seeds; tolerances are KS critical values or Student-t intervals at
//! level `ALPHA`. Run with `cargo test --release --test suite kinematic::`.

use crate::common;

use common::*;
use stickslip::observe::EventKind;
use stickslip::run_scene;
use stickslip::runner::record;
use stickslip_testkit::{events_of, scene};

/// Weak linear bonds pulled from `x = 0` by a kinematic plate, no re-formation.
const PULLED: &str = r#"
[junctions]
n = 20000
bond = "weak"
force_law = "linear"
kappa = 0.1
k0 = 0.1
kon0 = 0.0
dx = 1.0
temperature = 1.0
initial = "attached"
[plate]
kinematic = true
v = 0.5
[run]
engine = "exact"
t_end = 200.0
[fixed]
rng = "pcg"
[output]
trace = false
"#;

const K0: f64 = 0.1;
const KAPPA: f64 = 0.1;
const V: f64 = 0.5;

/// `S(t) = exp(-(k0 f_b / r)(exp(r t / f_b) - 1))`, `r = kappa V`, `f_b = 1/(beta dx) = 1`.
fn survival(t: f64) -> f64 {
    let r = KAPPA * V;
    (-(K0 / r) * ((r * t).exp() - 1.0)).exp()
}

/// Rupture times of every junction (each ruptures once: `kon0 = 0`).
fn rupture_times(overrides: &[&str]) -> Vec<f64> {
    let s = scene(PULLED, overrides);
    assert!(survival(s.run.t_end) < 1e-30, "t_end must cover the whole distribution");
    let ev = events_of(&s);
    let t: Vec<f64> = ev.iter().filter(|e| e.kind == EventKind::Rupture).map(|e| e.t).collect();
    assert_eq!(t.len(), s.junctions.n, "every junction ruptures once");
    t
}

#[test]
fn exact_engine_rupture_times_follow_the_exact_survival() {
    let mut t = rupture_times(&[]);
    let n = t.len();
    let d = ks_statistic(&mut t, |t| 1.0 - survival(t));
    let crit = ks_critical(n, ALPHA);
    eprintln!("exact engine: KS D = {d:.5}, critical {crit:.5} (n = {n})");
    assert!(d < crit, "KS D = {d:.5} >= critical {crit:.5} (n = {n})");
}

/// The same at `N = 2e5`, where the engine draws its rupture candidates from bins of
/// anchors (`BINNED_FROM`) instead of the sum tree.
#[test]
fn binned_engine_rupture_times_follow_the_exact_survival() {
    const { assert!(stickslip::engine::exact::BINNED_FROM <= 200_000) };
    let mut t = rupture_times(&["junctions.n=200000"]);
    let n = t.len();
    let d = ks_statistic(&mut t, |t| 1.0 - survival(t));
    let crit = ks_critical(n, ALPHA);
    eprintln!("exact engine, bins: KS D = {d:.5}, critical {crit:.5} (n = {n})");
    assert!(d < crit, "KS D = {d:.5} >= critical {crit:.5} (n = {n})");
}

/// The fixed-step scheme's rupture law at step `dt`: a junction attached at `x = 0` at
/// `t = 0` ruptures at step `j >= 0` (reported at `t = j dt`) with probability
/// `p_j = min(1, k(V j dt) dt)`, so `P(T <= j dt) = 1 - prod_{i<=j} (1 - p_i)`.
fn discrete_cdf(dt: f64, steps: usize) -> Vec<f64> {
    let mut surv = 1.0;
    (0..steps)
        .map(|j| {
            let k = K0 * (KAPPA * V * j as f64 * dt).exp();
            surv *= 1.0 - (k * dt).min(1.0);
            1.0 - surv
        })
        .collect()
}

/// `sup_t |G(t) - F(t)|` for a step function `G` with values `g[j]` on `[j dt, (j+1) dt)`
/// and the continuous cdf `F = 1 - S`: on each step `F` runs from `F(j dt)` to `F((j+1) dt)`.
fn sup_distance(g: &[f64], dt: f64) -> f64 {
    g.iter().enumerate().fold(0.0f64, |d, (j, &gj)| {
        let (a, b) = (1.0 - survival(j as f64 * dt), 1.0 - survival((j + 1) as f64 * dt));
        d.max((gj - a).abs()).max((gj - b).abs())
    })
}

/// With `dt` small the fixed-step scheme approaches the same law: at each `dt` its sample
/// passes the KS test against the scheme's own discrete law (exact; the continuous critical
/// value is conservative for a discrete law), and the discrete law's distance from the
/// exact survival, `D_bias(dt)`, is first order (a quarter at a quarter of the step). The
/// sample's KS distance from the exact law is within the critical value of `D_bias` (triangle
/// inequality), so it falls with `dt` as derived.
#[test]
fn fixed_engine_approaches_the_exact_survival_as_dt_falls() {
    let mut bias = Vec::new();
    for dt in [0.2, 0.05] {
        let dt_o = format!("fixed.dt={dt}");
        let t = rupture_times(&["run.engine=fixed", &dt_o]);
        let n = t.len();
        let steps = (200.0 / dt) as usize + 1;
        let mut counts = vec![0.0; steps];
        for &ti in &t {
            let j = (ti / dt).round() as usize;
            assert!((ti - j as f64 * dt).abs() < 1e-9 * dt.max(ti), "event off the step grid: {ti}");
            counts[j] += 1.0;
        }
        let mut acc = 0.0;
        let empirical: Vec<f64> = counts
            .iter()
            .map(|c| {
                acc += c;
                acc / n as f64
            })
            .collect();
        let law = discrete_cdf(dt, steps);
        let crit = ks_critical(n, ALPHA);
        let d_own = empirical.iter().zip(&law).fold(0.0f64, |d, (e, f)| d.max((e - f).abs()));
        assert!(d_own < crit, "dt = {dt}: KS against the scheme's own law D = {d_own:.5} >= {crit:.5}");
        let d_bias = sup_distance(&law, dt);
        let d_exact = sup_distance(&empirical, dt);
        eprintln!(
            "dt = {dt}: D(own law) = {d_own:.5}, D(exact law) = {d_exact:.5}, D_bias = {d_bias:.5}, crit {crit:.5}"
        );
        assert!((d_exact - d_bias).abs() < crit, "dt = {dt}: D = {d_exact:.5}, D_bias = {d_bias:.5}, crit {crit:.5}");
        bias.push(d_bias);
    }
    let ratio = bias[1] / bias[0];
    assert!((0.2..0.3).contains(&ratio), "first-order bias: D_bias ratio {ratio} for dt ratio 1/4 ({bias:?})");
}

/// Strong bonds on a plate at exactly `V`, `reattach = "residual"`: attached fraction
/// `n* = kon/(kon + k0)` and mean bond force per junction `kappa n* (V/k0)(1 + kon/lambda)`,
/// `kon = kon0 g(V)` (docs/model.md). Replicas, Student-t interval at level `1 - ALPHA`.
#[test]
fn strong_bonds_at_a_kinematic_drive_match_the_exact_mean_field() {
    for engine in ["exact", "fixed"] {
        let (mut n, mut f) = (Vec::new(), Vec::new());
        for seed in 0..10 {
            let seed_o = format!("run.seed={}", 100 + seed);
            let engine_o = format!("run.engine={engine}");
            let s = scene(
                PULLED,
                &[
                    "junctions.n=1000",
                    "junctions.bond=strong",
                    "junctions.kon0=0.1",
                    "junctions.lambda=0.1",
                    "junctions.initial=detached",
                    "plate.v=0.8",
                    "run.t_warmup=200",
                    "run.t_end=2200",
                    "fixed.dt=0.05",
                    &seed_o,
                    &engine_o,
                ],
            );
            let sum = run_scene(&s, None).unwrap();
            n.push(sum.attached_fraction_mean);
            f.push(sum.bond_force_mean / 1000.0);
        }
        let (kon, lambda, v) = (0.1 * (std::f64::consts::FRAC_PI_2 * 0.5 / 0.8).sin(), 0.1, 0.8);
        let n_star = kon / (kon + K0);
        // Mean extension of an attached junction: `a + V/k0`, where the extension at
        // attachment `a` solves `a = rho (a + V/k0)`, `rho = E[exp(-lambda T_d)] = kon/(kon + lambda)`.
        // The fixed scheme at step dt is exact in the same terms (geometric waiting times with
        // p = k dt per step give the same n*; attached extensions V j dt, j = 0..J-1, average
        // to a + V/k0 - V dt; the detached relaxation (1 - lambda dt)^I gives
        // rho_dt = kon (1 - lambda dt) / (kon + lambda - kon lambda dt)).
        let dt = if engine == "fixed" { 0.05 } else { 0.0 };
        let rho = kon * (1.0 - lambda * dt) / (kon + lambda - kon * lambda * dt);
        let f_star = KAPPA * n_star * (rho * v / (K0 * (1.0 - rho)) + v / K0 - v * dt);
        if engine == "exact" {
            assert!((f_star - KAPPA * n_star * (v / K0) * (1.0 + kon / lambda)).abs() < 1e-12);
        }
        for (what, x, want) in [("n*", &n, n_star), ("F_b / N", &f, f_star)] {
            let (m, hw) = mean_ci(x, ALPHA);
            eprintln!("{engine} {what}: {m:.5} +- {hw:.2e} vs {want:.5}");
            assert!((m - want).abs() <= hw, "{engine} {what}: {m:.5} +- {hw:.2e} vs {want:.5}");
            assert!(hw < 0.02 * want, "{engine} {what}: interval {hw:.2e} too wide");
        }
    }
}

/// The output convention of a kinematic run: `X = V t`, `Xd = V`, friction = `F_b`,
/// viscous force 0, and (exact engine) the segment variance of the linear-in-time `F_b`.
#[test]
fn kinematic_runs_report_the_bond_force_as_friction() {
    for engine in ["exact", "fixed"] {
        let engine_o = format!("run.engine={engine}");
        let s = scene(
            PULLED,
            &[
                "junctions.n=50",
                "junctions.kon0=0.1",
                "run.t_end=300",
                "output.sample_dt=0.5",
                "fixed.dt=0.1",
                &engine_o,
            ],
        );
        let r = record(&s);
        assert!(r.error.is_none(), "{engine}: {:?}", r.error);
        assert!(r.samples.len() > 500 && r.segments.len() > 500);
        for p in &r.samples {
            assert!((p.x - V * p.t).abs() <= 1e-12 * (1.0 + V * p.t), "{engine}: X = {} at t = {}", p.x, p.t);
            assert_eq!(p.v, V);
            assert_eq!(p.friction, p.bond_force);
        }
        for g in &r.segments {
            assert_eq!(g.viscous, 0.0);
            assert_eq!(g.friction, g.bond_force);
            let h = g.t1 - g.t0;
            let m2 = if engine == "exact" { (KAPPA * g.attached as f64 * V).powi(2) * h * h * h / 12.0 } else { 0.0 };
            assert!((g.friction_m2 - m2).abs() <= 1e-12 * m2.max(1e-300), "{engine}: m2 {} vs {m2}", g.friction_m2);
        }
        // F_b is continuous in time between events: the bond force at a segment's end is
        // the next segment's start value; with n attached it grows at kappa n V.
        assert!(r.counters.ruptures > 100 && r.counters.formations > 100);
    }
}
