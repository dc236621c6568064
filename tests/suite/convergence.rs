//! The fixed-step engine converges to the exact engine as `dt -> 0` on the letter's Fig. 1
//! scene: the bias of `friction_mean` is proportional to `dt`.
//! Run with `cargo test --release --test suite convergence::`.

use crate::common;

use common::{ALPHA, chi2_critical};
use statrs::distribution::{ContinuousCDF, Normal};
use stickslip::run_scene;
use stickslip_testkit as testkit;

const REPLICAS: u64 = 256;

/// Mean and standard error of `friction_mean` over independent replicas (seeds 1..=R).
fn friction_mean(overrides: &[&str]) -> (f64, f64) {
    let v: Vec<f64> = (1..=REPLICAS)
        .map(|seed| {
            let mut o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
            o.push(format!("run.seed={seed}"));
            o.push("output.trace=false".into());
            let o: Vec<&str> = o.iter().map(String::as_str).collect();
            run_scene(&testkit::fig1_with(&o), None).unwrap().friction_mean
        })
        .collect();
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

#[test]
fn fixed_step_bias_shrinks_in_proportion_to_dt() {
    let (exact, se_exact) = friction_mean(&["run.engine=exact"]);
    let dts = [0.5, 0.25, 0.125];
    // Bias b(dt) = fixed - exact and its standard error (independent replicas).
    let bias: Vec<(f64, f64, f64)> = dts
        .iter()
        .map(|&dt| {
            let (m, se) = friction_mean(&["run.engine=fixed", &format!("fixed.dt={dt}")]);
            (dt, m - exact, (se * se + se_exact * se_exact).sqrt())
        })
        .collect();
    // Weighted least squares for b = c dt. The exact reference is shared by the three
    // biases, so they are correlated; the fit is done with the full covariance
    // C_ij = se_i^2 delta_ij + se_exact^2.
    let k = bias.len();
    let mut cov = vec![vec![se_exact * se_exact; k]; k];
    for (i, b) in bias.iter().enumerate() {
        cov[i][i] = b.2 * b.2;
    }
    let inv = stickslip::studies::compare::fit::invert(&cov).expect("a covariance matrix is positive definite");
    let x: Vec<f64> = bias.iter().map(|b| b.0).collect();
    let y: Vec<f64> = bias.iter().map(|b| b.1).collect();
    let quad =
        |a: &[f64], b: &[f64]| -> f64 { (0..k).map(|i| (0..k).map(|j| a[i] * inv[i][j] * b[j]).sum::<f64>()).sum() };
    let c = quad(&x, &y) / quad(&x, &x);
    let se_c = (1.0 / quad(&x, &x)).sqrt();
    let r: Vec<f64> = (0..k).map(|i| y[i] - c * x[i]).collect();
    let chi2 = quad(&r, &r);
    let crit = chi2_critical(k - 1, ALPHA);
    let z = Normal::new(0.0, 1.0).unwrap().inverse_cdf(1.0 - ALPHA / 2.0);
    let report = format!(
        "exact {exact:.3} +- {se_exact:.3}; biases {bias:?}; c = {c:.3} +- {se_c:.3}; chi2 {chi2:.2} (crit {crit:.2})"
    );
    assert!(chi2 < crit, "bias not proportional to dt: {report}");
    assert!(c.abs() > z * se_c, "no detectable O(dt) bias at these dt (the test would be vacuous): {report}");
    eprintln!("{report}");
}
