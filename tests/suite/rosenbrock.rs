//! The Rosenbrock (RODAS4) integrator: accuracy against closed forms across plate regimes
//! (non-stiff to extremely stiff, `M -> 0`), stiffness-independent step counts, a nonlinear
//! stiff problem (Van der Pol, `eps = 1e-6`), convergence orders, dense output and its
//! bounds, the event-cut workload, checkpoints and error paths.
//!
//! Run: `cargo test --profile quick --test suite rosenbrock:: -- --nocapture` (prints the measured
//! numbers quoted in docs/rosenbrock.md).

use crate::rosenbrock_support;

use proptest::prelude::*;
use rosenbrock_support::{CubicPlate, Explicit, LinPlate, Mixed, VanDerPol};
use stickslip::engine::exact::stepper::linear::propagator::LinearPlate;
use stickslip::ode::{Dop853, OdeError, Rosenbrock, RosenbrockConfig, StiffSystem};

/// Closed form of `LinPlate` from `(x0, v0)` at time `t` (`M = 0`: `v0` ignored).
fn exact(p: &LinPlate, x0: f64, v0: f64, t: f64) -> [f64; 2] {
    let (x, v) = LinearPlate::new(p.m, p.eta, p.k).trajectory(x0, v0, p.a, p.b).at(t);
    [x, v]
}

/// Worst `|y_i - exact_i| / (atol + rtol max |exact_i|)` at step ends and at three dense
/// points per step, and the number of steps, over `[0, t_end]` with free steps. The max is
/// over the whole run (a fine grid, every step end and every dense point), the usual scale
/// of a global error.
struct Run {
    ends: f64,
    dense: f64,
    steps: u64,
    rejected: u64,
}

fn run_linear(p: LinPlate, x0: f64, v0: f64, t_end: f64, rtol: f64, atol: f64) -> Run {
    let n = p.dim();
    let mut ode = Rosenbrock::new(n, rtol, atol).unwrap();
    let mut sys = p;
    let (mut t, mut y) = (0.0, [x0, v0]);
    let mut scale = [0.0f64; 2];
    let see = |e: &[f64; 2], scale: &mut [f64; 2]| {
        for i in 0..n {
            scale[i] = scale[i].max(e[i].abs());
        }
    };
    for k in 0..=2000 {
        see(&exact(&p, x0, v0, t_end * k as f64 / 2000.0), &mut scale);
    }
    let (mut ends, mut dense) = ([0.0f64; 2], [0.0f64; 2]);
    let mut out = [0.0; 2];
    while t < t_end {
        ode.step(&mut sys, &mut t, &mut y[..n], t_end).unwrap();
        let (t0, t1) = ode.last_step().unwrap();
        let e1 = exact(&p, x0, v0, t1);
        see(&e1, &mut scale);
        for i in 0..n {
            ends[i] = ends[i].max((y[i] - e1[i]).abs());
        }
        for s in [0.25, 0.5, 0.75] {
            let ts = t0 + s * (t1 - t0);
            ode.dense(ts, &mut out[..n]).unwrap();
            let e = exact(&p, x0, v0, ts);
            see(&e, &mut scale);
            for i in 0..n {
                dense[i] = dense[i].max((out[i] - e[i]).abs());
            }
        }
    }
    let rel = |err: [f64; 2]| (0..n).map(|i| err[i] / (atol + rtol * scale[i])).fold(0.0, f64::max);
    Run { ends: rel(ends), dense: rel(dense), steps: ode.stats().accepted, rejected: ode.stats().rejected }
}

/// Global error within a small multiple (10) of the tolerance at step ends and in the dense
/// output, from non-stiff to extremely stiff plates, for three tolerances.
#[test]
fn linear_plate_matches_closed_form_in_every_regime() {
    let cases: [(&str, LinPlate, f64); 7] = [
        ("underdamped", LinPlate { m: 1.0, eta: 0.1, k: 4.0, a: 1.0, b: 0.05 }, 20.0),
        ("overdamped", LinPlate { m: 1.0, eta: 10.0, k: 1.0, a: 1.0, b: 0.05 }, 20.0),
        ("eta = 0", LinPlate { m: 1.0, eta: 0.0, k: 4.0, a: 1.0, b: 0.0 }, 20.0),
        ("letter's plate", LinPlate { m: 75.0, eta: 75.0, k: 150.0, a: 75.0, b: 1.0 }, 20.0),
        ("moderately stiff (M 1e-3, eta 1, k 1e4)", LinPlate { m: 1e-3, eta: 1.0, k: 1e4, a: 1e4, b: 1e3 }, 1.0),
        ("very stiff (M 1e-9, eta 100, k 1e9)", LinPlate { m: 1e-9, eta: 100.0, k: 1e9, a: 1e9, b: 1e8 }, 1.0),
        ("first order (eta 1e-3, k 1e6)", LinPlate { m: 0.0, eta: 1e-3, k: 1e6, a: 1e6, b: 1e5 }, 1.0),
    ];
    for (name, p, t_end) in cases {
        // The velocity of the very stiff plate is X' = (a + b t - k X - M X'')/eta with
        // `k X ~ 1e9`: its round-off floor is ~eps k |X| / eta ~ 2e-9 absolute, above rtol
        // 1e-10 times |X'| ~ 0.1, where the error estimate is pure round-off and the steps
        // collapse (see docs/rosenbrock.md, "Tolerances below the round-off floor"). Not tested there.
        let rtols: &[f64] = if p.m > 0.0 && p.k / p.eta >= 1e6 { &[1e-6, 1e-8] } else { &[1e-6, 1e-8, 1e-10] };
        for &rtol in rtols {
            let r = run_linear(p, 0.0, 0.0, t_end, rtol, rtol * 1e-2);
            println!(
                "{name:42} rtol {rtol:.0e}: ends {:.2} dense {:.2} tol, {} steps ({} rejected)",
                r.ends, r.dense, r.steps, r.rejected
            );
            assert!(r.ends <= 10.0, "{name}, rtol {rtol}: step-end error {} tol", r.ends);
            assert!(r.dense <= 10.0, "{name}, rtol {rtol}: dense error {} tol", r.dense);
        }
    }
}

/// Overdamped plates with `M` from 1e-3 to 1e-12 (fast rate `eta/M` from 1e5 to 1e14, slow
/// rate `k/eta = 100`) started on the slow manifold (`X' = r_s (X - X_p) + X_p'`, no fast
/// component): the step count over `[0, 1]` is set by the slow motion and does not grow
/// with stiffness (an explicit method would need at least `eta/M` steps), and the
/// `M = 1e-12` solution agrees with the first-order plate to the tolerance.
#[test]
fn step_count_does_not_grow_with_stiffness() {
    let (eta, k, a, b) = (100.0, 1e4, 1e4, 1e3);
    let (rtol, atol) = (1e-8, 1e-10);
    let mut counts = Vec::new();
    for m in [1e-3, 1e-6, 1e-9, 1e-12, 0.0] {
        let p = LinPlate { m, eta, k, a, b };
        // Slow root and particular solution X_p = (a + b t)/k - b eta/k^2.
        let r_s = -2.0 * k / (eta + (eta * eta - 4.0 * m * k).sqrt());
        let xp0 = a / k - b * eta / (k * k);
        let v0 = b / k + r_s * (0.0 - xp0);
        let r = run_linear(p, 0.0, v0, 1.0, rtol, atol);
        println!(
            "M = {m:.0e}: {} steps ({} rejected), ends {:.2} tol, dense {:.2} tol",
            r.steps, r.rejected, r.ends, r.dense
        );
        assert!(r.ends <= 10.0 && r.dense <= 10.0, "M = {m}: error {} / {} tol", r.ends, r.dense);
        counts.push(r.steps);
    }
    let base = counts[0];
    assert!(base < 400, "M = 1e-3 took {base} steps");
    for (&c, m) in counts.iter().zip(["1e-3", "1e-6", "1e-9", "1e-12", "0"]) {
        assert!(c <= base + base / 4, "M = {m}: {c} steps vs {base} at M = 1e-3");
    }
    // M = 1e-12 vs the first-order plate: y differs by O(M k / eta^2) = 1e-12 relative.
    let run = |m: f64| {
        let p = LinPlate { m, eta, k, a, b };
        let mut ode = Rosenbrock::new(p.dim(), rtol, atol).unwrap();
        let r_s = -2.0 * k / (eta + (eta * eta - 4.0 * m * k).sqrt());
        let (mut t, mut y, mut sys) = (0.0, [0.0, b / k - r_s * (a / k - b * eta / (k * k))], p);
        while t < 1.0 {
            ode.step(&mut sys, &mut t, &mut y[..p.dim()], 1.0).unwrap();
        }
        y[0]
    };
    let (x_m, x_0) = (run(1e-12), run(0.0));
    let exact0 = exact(&LinPlate { m: 0.0, eta, k, a, b }, 0.0, 0.0, 1.0)[0];
    assert!((x_m - exact0).abs() <= 10.0 * (atol + rtol * exact0.abs()), "{x_m} vs {exact0}");
    assert!((x_0 - exact0).abs() <= 10.0 * (atol + rtol * exact0.abs()), "{x_0} vs {exact0}");
}

/// The nonlinear stiff benchmark of Hairer & Wanner (Van der Pol, `eps = 1e-6`, `t` in
/// `[0, 2]`): the error at `t = 2` against a reference computed with `rtol = atol = 1e-13`
/// is proportional to the tolerance (log-log slope near 1, each error within 10 tol).
#[test]
fn van_der_pol_stiff_error_is_proportional_to_the_tolerance() {
    let vdp = VanDerPol { eps: 1e-6 };
    let solve = |tol: f64| {
        let mut ode = Rosenbrock::new(2, tol, tol).unwrap();
        let (mut t, mut y, mut sys) = (0.0, vdp.y0(), vdp);
        while t < 2.0 {
            ode.step(&mut sys, &mut t, &mut y, 2.0).unwrap();
        }
        (y, ode.stats())
    };
    let (reference, st) = solve(1e-13);
    println!("reference y(2) = {reference:?}, {} steps", st.accepted);
    let tols = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9];
    let mut pts = Vec::new();
    for tol in tols {
        let (y, st) = solve(tol);
        let err = (0..2).map(|i| (y[i] - reference[i]).abs() / (tol + tol * reference[i].abs())).fold(0.0, f64::max);
        println!("tol {tol:.0e}: err {err:.3} tol, {} steps ({} rejected)", st.accepted, st.rejected);
        assert!(err <= 10.0, "tol {tol}: error {err} tol");
        pts.push((tol.ln(), (err * tol).ln()));
    }
    let slope = ls_slope(&pts);
    println!("slope log err / log tol = {slope:.3}");
    assert!((0.8..=1.2).contains(&slope), "slope {slope}");
}

/// Non-stiff (`eps = 0.1`) Van der Pol: RODAS4 and DOP853 agree to the tolerance at `t = 2`.
#[test]
fn van_der_pol_non_stiff_agrees_with_dop853() {
    let vdp = VanDerPol { eps: 0.1 };
    let mut ode = Rosenbrock::new(2, 1e-9, 1e-9).unwrap();
    let (mut t, mut y, mut sys) = (0.0, vdp.y0(), vdp);
    while t < 2.0 {
        ode.step(&mut sys, &mut t, &mut y, 2.0).unwrap();
    }
    let mut dop = Dop853::new(2, 1e-13, 1e-13).unwrap();
    let (mut t2, mut y2, mut sys2) = (0.0, vdp.y0(), Explicit(vdp));
    while t2 < 2.0 {
        dop.step(&mut sys2, &mut t2, &mut y2, 2.0).unwrap();
    }
    for i in 0..2 {
        let err = (y[i] - y2[i]).abs() / (1e-9 * (1.0 + y2[i].abs()));
        println!("component {i}: {err:.3} tol");
        assert!(err <= 10.0, "component {i}: {} vs {}", y[i], y2[i]);
    }
}

fn ls_slope(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |(a, b), p| (a + p.0, b + p.1));
    let (mx, my) = (sx / n, sy / n);
    let num: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let den: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    num / den
}

/// Fixed steps on the non-autonomous nonlinear `Mixed` system (which exercises `df/dt`):
/// global error of order 4, local error of order 5, dense output local error of order 4
/// (a continuous extension of order 3).
#[test]
fn convergence_orders() {
    // Global: t in [0, 2], h = 2/N.
    let mut pts = Vec::new();
    for n_steps in [10, 20, 40, 80] {
        let h = 2.0 / n_steps as f64;
        let mut ode = Rosenbrock::new(5, 1e-8, 1e-8).unwrap();
        let (mut t, mut y) = (0.0, Mixed::exact(0.0));
        for _ in 0..n_steps {
            ode.step_fixed(&mut Mixed, &mut t, &mut y, h).unwrap();
        }
        let e = Mixed::exact(2.0);
        let err = (0..5).map(|i| (y[i] - e[i]).abs()).fold(0.0, f64::max);
        pts.push((h.ln(), err.ln()));
    }
    let global = ls_slope(&pts);
    // Local and dense: one step from the exact state at t0 = 0.3.
    let t0 = 0.3;
    let (mut loc, mut den) = (Vec::new(), Vec::new());
    for h in [0.2, 0.1, 0.05, 0.025] {
        let mut ode = Rosenbrock::new(5, 1e-8, 1e-8).unwrap();
        let (mut t, mut y) = (t0, Mixed::exact(t0));
        ode.step_fixed(&mut Mixed, &mut t, &mut y, h).unwrap();
        let e = Mixed::exact(t0 + h);
        loc.push((h.ln(), (0..5).map(|i| (y[i] - e[i]).abs()).fold(0.0, f64::max).ln()));
        let mut worst: f64 = 0.0;
        for s in [0.3, 0.6] {
            let mut out = [0.0; 5];
            ode.dense(t0 + s * h, &mut out).unwrap();
            let e = Mixed::exact(t0 + s * h);
            worst = (0..5).map(|i| (out[i] - e[i]).abs()).fold(worst, f64::max);
        }
        den.push((h.ln(), worst.ln()));
    }
    let (local, dense) = (ls_slope(&loc), ls_slope(&den));
    println!("slopes: global {global:.2} (4), local {local:.2} (5), dense {dense:.2} (4)");
    assert!((3.7..=4.3).contains(&global), "global order {global}");
    assert!((4.6..=5.4).contains(&local), "local order {local}");
    assert!((3.6..=4.4).contains(&dense), "dense order {dense}");
}

/// The engine's pattern at N = 1e6: steps cut at events 1e-5 apart, `reset` after each. The
/// result is the closed form to round-off, one attempt per interval (6 RHS evaluations and
/// one Jacobian each), and the step-size proposal is not shrunk by the cuts.
#[test]
fn event_cut_steps_are_exact_and_cheap() {
    let p = LinPlate { m: 75.0, eta: 75.0, k: 150.0, a: 75.0, b: 1.0 };
    let mut ode = Rosenbrock::new(2, 1e-10, 1e-12).unwrap();
    ode.set_h_proposal(0.5);
    let (mut t, mut y, mut sys) = (0.0, [0.3, -0.1], p);
    for k in 1..=1000 {
        ode.step(&mut sys, &mut t, &mut y, k as f64 * 1e-5).unwrap();
        ode.reset();
    }
    assert_eq!(t, 1000.0 * 1e-5);
    let e = exact(&p, 0.3, -0.1, t);
    for i in 0..2 {
        assert!((y[i] - e[i]).abs() <= 1e-13 * (1.0 + e[i].abs()), "{i}: {} vs {}", y[i], e[i]);
    }
    let st = ode.stats();
    assert_eq!((st.accepted, st.rejected, st.rhs_evals), (1000, 0, 6000));
    assert_eq!(ode.jacobian_evals(), 1000);
    assert_eq!(st.restarts, 999);
    assert!(ode.h_proposal().unwrap() >= 0.5);
}

/// The nonlinear plate with quadratures, stiff (`M = 1e-9`) and non-stiff, against DOP853 /
/// itself: the non-stiff case agrees with DOP853 at rtol 1e-13 to the tolerance; the stiff
/// case (where DOP853 cannot go) agrees with the first-order (`M = 0`) plate to the
/// tolerance, quadratures included, and `M = 1e-12` takes no more steps than `M = 1e-9`
/// (within 10%). (`M > 0` takes more steps than `M = 0`: its velocity component, absent
/// from the first-order system, is also error-controlled; see docs/rosenbrock.md.)
#[test]
fn cubic_plate_with_quadratures() {
    let t_end = 1.0;
    let run_r = |p: CubicPlate, rtol: f64| {
        let n = p.dim();
        let mut ode = Rosenbrock::new(n, rtol, rtol * 1e-2).unwrap();
        let mut y = [0.0; 5];
        y[0] = 0.2;
        let (mut t, mut sys) = (0.0, p);
        while t < t_end {
            ode.step(&mut sys, &mut t, &mut y[..n], t_end).unwrap();
        }
        (y, ode.stats())
    };
    let soft = CubicPlate { m: 1.0, eta: 2.0, k: 3.0, v: 0.5, kn: 1.0, c3: 4.0 };
    let (y, st) = run_r(soft, 1e-9);
    let mut dop = Dop853::new(5, 1e-13, 1e-15).unwrap();
    let (mut t, mut yd, mut sys) = (0.0, [0.2, 0.0, 0.0, 0.0, 0.0], Explicit(soft));
    while t < t_end {
        dop.step(&mut sys, &mut t, &mut yd, t_end).unwrap();
    }
    for i in 0..5 {
        let err = (y[i] - yd[i]).abs() / (1e-11 + 1e-9 * yd[i].abs());
        println!("non-stiff component {i}: {err:.3} tol ({} steps)", st.accepted);
        assert!(err <= 10.0, "component {i}: {} vs {}", y[i], yd[i]);
    }
    let stiff = CubicPlate { m: 1e-9, eta: 1.0, k: 1e3, v: 0.5, kn: 1e3, c3: 1e4 };
    let first = CubicPlate { m: 0.0, ..stiff };
    let (ys, sts) = run_r(stiff, 1e-9);
    let (_, st12) = run_r(CubicPlate { m: 1e-12, ..stiff }, 1e-9);
    let (yf, stf) = run_r(first, 1e-9);
    println!("stiff: {} steps, M = 1e-12: {}, first order: {} steps", sts.accepted, st12.accepted, stf.accepted);
    // Components: X, then the quadratures (index shifted by the velocity).
    for (is, i_f) in [(0, 0), (2, 1), (3, 2), (4, 3)] {
        let err = (ys[is] - yf[i_f]).abs() / (1e-11 + 1e-9 * yf[i_f].abs());
        println!("stiff vs first order, component {is}: {err:.3} tol");
        assert!(err <= 10.0, "component {is}: {} vs {}", ys[is], yf[i_f]);
    }
    assert!(st12.accepted * 10 <= sts.accepted * 11, "{} vs {}", st12.accepted, sts.accepted);
}

/// Checkpoints: a JSON round trip (serde_json with `float_roundtrip`) resumes bit for bit.
#[test]
fn serde_roundtrip_resumes_identically() {
    let p = CubicPlate { m: 1e-3, eta: 1.0, k: 1e4, v: 0.5, kn: 1.0, c3: 4.0 };
    let mut ode = Rosenbrock::new(5, 1e-8, 1e-10).unwrap();
    let (mut t, mut y, mut sys) = (0.0, [0.1, 0.0, 0.0, 0.0, 0.0], p);
    for _ in 0..10 {
        ode.step(&mut sys, &mut t, &mut y, 1.0).unwrap();
    }
    let json = serde_json::to_string(&ode).unwrap();
    let mut copy: Rosenbrock = serde_json::from_str(&json).unwrap();
    assert_eq!(copy.last_step(), ode.last_step());
    let (mut t2, mut y2) = (t, y);
    for _ in 0..10 {
        ode.step(&mut sys, &mut t, &mut y, 1.0).unwrap();
        copy.step(&mut sys, &mut t2, &mut y2, 1.0).unwrap();
        assert_eq!((t, y), (t2, y2));
        assert_eq!(ode.dense_component(0, t - 1e-6).unwrap(), copy.dense_component(0, t - 1e-6).unwrap());
    }
    assert_eq!(ode.stats(), copy.stats());
    // A corrupt checkpoint is an error, not a panic.
    let bad = json.replacen("\"dim\":5", "\"dim\":3", 1);
    assert!(serde_json::from_str::<Rosenbrock>(&bad).is_err());
    let bad = json.replacen("\"dim\":5", "\"dim\":9", 1);
    assert!(serde_json::from_str::<Rosenbrock>(&bad).is_err());
}

/// Bounds of the dense output over a step contain its values on a fine grid (2001 points
/// per step, ends included), over random plates (from non-stiff to `M = 1e-9`, nonlinear
/// with quadratures) and random step limits.
fn check_bounds(p: CubicPlate, x0: f64, v0: f64, h_init: f64, t_max: f64) -> Result<(), TestCaseError> {
    let n = p.dim();
    let cfg = RosenbrockConfig { rtol: 1e-8, atol: 1e-10, h_init: Some(h_init), ..RosenbrockConfig::default() };
    let mut ode = Rosenbrock::with_config(n, cfg).unwrap();
    let mut y = [x0, v0, 0.0, 0.0, 0.0];
    let (mut t, mut sys) = (0.0, p);
    for _ in 0..4 {
        if t >= t_max {
            break;
        }
        ode.step(&mut sys, &mut t, &mut y[..n], t_max).unwrap();
        let (t0, t1) = ode.last_step().unwrap();
        for i in 0..n {
            let (lo, hi) = ode.component_bounds(i).unwrap();
            prop_assert!(lo <= hi);
            for k in 0..=2000 {
                let tk = if k == 2000 { t1 } else { t0 + (t1 - t0) * k as f64 / 2000.0 };
                let v = ode.dense_component(i, tk).unwrap();
                prop_assert!(lo <= v && v <= hi, "component {i} at {tk}: {v} outside [{lo}, {hi}]");
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(200),
        rng_seed: proptest::test_runner::RngSeed::Fixed(
            std::env::var("PROPTEST_RNG_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(20261124),
        ),
        ..ProptestConfig::default()
    })]

    #[test]
    fn component_bounds_contain_dense_values(
        lm in -9.0f64..1.0, first_order in any::<bool>(), leta in -2.0f64..2.0, lk in -1.0f64..6.0,
        c3 in 0.0f64..10.0, x0 in -2.0f64..2.0, v0 in -2.0f64..2.0, lh in -6.0f64..0.0, lt in -5.0f64..1.0,
    ) {
        let m = if first_order { 0.0 } else { 10f64.powf(lm) };
        let p = CubicPlate { m, eta: 10f64.powf(leta), k: 10f64.powf(lk), v: 0.5, kn: 1.0, c3 };
        check_bounds(p, x0, v0, 10f64.powf(lh), 10f64.powf(lt))?;
    }
}

/// Errors: every path returns an `OdeError` and leaves `t`, `y` unchanged.
#[test]
fn error_paths() {
    struct Nan {
        after: f64,
    }
    impl StiffSystem for Nan {
        fn rhs(&mut self, t: f64, _y: &[f64], d: &mut [f64]) {
            d[0] = if t > self.after { f64::NAN } else { 1.0 };
        }
        fn jacobian(&mut self, _t: f64, _y: &[f64], j: &mut [f64], ft: &mut [f64]) {
            j[0] = 0.0;
            ft[0] = 0.0;
        }
    }
    // NaN at the start.
    let mut ode = Rosenbrock::new(1, 1e-8, 1e-10).unwrap();
    let (mut t, mut y) = (2.0, [1.0]);
    assert_eq!(ode.step(&mut Nan { after: 1.0 }, &mut t, &mut y, 3.0), Err(OdeError::NonFiniteRhs { t: 2.0 }));
    assert_eq!((t, y), (2.0, [1.0]));
    // NaN beyond t = 1: creeps towards 1, then fails; never a NaN state.
    let (mut t, mut y) = (0.0, [0.0]);
    let err = loop {
        match ode.step(&mut Nan { after: 1.0 }, &mut t, &mut y, 2.0) {
            Ok(()) => assert!(t <= 1.0 && y[0].is_finite()),
            Err(e) => break e,
        }
    };
    assert!(matches!(err, OdeError::NonFiniteStep { .. } | OdeError::StepSizeUnderflow { .. }), "{err:?}");
    assert!(t <= 1.0 && (y[0] - t).abs() < 1e-12);
    // Non-finite Jacobian at the start.
    struct BadJac;
    impl StiffSystem for BadJac {
        fn rhs(&mut self, _t: f64, _y: &[f64], d: &mut [f64]) {
            d[0] = 0.0;
        }
        fn jacobian(&mut self, _t: f64, _y: &[f64], j: &mut [f64], ft: &mut [f64]) {
            j[0] = f64::INFINITY;
            ft[0] = 0.0;
        }
    }
    let (mut t, mut y) = (0.0, [1.0]);
    assert!(matches!(ode.step(&mut BadJac, &mut t, &mut y, 1.0), Err(OdeError::NonFiniteRhs { .. })));
    // Bad interval, bad state, wrong lengths.
    let mut sys = LinPlate { m: 1.0, eta: 1.0, k: 1.0, a: 0.0, b: 0.0 };
    let mut ode = Rosenbrock::new(2, 1e-8, 1e-10).unwrap();
    let (mut t, mut y) = (1.0, [1.0, 0.0]);
    assert!(matches!(ode.step(&mut sys, &mut t, &mut y, 1.0), Err(OdeError::InvalidInterval { .. })));
    assert!(matches!(ode.step(&mut sys, &mut t, &mut y, 0.5), Err(OdeError::InvalidInterval { .. })));
    assert!(matches!(ode.step(&mut sys, &mut t, &mut y, f64::NAN), Err(OdeError::InvalidInterval { .. })));
    let mut bad = [f64::NAN, 0.0];
    assert!(matches!(ode.step(&mut sys, &mut t, &mut bad, 2.0), Err(OdeError::NonFiniteState { .. })));
    assert!(matches!(ode.step(&mut sys, &mut t, &mut y[..1], 2.0), Err(OdeError::DimensionMismatch { .. })));
    assert_eq!((t, y), (1.0, [1.0, 0.0]));
    // Dense output misuse.
    assert_eq!(ode.dense_component(0, 1.0), Err(OdeError::NoDenseOutput));
    assert_eq!(ode.component_bounds(0), Err(OdeError::NoDenseOutput));
    ode.step(&mut sys, &mut t, &mut y, 1.5).unwrap();
    let (t0, t1) = ode.last_step().unwrap();
    assert!(matches!(ode.dense_component(0, t1 + 1.0), Err(OdeError::OutsideDenseInterval { .. })));
    assert!(matches!(ode.dense_component(2, t0), Err(OdeError::DimensionMismatch { .. })));
    assert!(matches!(ode.component_bounds(2), Err(OdeError::DimensionMismatch { .. })));
    let mut out = [0.0; 3];
    assert!(matches!(ode.dense(t0, &mut out), Err(OdeError::DimensionMismatch { .. })));
    // Too many rejections: a huge first step on a fast oscillation with a limit of 1.
    let cfg = RosenbrockConfig { h_init: Some(10.0), max_consecutive_rejections: 1, ..RosenbrockConfig::default() };
    let mut ode = Rosenbrock::with_config(2, cfg).unwrap();
    let mut fast = LinPlate { m: 1.0, eta: 0.0, k: 1e4, a: 0.0, b: 0.0 };
    let (mut t, mut y) = (0.0, [1.0, 0.0]);
    assert!(matches!(ode.step(&mut fast, &mut t, &mut y, 100.0), Err(OdeError::TooManyRejections { .. })));
    assert_eq!((t, y), (0.0, [1.0, 0.0]));
}

#[test]
fn invalid_config_names_the_field() {
    let d = RosenbrockConfig::default;
    let cases: [(&str, RosenbrockConfig); 11] = [
        ("rtol", RosenbrockConfig { rtol: 0.0, ..d() }),
        ("rtol", RosenbrockConfig { rtol: f64::NAN, ..d() }),
        ("atol", RosenbrockConfig { atol: 0.0, ..d() }),
        ("atol", RosenbrockConfig { atol: f64::INFINITY, ..d() }),
        ("safety", RosenbrockConfig { safety: 1.0, ..d() }),
        ("fac_min", RosenbrockConfig { fac_min: 0.0, ..d() }),
        ("fac_max", RosenbrockConfig { fac_max: 1.0, ..d() }),
        ("h_max", RosenbrockConfig { h_max: Some(0.0), ..d() }),
        ("h_max", RosenbrockConfig { h_max: Some(f64::NAN), ..d() }),
        ("h_init", RosenbrockConfig { h_init: Some(-1.0), ..d() }),
        ("max_consecutive_rejections", RosenbrockConfig { max_consecutive_rejections: 0, ..d() }),
    ];
    for (field, cfg) in cases {
        match Rosenbrock::with_config(2, cfg) {
            Err(OdeError::InvalidConfig { name, .. }) => assert_eq!(name, field),
            other => panic!("{field}: {other:?}"),
        }
    }
    assert!(matches!(Rosenbrock::new(2, 1e-20, 1e-10), Err(OdeError::InvalidConfig { name: "rtol", .. })));
    assert!(matches!(Rosenbrock::new(9, 1e-8, 1e-10), Err(OdeError::DimensionMismatch { .. })));
}

/// `h_max` bounds every step.
#[test]
fn h_max_bounds_the_steps() {
    let cfg = RosenbrockConfig { h_max: Some(0.05), ..RosenbrockConfig::default() };
    let mut ode = Rosenbrock::with_config(2, cfg).unwrap();
    let mut sys = LinPlate { m: 1.0, eta: 10.0, k: 1.0, a: 1.0, b: 0.0 };
    let (mut t, mut y) = (0.0, [0.0, 0.0]);
    while t < 2.0 {
        ode.step(&mut sys, &mut t, &mut y, 2.0).unwrap();
        let (t0, t1) = ode.last_step().unwrap();
        assert!(t1 - t0 <= 0.05 * (1.0 + 1e-12));
    }
    assert!(ode.stats().accepted >= 40);
}
