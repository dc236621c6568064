//! Statistical tests of the exact engine against exact results (docs/model.md, "Exact
//! facts used as checks"). Fixed seeds; every tolerance is a critical value at level `ALPHA`.
//! Run with `cargo test --release --test suite exact_stats::`.

use crate::common;

use common::*;
use stickslip::observe::EventKind;
use stickslip::run_scene;
use stickslip_testkit::{events_of, first_rupture, samples_of, scene};

/// One weak linear bond pulled by a plate that follows the driver (M = 0, K/eta = 1e9:
/// lag behind the driver below 1e-5), no re-formation.
const SINGLE_WEAK_BOND: &str = r#"
[junctions]
n = 1
bond = "weak"
force_law = "linear"
kappa = 0.1
k0 = 0.1
kon0 = 0.0
dx = 1.0
temperature = 1.0
initial = "attached"
[plate]
mass = 0.0
eta = 1e-3
k = 1e6
v = 0.5
[run]
engine = "exact"
t_end = 200.0
[output]
trace = false
"#;

/// `S(t) = exp(-(k0 f_b / r)(exp(r t / f_b) - 1))`, `r = kappa V`, `f_b = 1/(beta dx)`.
fn single_bond_cdf(k0: f64, kappa: f64, v: f64, beta_dx: f64) -> impl Fn(f64) -> f64 {
    let (r, fb) = (kappa * v, 1.0 / beta_dx);
    move |t: f64| 1.0 - (-(k0 * fb / r) * ((r * t / fb).exp() - 1.0)).exp()
}

fn rupture_times(base: &stickslip::Scene, samples: usize, seed0: u64) -> Vec<f64> {
    (0..samples)
        .map(|i| {
            let mut s = base.clone();
            s.run.seed = seed0 + i as u64;
            first_rupture(&events_of(&s)).expect("the bond ruptures before t_end")
        })
        .collect()
}

#[test]
fn single_weak_bond_rupture_times_follow_the_exact_survival() {
    let n = 100_000;
    let base = scene(SINGLE_WEAK_BOND, &[]);
    let cdf = single_bond_cdf(0.1, 0.1, 0.5, 1.0);
    assert!(1.0 - cdf(base.run.t_end) < 1e-30, "t_end must cover the whole distribution");
    let mut t = rupture_times(&base, n, 1);
    let d = ks_statistic(&mut t, &cdf);
    let crit = ks_critical(n, ALPHA);
    assert!(d < crit, "exact engine: KS D = {d:.5} >= critical {crit:.5} (n = {n})");
}

#[test]
fn fixed_step_at_the_letters_dt_fails_the_single_bond_test() {
    // The same bond in the fixed-step scheme at dt = 1. Its kinematic plate: M = 0 and
    // K dt / eta = 1, so explicit Euler puts X on the driver after every step (X_n = V t_{n-1}).
    let n = 20_000;
    let base = scene(
        SINGLE_WEAK_BOND,
        &["run.engine=fixed", "fixed.dt=1.0", "plate.eta=1e6", "plate.k=1e6", "fixed.rng=park-miller"],
    );
    let mut t = rupture_times(&base, n, 1);
    let d = ks_statistic(&mut t, single_bond_cdf(0.1, 0.1, 0.5, 1.0));
    let crit = ks_critical(n, ALPHA);
    assert!(d > 5.0 * crit, "fixed step dt = 1 should fail visibly: D = {d:.4}, critical {crit:.4}");
}

/// Many weak bonds re-forming unstretched on a plate that follows the driver: every attached
/// lifetime has the single-bond law, every detached time is Exp(kon0) (V <= V0, so g = 1).
/// This exercises thinning with the sum tree over many junctions.
#[test]
fn many_weak_bonds_lifetimes_and_waiting_times() {
    many_weak_bonds(200, 2500.0);
}

/// The same with `N = 1e5` junctions, whose rupture candidates come from bins of anchors
/// (`BINNED_FROM`).
#[test]
fn many_weak_bonds_in_bins_lifetimes_and_waiting_times() {
    const { assert!(stickslip::engine::exact::BINNED_FROM <= 100_000) };
    many_weak_bonds(100_000, 300.0);
}

fn many_weak_bonds(n: usize, t_end: f64) {
    let (n, t) = (format!("junctions.n={n}"), format!("run.t_end={t_end}"));
    let s = scene(
        SINGLE_WEAK_BOND,
        &[&n, "junctions.kon0=0.1", "junctions.reattach=unstretched", "junctions.initial=detached", &t],
    );
    let ev = events_of(&s);
    let t_end = s.run.t_end;
    let mut last: Vec<Option<(EventKind, f64)>> = vec![None; s.junctions.n];
    let (mut attached, mut detached) = (Vec::new(), Vec::new());
    for e in &ev {
        let j = e.junction as usize;
        if let Some((kind, t0)) = last[j] {
            // Keep intervals that start early enough to be complete with certainty
            // (survival < 1e-9 at the end), so censoring cannot bias the sample.
            match kind {
                EventKind::Formation if t0 < t_end - 60.0 => attached.push(e.t - t0),
                EventKind::Rupture if t0 < t_end - 210.0 => detached.push(e.t - t0),
                _ => {}
            }
        }
        last[j] = Some((e.kind, e.t));
    }
    assert!(attached.len() > 20_000 && detached.len() > 20_000, "{} {}", attached.len(), detached.len());
    let (na, nd) = (attached.len(), detached.len());
    let d = ks_statistic(&mut attached, single_bond_cdf(0.1, 0.1, 0.5, 1.0));
    assert!(d < ks_critical(na, ALPHA), "attached lifetimes: D = {d:.5}, n = {na}");
    let d = ks_statistic(&mut detached, |t| 1.0 - (-0.1 * t).exp());
    assert!(d < ks_critical(nd, ALPHA), "detached times: D = {d:.5}, n = {nd}");
}

/// Attached counts on the output grid.
fn counts_of(scene: &stickslip::Scene) -> Vec<u64> {
    samples_of(scene).iter().map(|s| s.attached).collect()
}

/// Strong bonds, kappa = 0, plate at rest: each junction is an independent two-state
/// process, so the stationary attached count is Binomial(N, kon0 / (kon0 + k0)).
#[test]
fn kappa_zero_attached_count_is_binomial() {
    let (n, k0, kon0) = (40usize, 0.1, 0.3);
    let s = scene(
        "",
        &[
            "junctions.n=40",
            "junctions.force_law=linear",
            "junctions.kappa=0",
            "junctions.k0=0.1",
            "junctions.kon0=0.3",
            "junctions.initial=stationary",
            "plate.v=0",
            "run.engine=exact",
            "run.t_end=1000000",
            // Samples 50 time units apart: correlation exp(-(k0+kon0) 50) = exp(-20).
            "output.sample_dt=50",
        ],
    );
    let counts = counts_of(&s);
    let p = kon0 / (kon0 + k0);
    let m = counts.len() as f64;
    let mut observed = vec![0.0; n + 1];
    counts.iter().for_each(|&c| observed[c as usize] += 1.0);
    let binom = statrs::distribution::Binomial::new(p, n as u64).unwrap();
    use statrs::distribution::Discrete;
    let expected: Vec<f64> = (0..=n).map(|k| m * binom.pmf(k as u64)).collect();
    let (chi2, df) = chi_square(&observed, &expected);
    let crit = chi2_critical(df, ALPHA);
    assert!(chi2 < crit, "chi-square {chi2:.2} >= {crit:.2} (df {df}, {m} samples)");
}

/// Strong bonds, linear law, plate moving at V (stiff spring), residual re-attachment:
/// mean bond force per junction `kappa n* (V/k0)(1 + k_on/lambda)`, `n* = k_on/(k_on+k0)`.
#[test]
fn mean_field_bond_force() {
    let (kappa, k0, kon, lambda, v) = (0.1, 0.1, 0.1, 0.1, 0.25);
    let expected = kappa * (kon / (kon + k0)) * (v / k0) * (1.0 + kon / lambda);
    let per_junction: Vec<f64> = (0..16)
        .map(|r| {
            let s = scene(
                SINGLE_WEAK_BOND,
                &[
                    "junctions.bond=strong",
                    "junctions.n=200",
                    "junctions.kon0=0.1",
                    "junctions.initial=stationary",
                    "plate.v=0.25",
                    "run.t_end=3000",
                    "run.t_warmup=300",
                    &format!("run.seed={}", 100 + r),
                ],
            );
            let sum = run_scene(&s, None).unwrap();
            sum.bond_force_mean / s.junctions.n as f64
        })
        .collect();
    let (m, half) = mean_ci(&per_junction, ALPHA);
    assert!((m - expected).abs() <= half, "bond force per junction {m:.5} +- {half:.5}, expected {expected:.5}");
}
