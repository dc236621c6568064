//! Low-velocity creep (`scenarios/creep.toml`): the exact engine against the thermally
//! activated (Bell) theory of `stickslip_testkit::creep`.
//!
//! A weak junction formed unstretched and loaded at `r = kappa V` ruptures at mean force
//! `E[f] = f_b e^a E1(a)`, `a = k0 f_b / r`; by renewal-reward the mean friction per junction
//! is `E[f^2] / (2 r) / (E[f] / r + 1 / kon0) + eta V / N`. Each replica's window averages
//! are independent (disjoint seeds), so their mean has a Student-t interval; the test fails
//! if the theory lies outside the 99.9 % interval. Run with `cargo test --release --test suite creep::`
//! (about a second).

use crate::common;

use std::path::Path;

use common::mean_ci;
use stickslip::studies::seeds::{Role, pcg_seed};
use stickslip::{Scene, run_scene};
use stickslip_testkit::creep::{bell_moments, theory};

fn creep(v: f64) -> Scene {
    // About 2000 / (kappa V) time units: some 150 junction lifetimes per replica.
    let t_end = 2000.0 / (0.1 * v);
    let o = [
        format!("plate.v={v:e}"),
        format!("run.t_end={t_end:e}"),
        format!("run.t_warmup={:e}", 0.2 * t_end),
        "output.trace=false".to_string(),
    ];
    Scene::from_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/creep.toml"), &o)
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn creep_rupture_force_and_friction_follow_the_bell_theory() {
    const REPLICAS: u64 = 16;
    const ALPHA: f64 = 1e-3;
    for (k, v) in [1e-6, 1e-3].into_iter().enumerate() {
        let scene = creep(v);
        let th = theory(&scene);
        let (mut rf, mut fr) = (Vec::new(), Vec::new());
        for r in 0..REPLICAS {
            let mut s = scene.clone();
            s.run.seed = pcg_seed(7, Role::Exact, k as u64, r);
            let sum = run_scene(&s, None).unwrap_or_else(|e| panic!("V = {v}: {e}"));
            rf.push(sum.rupture_force_mean.expect("ruptures in the window"));
            fr.push(sum.friction_per_junction);
        }
        let (m, h) = mean_ci(&rf, ALPHA);
        assert!((m - th.rupture_force).abs() <= h, "V = {v}: rupture force {m} +- {h}, theory {}", th.rupture_force);
        let (m, h) = mean_ci(&fr, ALPHA);
        assert!(
            (m - th.friction_per_junction).abs() <= h,
            "V = {v}: friction per junction {m} +- {h}, theory {}",
            th.friction_per_junction
        );
    }
}

#[test]
fn creep_rupture_force_grows_by_f_b_per_e_fold_of_velocity() {
    // Three decades apart: E[f] rises by about f_b ln(1000) = 6.9 (Bell); a scheme without
    // force-dependent rupture would give no rise at all.
    let mean = |v: f64, k: u64| {
        let scene = creep(v);
        let x: Vec<f64> = (0..8)
            .map(|r| {
                let mut s = scene.clone();
                s.run.seed = pcg_seed(11, Role::Exact, k, r);
                run_scene(&s, None).unwrap().rupture_force_mean.unwrap()
            })
            .collect();
        mean_ci(&x, 1e-3)
    };
    let ((lo, hl), (hi, hh)) = (mean(1e-6, 0), mean(1e-3, 1));
    let expected = theory(&creep(1e-3)).rupture_force - theory(&creep(1e-6)).rupture_force;
    assert!((expected - 1000f64.ln()).abs() < 0.05, "theory's rise {expected}");
    assert!(((hi - lo) - expected).abs() <= hl + hh, "rise {} +- {}, theory {expected}", hi - lo, hl + hh);
}

// The theory itself (testkit/src/creep.rs).

/// `E1(a)` by its power series (for small `a`).
fn e1(a: f64) -> f64 {
    let gamma = 0.577_215_664_901_532_9;
    let mut sum = 0.0;
    let mut term = 1.0; // a^k / k!
    for k in 1..60 {
        term *= a / k as f64;
        sum += if k % 2 == 1 { 1.0 } else { -1.0 } * term / k as f64;
    }
    -gamma - a.ln() + sum
}

#[test]
fn mean_rupture_force_is_f_b_exp_a_e1_a() {
    for (r, k0, f_b) in [(1e-7, 1e-10, 1.0), (1e-4, 1e-10, 1.0), (0.05, 0.1, 1.0), (1e-3, 1e-6, 2.0)] {
        let a = k0 * f_b / r;
        let (m1, _) = bell_moments(r, k0, f_b);
        let expected = f_b * a.exp() * e1(a);
        assert!((m1 - expected).abs() < 1e-9 * expected, "r {r}: {m1} vs {expected}");
    }
}

#[test]
fn second_moment_approaches_the_gumbel_law() {
    // a = 1e-6: E[f^2] = f_b^2 e^a ((ln a + gamma)^2 + pi^2/6) + O(a ln^2 a).
    let (r, k0) = (1e-4, 1e-10);
    let a: f64 = k0 / r;
    let (_, m2) = bell_moments(r, k0, 1.0);
    let g = 0.577_215_664_901_532_9;
    let expected = a.exp() * ((a.ln() + g).powi(2) + std::f64::consts::PI.powi(2) / 6.0);
    assert!((m2 - expected).abs() < 1e-4 * expected, "{m2} vs {expected}");
}
