//! Tests of the short path ([`super::short`]) against the plate's Taylor loop.

use super::short::*;
use super::terms::{Integrals, RECIP, hilbert_fixed};
use super::{LinearPlate, Trajectory};
use crate::rng::{UniformSource, pcg};

/// `sum_n |t_n|` and `sum_n n |t_n| / tau` of the Taylor terms `t_n = c_n tau^n` (the
/// recurrence of the module's doc, 40 terms): the natural scales of `u` and `u' - v0`.
fn scales(tr: &Trajectory, tau: f64) -> (f64, f64) {
    let (m, eta, k) = tr.plate.coefficients();
    let mut c = [0.0; 40];
    c[1] = tr.v0;
    c[2] = (tr.f0 - eta * tr.v0) / (2.0 * m);
    c[3] = (tr.b - 2.0 * eta * c[2] - k * tr.v0) / (6.0 * m);
    for n in 4..40 {
        c[n] = -(eta * c[n - 1] / n as f64 + k * c[n - 2] / (n * (n - 1)) as f64) / m;
    }
    let t: Vec<f64> = (0..40).map(|n| c[n] * tau.powi(n as i32)).collect();
    let su: f64 = t.iter().map(|x| x.abs()).sum();
    let sv: f64 = t.iter().enumerate().skip(2).map(|(n, x)| n as f64 * x.abs()).sum::<f64>() / tau;
    (su, sv)
}

/// Random plates (under- and overdamped, stiff, soft), states and steps up to the short
/// path's limit: the polynomial, where it is taken, agrees with the Taylor loop to 1e-12
/// of the natural scales (state and integrals), and it is taken at the engine's steps.
#[test]
fn agrees_with_the_taylor_loop() {
    let mut rng = pcg(11);
    let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
    let (mut taken, mut tried) = (0, 0);
    for _ in 0..4000 {
        let (m, eta, k) = (10f64.powf(r(-3.0, 6.0)), 10f64.powf(r(-3.0, 6.0)), 10f64.powf(r(-3.0, 7.0)));
        let p = LinearPlate::new(m, eta, k);
        let tr = p.trajectory(r(-1e3, 1e3), r(-2.0, 2.0), r(-1e3, 1e3) * k, r(-1.0, 1.0) * k);
        let tau = 10f64.powf(r(-9.0, -2.4)) / p.rho();
        let s = r(-1.0, 1.0);
        tried += 1;
        let Some(c) = tr.short(tau) else { continue };
        taken += 1;
        let (u, du) = Short::state(&c, tau);
        let (ut, dut) = tr.taylor_at(tau);
        let (su, sv) = scales(&tr, tau);
        assert!((u - ut).abs() <= 1e-12 * su, "u {u} {ut} scale {su} (m {m} eta {eta} k {k} tau {tau})");
        assert!((du - dut).abs() <= 1e-12 * (sv + tr.v0.abs()), "u' {du} {dut} (m {m} eta {eta} k {k})");
        let i = Short::integrals(&c, tau, s);
        let it = tr.taylor_with_integrals(tau, s).2;
        let ws = su + s.abs() * tau;
        assert!((i.i1 - it.i1).abs() <= 1e-12 * su * tau, "i1 {} {}", i.i1, it.i1);
        assert!((i.i2 - it.i2).abs() <= 1e-12 * ws * ws * tau, "i2 {} {}", i.i2, it.i2);
    }
    assert!(taken > tried / 3, "short path taken {taken} of {tried} times");
}

/// The bench's plate at `N = 1e6` (`M = eta = 2.5e5`, `k = 5.5e5`) and its event spacing
/// (`tau ~ 1e-5`, up to 2e-4): the short path is taken, including at zero acceleration
/// (`f0 = eta v0`, `c_2 = 0`).
#[test]
fn is_taken_at_large_n() {
    let p = LinearPlate::new(2.5e5, 2.5e5, 5.5e5);
    for &(v0, a) in &[(0.5, 2.5e5 * 0.5 + 3.0), (0.5, 2.5e5 * 0.5), (0.49, 1.0e5)] {
        let tr = p.trajectory(0.0, v0, a, 2.5e5);
        for &tau in &[1e-7, 1e-6, 1e-5, 5e-5, 2e-4] {
            assert!(tr.short(tau).is_some(), "v0 {v0} a {a} tau {tau}");
        }
    }
}

/// The square integral from degree 5, where its test lets it, agrees with all 28 pairs
/// to within rounding of the natural scale `S^2 h` (the proven bound is `2^-56 S^2 h`);
/// at the bench plate's steps at `N = 1e6` it is taken.
#[test]
fn square_integral_drops_only_what_rounding_hides() {
    let mut rng = pcg(12);
    let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
    let mut truncated = 0;
    for case in 0..4000 {
        let (m, eta, k) = if case % 2 == 0 {
            (10f64.powf(r(-3.0, 6.0)), 10f64.powf(r(-3.0, 6.0)), 10f64.powf(r(-3.0, 7.0)))
        } else {
            (2.5e5, 2.5e5, 5.5e5)
        };
        let p = LinearPlate::new(m, eta, k);
        let tr = p.trajectory(r(-1e3, 1e3), r(-2.0, 2.0), r(-1e3, 1e3) * k, r(-1.0, 1.0) * k);
        let h = if case % 2 == 0 { 10f64.powf(r(-9.0, -2.4)) / p.rho() } else { 10f64.powf(r(-7.0, -4.0)) };
        let Some(c) = tr.short(h) else { continue };
        let mut t = [0.0; LEN];
        let mut hn = h;
        for n in 1..LEN {
            t[n] = c[n] * hn;
            hn *= h;
        }
        t[1] -= r(-1.0, 1.0) * h;
        let s: f64 = t.iter().map(|x| x.abs()).sum();
        let (got, full) = (square_integral(&t, h), hilbert_fixed::<LEN>(&t, h));
        assert!((got - full).abs() <= 4.0 * f64::EPSILON * s * s * h, "{got} vs {full} (m {m} eta {eta} k {k} h {h})");
        let high = t[6].abs() + t[7].abs();
        if case % 2 == 1 {
            assert!(high <= HIGH_NEGLIGIBLE * (s - high), "not truncated at h {h}: {t:?}");
        }
        truncated += usize::from(high <= HIGH_NEGLIGIBLE * (s - high));
    }
    assert!(truncated >= 2000, "truncated {truncated} times");
}

/// A plate without mass, a non-finite state and a step beyond the limit never take it.
#[test]
fn is_not_taken_outside_its_range() {
    let tr = LinearPlate::new(0.0, 2.0, 3.0).trajectory(0.5, 0.0, 1.0, 1.0);
    assert!(tr.short(1e-9).is_none());
    let p = LinearPlate::new(1.0, 1.0, 1.0);
    assert!(p.trajectory(0.5, f64::NAN, 1.0, 1.0).short(1e-9).is_none());
    assert!(p.trajectory(0.5, 0.1, f64::INFINITY, 1.0).short(1e-9).is_none());
    assert!(p.trajectory(0.5, 0.1, 1.0, 1.0).short(0.01).is_none());
    assert!(p.trajectory(0.5, 0.1, 1.0, 1.0).short(f64::NAN).is_none());
}

/// Written and read back, a plate derives the same short-path constants.
#[test]
fn survives_serialization() {
    let p = LinearPlate::new(2.5e5, 2.5e5, 5.5e5);
    let back: LinearPlate = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
    assert_eq!(p, back);
}

/// Four pieces' integrals side by side are each the bits of the piece alone, whether the
/// lanes all drop the square's higher terms or some keep them; and the one-lane
/// form is the scalar sum written out (`t_n = c_n h^n`, [`square_integral`]).
#[test]
fn lanes_give_the_bits_of_each_piece_alone() {
    let mut rng = pcg(13);
    let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
    let (mut mixed, mut kept) = (0, 0);
    for _ in 0..2000 {
        let (mut c, mut h) = ([[0.0; 4]; LEN], [0.0; 4]);
        let s = r(-1.0, 1.0);
        let mut high = [false; 4];
        for l in 0..4 {
            let p = LinearPlate::new(10f64.powf(r(-3.0, 6.0)), 10f64.powf(r(-3.0, 6.0)), 10f64.powf(r(-3.0, 7.0)));
            let tr = p.trajectory(r(-1e3, 1e3), r(-2.0, 2.0), r(-1e3, 1e3) * p.coefficients().2, r(-1.0, 1.0));
            let (coef, tau) = loop {
                let tau = 10f64.powf(r(-9.0, -2.4)) / p.rho();
                if let Some(coef) = tr.short(tau) {
                    break (coef, tau);
                }
            };
            h[l] = tau;
            let (mut t, mut hn, mut i1) = ([0.0; LEN], tau, 0.0);
            for n in 1..LEN {
                c[n][l] = coef[n];
                t[n] = coef[n] * hn;
                i1 += t[n] * RECIP[n + 1];
                hn *= tau;
            }
            t[1] -= s * tau;
            let want = Integrals { i1: i1 * tau, i2: square_integral(&t, tau) };
            assert_eq!(Short::integrals(&coef, tau, s), want);
            let low: f64 = t[1..6].iter().map(|x| x.abs()).sum();
            high[l] = t[6].abs() + t[7].abs() > HIGH_NEGLIGIBLE * low;
        }
        let (i1, i2) = integrals_in_lanes(&c, &h, s);
        for l in 0..4 {
            let alone = Short::integrals(&c.map(|row| row[l]), h[l], s);
            assert_eq!((i1[l].to_bits(), i2[l].to_bits()), (alone.i1.to_bits(), alone.i2.to_bits()), "lane {l}");
        }
        kept += high.iter().filter(|&&k| k).count();
        mixed += usize::from(high.iter().any(|&k| k) && !high.iter().all(|&k| k));
    }
    assert!(mixed > 100 && kept > 300, "{mixed} mixed batches, {kept} lanes keeping the higher terms");
}
