//! Failure modes are errors, never panics, hangs or NaN; `t` and `y` are untouched on error.

use stickslip::ode::{Dop853, Dop853Config, MIN_RTOL, OdeError};

#[test]
fn nan_rhs_is_an_error() {
    let mut ode = Dop853::new(2, 1e-10, 1e-12).unwrap();
    let mut nan = |_t: f64, _y: &[f64], d: &mut [f64]| d.fill(f64::NAN);
    let (mut t, mut y) = (0.0, [1.0, 2.0]);
    assert_eq!(ode.step(&mut nan, &mut t, &mut y, 1.0), Err(OdeError::NonFiniteRhs { t: 0.0 }));
    assert_eq!((t, y), (0.0, [1.0, 2.0]));
    let mut inf = |_t: f64, _y: &[f64], d: &mut [f64]| {
        d[0] = 1.0;
        d[1] = f64::INFINITY;
    };
    assert_eq!(ode.step(&mut inf, &mut t, &mut y, 1.0), Err(OdeError::NonFiniteRhs { t: 0.0 }));
}

/// The RHS is NaN beyond t = 1 (a domain error the solution runs into): trial steps that
/// reach past 1 are retried smaller; the integration creeps up to 1 and then fails with
/// `NonFiniteStep` (never a NaN in the state, never a hang).
#[test]
fn nan_beyond_a_time_is_an_error_after_retries() {
    let mut ode = Dop853::new(1, 1e-10, 1e-12).unwrap();
    let mut f = |t: f64, _y: &[f64], d: &mut [f64]| d[0] = if t > 1.0 { f64::NAN } else { 1.0 };
    let (mut t, mut y) = (0.0, [0.0]);
    let mut result = Ok(());
    for _ in 0..10_000 {
        result = ode.step(&mut f, &mut t, &mut y, 5.0);
        assert!(y[0].is_finite() && t <= 1.0);
        if result.is_err() {
            break;
        }
    }
    eprintln!("{result:?} at t = {t}, {:?}", ode.stats());
    assert!(matches!(result, Err(OdeError::NonFiniteStep { .. })), "{result:?}");
    assert!((y[0] - t).abs() < 1e-12);
    assert!(ode.stats().rejected_non_finite > 0);
}

/// The solution blows up (y' = y^2, y = 1/(1 - t)): an error near t = 1 (the numerical pole
/// may sit a hair beyond the exact one), not a NaN or a hang.
#[test]
fn blow_up_is_an_error() {
    let mut ode = Dop853::new(1, 1e-10, 1e-12).unwrap();
    let mut f = |_t: f64, y: &[f64], d: &mut [f64]| d[0] = y[0] * y[0];
    let (mut t, mut y) = (0.0, [1.0]);
    let mut result = Ok(());
    let mut steps = 0;
    while result.is_ok() && t < 2.0 {
        result = ode.step(&mut f, &mut t, &mut y, 2.0);
        steps += 1;
        assert!(steps < 100_000, "hangs");
    }
    eprintln!("{result:?} at t = {t}, y = {}, {} steps, {:?}", y[0], steps, ode.stats());
    assert!(result.is_err());
    assert!(t < 1.0 + 1e-9 && y[0].is_finite() && y[0] > 1e10);
}

/// Tolerances below double precision are refused up front (`MIN_RTOL = 4 eps`): with
/// `rtol = 1e-20` the error estimate is round-off and a stiff problem crawls with h ~ 1e-8
/// (no underflow, no progress). At `MIN_RTOL` itself a stiff problem completes in a bounded
/// number of steps; an `atol` far below the solution's round-off near y = 0 fails cleanly.
#[test]
fn too_tight_tolerances() {
    assert!(matches!(Dop853::new(1, 1e-20, 1e-30), Err(OdeError::InvalidConfig { name: "rtol", .. })));
    let lam = 1e4;
    let mut f = |t: f64, y: &[f64], d: &mut [f64]| d[0] = -lam * (y[0] - t.cos());
    let mut ode = Dop853::new(1, MIN_RTOL, 1e-300).unwrap();
    let (mut t, mut y) = (0.0, [1.0]);
    let mut calls = 0;
    while t < 1.0 {
        ode.step(&mut f, &mut t, &mut y, 1.0).unwrap();
        calls += 1;
        assert!(calls < 100_000, "too many steps");
    }
    let approx = 1f64.cos() + 1f64.sin() / lam - 1f64.cos() / (lam * lam);
    eprintln!("stiff at MIN_RTOL: y - approx = {:e}, {:?}", y[0] - approx, ode.stats());
    assert!((y[0] - approx).abs() < 1e-10);
    // A quadrature starting at 0 with atol = 1e-300: the first step cannot meet the tolerance.
    let mut q = |t: f64, _y: &[f64], d: &mut [f64]| d[0] = (3.0 * t).cos();
    let mut ode = Dop853::new(1, MIN_RTOL, 1e-300).unwrap();
    let (mut t, mut y) = (0.0, [0.0]);
    let mut result = Ok(());
    for _ in 0..10_000 {
        result = ode.step(&mut q, &mut t, &mut y, 1.0);
        if result.is_err() || t >= 1.0 {
            break;
        }
    }
    eprintln!("quadrature, atol 1e-300: {result:?} at t = {t}, {:?}", ode.stats());
    assert!(y[0].is_finite());
    assert!(
        matches!(result, Ok(()) | Err(OdeError::StepSizeUnderflow { .. } | OdeError::TooManyRejections { .. })),
        "{result:?}"
    );
}

/// A stiff problem (lambda = -1e4) with a tight tolerance: the explicit method is limited by
/// stability to h ~ 6e-4; it completes within a bounded number of steps and stays accurate.
#[test]
fn stiff_problem_completes_in_bounded_steps() {
    let lam = 1e4;
    let mut f = |t: f64, y: &[f64], d: &mut [f64]| d[0] = -lam * (y[0] - t.cos());
    let mut ode = Dop853::new(1, 1e-12, 1e-14).unwrap();
    let (mut t, mut y) = (0.0, [1.0]);
    let mut calls = 0;
    while t < 1.0 {
        ode.step(&mut f, &mut t, &mut y, 1.0).unwrap();
        calls += 1;
        assert!(calls < 50_000, "too many steps");
    }
    // Slow manifold: y ~ cos t + sin t / lam + O(1/lam^2).
    let approx = 1f64.cos() + 1f64.sin() / lam - 1f64.cos() / (lam * lam);
    let st = ode.stats();
    eprintln!("stiff: y = {}, approx {approx}, {st:?}", y[0]);
    assert!((y[0] - approx).abs() < 1e-10);
    assert!(st.accepted > 500, "stability should limit the step");
}

/// An unannounced jump of the RHS in time: steps across it are rejected until the step is
/// small enough; with a small rejection limit this is `TooManyRejections`, with the default
/// the jump is crossed.
#[test]
fn unannounced_discontinuity_and_rejection_limit() {
    let mut f = |t: f64, _y: &[f64], d: &mut [f64]| d[0] = if t < 0.5 { 0.0 } else { 1.0 };
    let cfg = Dop853Config { rtol: 1e-10, atol: 1e-12, max_consecutive_rejections: 3, ..Dop853Config::default() };
    let mut ode = Dop853::with_config(1, cfg).unwrap();
    ode.set_h_proposal(0.3);
    let (mut t, mut y) = (0.0, [1.0]);
    let mut result = Ok(());
    for _ in 0..100 {
        result = ode.step(&mut f, &mut t, &mut y, 2.0);
        if result.is_err() {
            break;
        }
    }
    assert!(matches!(result, Err(OdeError::TooManyRejections { rejections: 3, .. })), "{result:?}");
    let (t_fail, y_fail) = (t, y);
    assert!(t_fail < 0.5 && y_fail == [1.0]);
    // Default limit: crosses the jump (y = 1 + (t - 0.5) afterwards, to ~ atol-ish accuracy).
    let mut ode = Dop853::new(1, 1e-10, 1e-12).unwrap();
    let (mut t, mut y) = (0.0, [1.0]);
    let mut calls = 0;
    while t < 2.0 {
        ode.step(&mut f, &mut t, &mut y, 2.0).unwrap();
        calls += 1;
        assert!(calls < 10_000);
    }
    eprintln!("jump: y(2) - 2.5 = {:e}, {:?}", y[0] - 2.5, ode.stats());
    assert!((y[0] - 2.5).abs() < 1e-8);
}

#[test]
fn invalid_inputs() {
    assert!(matches!(Dop853::new(0, 1e-10, 1e-12), Err(OdeError::DimensionMismatch { .. })));
    assert!(matches!(Dop853::new(1, 1e-10, 0.0), Err(OdeError::InvalidConfig { name: "atol", .. })));
    assert!(matches!(Dop853::new(1, f64::NAN, 1e-12), Err(OdeError::InvalidConfig { name: "rtol", .. })));
    assert!(matches!(Dop853::new(1, -1.0, 1e-12), Err(OdeError::InvalidConfig { name: "rtol", .. })));
    for cfg in [
        Dop853Config { safety: 1.0, ..Default::default() },
        Dop853Config { fac_min: 0.0, ..Default::default() },
        Dop853Config { fac_max: 1.0, ..Default::default() },
        Dop853Config { beta: 0.3, ..Default::default() },
        Dop853Config { h_max: Some(0.0), ..Default::default() },
        Dop853Config { h_init: Some(f64::INFINITY), ..Default::default() },
        Dop853Config { event_samples: 0, ..Default::default() },
        Dop853Config { max_consecutive_rejections: 0, ..Default::default() },
    ] {
        assert!(matches!(Dop853::with_config(1, cfg), Err(OdeError::InvalidConfig { .. })));
    }
    let mut ode = Dop853::new(2, 1e-10, 1e-12).unwrap();
    let mut f = |_t: f64, y: &[f64], d: &mut [f64]| d.copy_from_slice(y);
    let mut t = 0.0;
    assert!(matches!(
        ode.step(&mut f, &mut t, &mut [1.0], 1.0),
        Err(OdeError::DimensionMismatch { expected: 2, got: 1 })
    ));
    assert!(matches!(ode.step(&mut f, &mut t, &mut [1.0, 1.0], 0.0), Err(OdeError::InvalidInterval { .. })));
    assert!(matches!(ode.step(&mut f, &mut t, &mut [1.0, 1.0], -1.0), Err(OdeError::InvalidInterval { .. })));
    assert!(matches!(ode.step(&mut f, &mut t, &mut [1.0, 1.0], f64::NAN), Err(OdeError::InvalidInterval { .. })));
    assert!(matches!(ode.step(&mut f, &mut t, &mut [f64::NAN, 1.0], 1.0), Err(OdeError::NonFiniteState { .. })));
    assert!(matches!(ode.step_fixed(&mut f, &mut t, &mut [1.0, 1.0], -0.1), Err(OdeError::InvalidInterval { .. })));
    assert!(matches!(ode.dense_component(0, 0.0), Err(OdeError::NoDenseOutput)));
    let mut out = [0.0; 3];
    assert!(matches!(ode.dense(0.0, &mut out), Err(OdeError::DimensionMismatch { .. })));
    // Errors display.
    let e = OdeError::StepSizeUnderflow { t: 1.0, h: 1e-20 };
    assert!(e.to_string().contains("underflow"));
}

/// A step whose limit is a hair after t (an event a few ulps away) is taken, not an error.
#[test]
fn tiny_steps_to_close_limits_are_fine() {
    let mut ode = Dop853::new(1, 1e-10, 1e-12).unwrap();
    let mut f = |_t: f64, y: &[f64], d: &mut [f64]| d[0] = -y[0];
    let (mut t, mut y) = (1000.0, [1.0]);
    ode.step(&mut f, &mut t, &mut y, 1000.5).unwrap();
    let h_prop = ode.h_proposal().unwrap();
    let next = f64::from_bits(t.to_bits() + 1);
    ode.reset();
    ode.step(&mut f, &mut t, &mut y, next).unwrap();
    assert_eq!(t, next);
    // The proposal survives the sliver step (it was cut short by t_max).
    assert!(ode.h_proposal().unwrap() >= h_prop);
}

/// A NaN returned at any stage rejects the trial step, even when it would not reach the new
/// state (a RHS that ignores `y` absorbs a NaN argument): no accepted step ever used a NaN.
#[test]
fn no_accepted_step_uses_a_nan_stage() {
    use stickslip::ode::coefficients::C;
    let window = (0.5, 0.5 + 1e-2);
    let mut f = |t: f64, _y: &[f64], d: &mut [f64]| {
        d[0] = if t >= window.0 && t <= window.1 { f64::NAN } else { 1.0 + 0.1 * t };
    };
    for h0 in (1..=60).map(|i| 0.05 * f64::from(i)) {
        let mut ode = Dop853::with_config(1, Dop853Config { h_init: Some(h0), ..Dop853Config::default() }).unwrap();
        let (mut t, mut y) = (0.0, [0.0]);
        for _ in 0..1000 {
            if ode.step(&mut f, &mut t, &mut y, 5.0).is_err() || t >= 5.0 {
                break;
            }
            let (t_old, t_new) = ode.last_step().unwrap();
            let h = t_new - t_old;
            for (j, c) in C.iter().enumerate() {
                let ts = t_old + c * h;
                assert!(
                    !(ts >= window.0 && ts <= window.1),
                    "h0 {h0}: accepted step [{t_old}, {t_new}] evaluated NaN at stage {j}"
                );
            }
        }
    }
}
