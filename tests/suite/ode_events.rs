//! Event location on the dense output: crossings inside a step, exactly at a step end, no
//! false crossings, non-monotone event functions, errors.

use std::f64::consts::LN_2;

use stickslip::ode::{Dop853, OdeError};

/// Cumulative hazard `H' = e^t` (`H = e^t - 1`) and a decaying `y' = -y`: both reach their
/// level (`H = 1`, `y = 0.5`) at `t = ln 2`.
fn hazard(t: f64, y: &[f64], d: &mut [f64]) {
    d[0] = t.exp();
    d[1] = -y[1];
}

#[test]
fn crossing_inside_a_free_step() {
    let mut ode = Dop853::new(2, 1e-13, 1e-15).unwrap();
    let (mut t, mut y) = (0.0, [0.0, 1.0]);
    let mut found = None;
    for _ in 0..1000 {
        ode.step(&mut hazard, &mut t, &mut y, 5.0).unwrap();
        let a = ode.locate_component(0, 1.0).unwrap();
        let b = ode.locate(|_t, y| 0.5 - y[1]).unwrap();
        if let Some(ta) = a {
            found = Some((ta, b.expect("both functions cross at ln 2"), ode.last_step().unwrap()));
            break;
        }
        assert_eq!(b, None, "the decay crossed in a step where the hazard did not");
    }
    let (ta, tb, (t_old, t_new)) = found.expect("crossing not found");
    eprintln!("hazard: {:.3e}, decay: {:.3e}, step [{t_old}, {t_new}]", ta - LN_2, tb - LN_2);
    assert!(
        t_old < LN_2 && LN_2 < t_new && t_new - LN_2 > 1e-3 && LN_2 - t_old > 1e-3,
        "crossing should be inside the step"
    );
    assert!((ta - LN_2).abs() < 1e-12, "{:e}", ta - LN_2);
    assert!((tb - LN_2).abs() < 1e-12, "{:e}", tb - LN_2);
    // The returned time is where the dense output has reached the level.
    assert!(ode.dense_component(0, ta).unwrap() >= 1.0);
}

#[test]
fn crossing_with_steps_cut_every_0_03() {
    let mut ode = Dop853::new(2, 1e-10, 1e-12).unwrap();
    let (mut t, mut y) = (0.0, [0.0, 1.0]);
    let mut k = 1;
    let mut hits = Vec::new();
    while t < 1.0 {
        let t_max = f64::from(k) * 0.03;
        ode.step(&mut hazard, &mut t, &mut y, t_max).unwrap();
        if t == t_max {
            k += 1;
            ode.reset();
        }
        if let Some(tc) = ode.locate_component(0, 1.0).unwrap() {
            hits.push(tc);
        }
    }
    assert_eq!(hits.len(), 1, "{hits:?}");
    assert!((hits[0] - LN_2).abs() < 1e-12, "{:e}", hits[0] - LN_2);
}

#[test]
fn crossing_exactly_at_a_step_end_is_reported_once() {
    let mut ode = Dop853::new(2, 1e-10, 1e-12).unwrap();
    let (mut t, mut y) = (0.0, [0.0, 1.0]);
    let t_end = 0.6;
    while t < t_end {
        ode.step(&mut hazard, &mut t, &mut y, t_end).unwrap();
    }
    assert_eq!(t, t_end);
    // Level equal to the state reached at the step end: the crossing is the step end itself.
    let level = y[0];
    assert_eq!(ode.locate_component(0, level).unwrap(), Some(t_end));
    assert_eq!(ode.locate(|t, _| t - t_end).unwrap(), Some(t_end));
    assert_eq!(ode.locate(|_, y| y[0] - level).unwrap(), Some(t_end));
    // The next step starts on the level (g = 0 >= 0): no second report.
    ode.step(&mut hazard, &mut t, &mut y, 2.0).unwrap();
    assert_eq!(ode.locate_component(0, level).unwrap(), None);
    assert_eq!(ode.locate(|t, _| t - t_end).unwrap(), None);
}

#[test]
fn no_false_crossings() {
    let mut ode = Dop853::new(2, 1e-10, 1e-12).unwrap();
    let (mut t, mut y) = (0.0, [0.0, 1.0]);
    let mut n_steps = 0;
    while t < 3.0 {
        ode.step(&mut hazard, &mut t, &mut y, 3.0).unwrap();
        n_steps += 1;
        // Level never reached on [0, 3]: e^3 - 1 = 19.1.
        assert_eq!(ode.locate_component(0, 25.0).unwrap(), None);
        // A level reached before this step (or at its start): not a crossing of this step.
        let (t_old, _) = ode.last_step().unwrap();
        if t_old > 0.5 {
            assert_eq!(ode.locate_component(0, 0.5f64.exp() - 1.0).unwrap(), None);
        }
        // Decreasing function crossing downwards only: never an upward crossing.
        assert_eq!(ode.locate(|_t, y| y[1] - 0.3).unwrap(), None);
    }
    assert!(n_steps >= 3);
}

/// `sin t` rises above 0.999 and falls back inside one step: both ends below the level,
/// found by the interior sampling; the upward crossing is `asin(0.999)`.
#[test]
fn non_monotone_crossing_inside_one_step() {
    let mut osc = |_t: f64, y: &[f64], d: &mut [f64]| {
        d[0] = y[1];
        d[1] = -y[0];
    };
    let mut ode = Dop853::new(2, 1e-10, 1e-12).unwrap();
    let t0 = 1.45f64;
    let (mut t, mut y) = (t0, [t0.sin(), t0.cos()]);
    ode.step_fixed(&mut osc, &mut t, &mut y, 0.25).unwrap();
    assert!(y[0] < 0.999 && t0.sin() < 0.999);
    let tc = ode.locate_component(0, 0.999).unwrap().expect("crossing inside the step");
    let exact = 0.999f64.asin();
    eprintln!("non-monotone: {:.3e}", tc - exact);
    assert!((tc - exact).abs() < 1e-10, "{:e}", tc - exact);
    // The root finder itself: the returned point has reached the level, a point 1e-14 earlier
    // has not (the dense polynomial's own crossing to ~1e-14 relative).
    assert!(ode.dense_component(0, tc).unwrap() >= 0.999);
    assert!(ode.dense_component(0, tc - 1e-14 * tc).unwrap() < 0.999);
    // The downward crossing is not an upward crossing of y - level, but it is one of level - y.
    let td = ode.locate(|_, y| 0.999 - y[0]).unwrap().unwrap();
    assert!((td - (std::f64::consts::PI - exact)).abs() < 1e-10);
}

#[test]
fn locate_errors() {
    let mut ode = Dop853::new(2, 1e-10, 1e-12).unwrap();
    assert_eq!(ode.locate_component(0, 1.0), Err(OdeError::NoDenseOutput));
    assert_eq!(ode.locate(|_, _| 1.0), Err(OdeError::NoDenseOutput));
    let (mut t, mut y) = (0.0, [0.0, 1.0]);
    ode.step(&mut hazard, &mut t, &mut y, 1.0).unwrap();
    assert!(matches!(ode.locate(|t, _| if t > 0.0 { f64::NAN } else { -1.0 }), Err(OdeError::NonFiniteEvent { .. })));
    assert!(matches!(ode.locate_component(2, 1.0), Err(OdeError::DimensionMismatch { .. })));
    let (t_old, t_new) = ode.last_step().unwrap();
    assert!(matches!(ode.dense_component(0, t_new + 1e-6), Err(OdeError::OutsideDenseInterval { .. })));
    assert!(matches!(ode.dense_component(0, t_old - 1e-6), Err(OdeError::OutsideDenseInterval { .. })));
    // Ends are exact.
    assert_eq!(ode.dense_component(0, t_new).unwrap(), y[0]);
    assert_eq!(ode.dense_component(0, t_old).unwrap(), 0.0);
}

/// The ends of the dense output are the accepted states bit for bit (not `y_old + (y_new -
/// y_old)`, which may differ in the last bit), so a level reached exactly at a step end is
/// seen by `locate` in that step.
#[test]
fn dense_output_ends_are_the_accepted_states() {
    let mut sys = |t: f64, y: &[f64], d: &mut [f64]| {
        d[0] = y[1];
        d[1] = -y[0] + 0.3 * (1.7 * t).sin();
        d[2] = (0.2 * y[0]).exp();
    };
    let mut ode = Dop853::new(3, 1e-10, 1e-12).unwrap();
    let (mut t, mut y) = (0.0, [0.731, -0.217, 0.0]);
    let mut out = [0.0; 3];
    for k in 1..=300 {
        let y_old = y;
        ode.step(&mut sys, &mut t, &mut y, f64::from(k) * 0.37).unwrap();
        let (t_old, t_new) = ode.last_step().unwrap();
        ode.dense(t_new, &mut out).unwrap();
        assert_eq!(out.map(f64::to_bits), y.map(f64::to_bits), "step {k}");
        ode.dense(t_old, &mut out).unwrap();
        assert_eq!(out.map(f64::to_bits), y_old.map(f64::to_bits), "step {k}");
    }
}
