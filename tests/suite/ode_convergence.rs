//! Orders of convergence of DOP853 with fixed steps (error control off): global error h^8,
//! local error h^9, dense output of order 7 (local error h^8 inside a step), embedded
//! estimators of orders 5 and 3. These catch coefficient typos that the algebraic checks in
//! `src/ode/coefficients.rs` might not (e.g. a wrong stage index in the stepper).

use crate::ode_support;

use ode_support::{Driven, Mixed, max_abs_diff, sci, slope};
use stickslip::ode::{Dop853, OdeSystem};

fn integrate_fixed<S: OdeSystem>(sys: &mut S, y0: &[f64], t_end: f64, n: usize) -> Vec<f64> {
    let mut ode = Dop853::new(y0.len(), 1e-10, 1e-12).unwrap();
    let mut y = y0.to_vec();
    let mut t = 0.0;
    let h = t_end / n as f64;
    for _ in 0..n {
        ode.step_fixed(sys, &mut t, &mut y, h).unwrap();
    }
    assert!((t - t_end).abs() < 1e-12);
    y
}

#[test]
fn global_error_is_order_8() {
    let t_end = 4.0;
    let ns = [16usize, 24, 32, 48, 64];
    let mut hs = Vec::new();
    let mut errs = Vec::new();
    for &n in &ns {
        let y = integrate_fixed(&mut Mixed, &Mixed::exact(0.0), t_end, n);
        hs.push(t_end / n as f64);
        errs.push(max_abs_diff(&y, &Mixed::exact(t_end)));
    }
    let p = slope(&hs, &errs);
    eprintln!("global: h = {hs:?}\n        err = {}\n        slope = {p:.3}", sci(&errs));
    assert!(errs.iter().all(|&e| e > 1e-14), "errors reached round-off; choose larger h");
    assert!((7.6..=8.6).contains(&p), "global order {p}");
}

#[test]
fn global_error_is_order_8_for_linear_oscillator() {
    let sys = Driven::LIGHT;
    let t_end = 10.0;
    let ns = [20usize, 28, 40, 56];
    let mut hs = Vec::new();
    let mut errs = Vec::new();
    for &n in &ns {
        let y = integrate_fixed(&mut sys.clone(), &sys.y0(), t_end, n);
        hs.push(t_end / n as f64);
        errs.push(max_abs_diff(&y, &sys.exact(t_end)));
    }
    let p = slope(&hs, &errs);
    eprintln!("oscillator: h = {hs:?}\n        err = {}\n        slope = {p:.3}", sci(&errs));
    assert!(errs.iter().all(|&e| e > 1e-14));
    assert!((7.6..=8.6).contains(&p), "global order {p}");
}

/// One step from the exact solution: end-point error ~ h^9, dense output inside ~ h^8,
/// estimators ~ h^6 (5th order) and h^4 (3rd order). Measured on the components of `Mixed`
/// whose solutions are entire (sin, cos, exp(t) of the nonlinear `y4' = y4^2 e^-t`), so that
/// these step sizes are in the asymptotic regime.
#[test]
fn local_errors_dense_output_and_estimators() {
    let t0 = 0.3;
    let hs = [0.8, 0.56, 0.4, 0.28, 0.2];
    let comps = 2..5;
    let maxc = |v: &[f64]| v[comps.clone()].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let (mut e_end, mut e_dense, mut e5s, mut e3s) = (vec![], vec![], vec![], vec![]);
    for &h in &hs {
        let mut ode = Dop853::new(5, 1e-10, 1e-12).unwrap();
        let mut y = Mixed::exact(t0).to_vec();
        let (_, e5, e3) = ode.probe_step(&mut Mixed, t0, &y, h).unwrap();
        e5s.push(maxc(&e5));
        e3s.push(maxc(&e3));
        let mut t = t0;
        ode.step_fixed(&mut Mixed, &mut t, &mut y, h).unwrap();
        let diff: Vec<f64> = y.iter().zip(Mixed::exact(t)).map(|(a, b)| a - b).collect();
        e_end.push(maxc(&diff));
        let mut worst: f64 = 0.0;
        let mut out = [0.0; 5];
        for s in [0.17, 0.38, 0.5, 0.71, 0.9] {
            let ts = t0 + s * h;
            ode.dense(ts, &mut out).unwrap();
            let diff: Vec<f64> = out.iter().zip(Mixed::exact(ts)).map(|(a, b)| a - b).collect();
            worst = worst.max(maxc(&diff));
        }
        e_dense.push(worst);
    }
    let (p_end, p_dense, p5, p3) = (slope(&hs, &e_end), slope(&hs, &e_dense), slope(&hs, &e5s), slope(&hs, &e3s));
    eprintln!("local end: {} slope {p_end:.3}", sci(&e_end));
    eprintln!("dense:     {} slope {p_dense:.3}", sci(&e_dense));
    eprintln!("est5:      {} slope {p5:.3}", sci(&e5s));
    eprintln!("est3:      {} slope {p3:.3}", sci(&e3s));
    assert!(e_end.iter().all(|&e| e > 1e-13), "errors reached round-off");
    assert!((8.6..=9.4).contains(&p_end), "local order {p_end}");
    assert!((7.6..=8.4).contains(&p_dense), "dense local order {p_dense} (order 7 means h^8)");
    assert!((5.6..=6.4).contains(&p5), "5th-order estimator slope {p5}");
    assert!((3.6..=4.4).contains(&p3), "3rd-order estimator slope {p3}");
}

/// Dense output of a fixed-step run, sampled inside every step: global error ~ h^8 (the
/// interpolant adds a local h^8 error that does not accumulate).
#[test]
fn dense_output_global_order() {
    let t_end = 4.0;
    let ns = [16usize, 24, 32, 48];
    let mut hs = Vec::new();
    let mut errs = Vec::new();
    for &n in &ns {
        let mut ode = Dop853::new(5, 1e-10, 1e-12).unwrap();
        let mut y = Mixed::exact(0.0).to_vec();
        let mut t = 0.0;
        let h = t_end / n as f64;
        let mut worst: f64 = 0.0;
        let mut out = [0.0; 5];
        for _ in 0..n {
            let t_old = t;
            ode.step_fixed(&mut Mixed, &mut t, &mut y, h).unwrap();
            for s in [0.25, 0.5, 0.75] {
                ode.dense(t_old + s * h, &mut out).unwrap();
                worst = worst.max(max_abs_diff(&out, &Mixed::exact(t_old + s * h)));
            }
        }
        hs.push(h);
        errs.push(worst);
    }
    let p = slope(&hs, &errs);
    eprintln!("dense global: {} slope {p:.3}", sci(&errs));
    assert!((7.4..=8.6).contains(&p), "dense global order {p}");
}

/// Pure quadrature `y' = t^q`: the dense output reproduces polynomials of degree <= 7 to
/// round-off at any point of the step (the continuous extension has order 7).
#[test]
fn dense_output_exact_for_polynomials_up_to_degree_7() {
    for q in 0..=7i32 {
        let mut sys = |t: f64, _y: &[f64], d: &mut [f64]| d[0] = t.powi(q);
        let mut ode = Dop853::new(1, 1e-10, 1e-12).unwrap();
        let (t0, h) = (0.4f64, 0.9f64);
        let mut t = t0;
        let mut y = [t0.powi(q + 1) / f64::from(q + 1)];
        ode.step_fixed(&mut sys, &mut t, &mut y, h).unwrap();
        let exact = |t: f64| t.powi(q + 1) / f64::from(q + 1);
        for s in [0.0, 0.13, 0.5, 0.77, 1.0] {
            let ts = t0 + s * h;
            let got = ode.dense_component(0, ts).unwrap();
            let err = (got - exact(ts)).abs();
            if q <= 6 {
                assert!(err < 1e-14, "q = {q}, s = {s}: {err:e}");
            } else if s > 0.0 && s < 1.0 {
                // Degree 8: no longer exact inside the step.
                assert!(err > 1e-9, "q = {q}, s = {s}: {err:e} (should not be exact)");
            }
        }
    }
}
