//! Counters, FSAL/restart bookkeeping, step-size memory across `t_max` cuts, checkpoints.

use crate::ode_support;

use ode_support::Driven;
use std::cell::Cell;

use stickslip::ode::{Dop853, OdeStats, OdeSystem};

/// Work accounting: an attempt costs 11 RHS evaluations (stages 2..12; stage 1 is the FSAL
/// derivative); an accepted step 4 more (FSAL at the new point + 3 dense-output stages); a
/// restart 1; Hairer's initial step estimate 1.
fn expected_evals(st: &OdeStats, hinit: u64) -> u64 {
    11 * (st.accepted + st.rejected) + 4 * st.accepted + st.restarts + hinit
}

#[test]
fn rhs_evaluation_count_is_consistent() {
    let sys = Driven::LIGHT;
    // Free steps (with some rejections), then steps cut every 0.03 with resets.
    let mut ode = Dop853::new(3, 1e-6, 1e-8).unwrap();
    let (mut t, mut y) = (0.0, sys.y0());
    let counted = Cell::new(0u64);
    let mut counting = |tt: f64, yy: &[f64], d: &mut [f64]| {
        counted.set(counted.get() + 1);
        let mut s = sys;
        s.rhs(tt, yy, d);
    };
    while t < 20.0 {
        ode.step(&mut counting, &mut t, &mut y, 20.0).unwrap();
    }
    let st = ode.stats();
    assert!(st.rejected > 0, "want some rejections: {st:?}");
    assert_eq!(st.restarts, 1);
    assert_eq!(st.rhs_evals, expected_evals(&st, 1));
    let mut k = 1;
    while t < 23.0 {
        let t_max = 20.0 + f64::from(k) * 0.03;
        ode.step(&mut counting, &mut t, &mut y, t_max).unwrap();
        if t == t_max {
            ode.reset();
            k += 1;
        }
    }
    let st = ode.stats();
    eprintln!("{st:?}");
    assert_eq!(st.rhs_evals, expected_evals(&st, 1));
    assert_eq!(st.rhs_evals, counted.get());
    // 100 resets; the last one takes effect at the next step.
    assert_eq!(st.restarts, 1 + 99);
    ode.step(&mut counting, &mut t, &mut y, 1e3).unwrap();
    assert_eq!(ode.stats().restarts, 1 + 100);
    // Without resets, FSAL: 15 evaluations per accepted step.
    let before = ode.stats();
    for _ in 0..10 {
        ode.step(&mut counting, &mut t, &mut y, 1e3).unwrap();
    }
    let after = ode.stats();
    let (acc, rej) = (after.accepted - before.accepted, after.rejected - before.rejected);
    assert_eq!(after.rhs_evals - before.rhs_evals, 15 * acc + 11 * rej);
    assert_eq!(after.restarts, before.restarts);
}

/// Changing `y` between steps (e.g. the engine zeroes a quadrature) is detected and the FSAL
/// derivative recomputed, without an explicit `reset`.
#[test]
fn state_change_between_steps_forces_a_restart() {
    let mut ode = Dop853::new(1, 1e-10, 1e-12).unwrap();
    let mut f = |_t: f64, y: &[f64], d: &mut [f64]| d[0] = -y[0];
    let (mut t, mut y) = (0.0, [1.0]);
    ode.step(&mut f, &mut t, &mut y, 10.0).unwrap();
    assert_eq!(ode.stats().restarts, 1);
    ode.step(&mut f, &mut t, &mut y, 10.0).unwrap();
    assert_eq!(ode.stats().restarts, 1);
    y[0] = 2.0;
    let t1 = t;
    ode.step(&mut f, &mut t, &mut y, 10.0).unwrap();
    assert_eq!(ode.stats().restarts, 2);
    assert!((y[0] - 2.0 * (-(t - t1)).exp()).abs() < 1e-10);
}

/// A step cut short by `t_max` does not shrink the proposal for the next free step.
#[test]
fn proposal_survives_cut_steps() {
    let sys = Driven::LIGHT;
    let mut ode = Dop853::new(3, 1e-8, 1e-10).unwrap();
    let (mut t, mut y) = (0.0, sys.y0());
    for _ in 0..20 {
        ode.step(&mut sys.clone(), &mut t, &mut y, 100.0).unwrap();
    }
    let h_free = ode.h_proposal().unwrap();
    assert!(h_free > 0.1, "{h_free}");
    for _ in 0..50 {
        let t_max = t + 1e-3;
        ode.step(&mut sys.clone(), &mut t, &mut y, t_max).unwrap();
        assert_eq!(t, t_max);
        ode.reset();
    }
    let h_after = ode.h_proposal().unwrap();
    assert!(h_after >= h_free, "{h_after} < {h_free}");
    // ... and never grows beyond 6 x the steps actually validated.
    assert!(h_after <= 6.0 * h_free);
}

/// Advances both integrators to the same `t_max` grid (several steps per segment) and
/// compares: bit for bit, or to the tolerance level (the step sequences may then differ).
fn run_pair(a: &mut Dop853, b: &mut Dop853, t: f64, y: [f64; 3], exact: bool) {
    let sys = Driven::LIGHT;
    let (mut ta, mut ya, mut tb, mut yb) = (t, y, t, y);
    for k in 41..=80 {
        let t_max = f64::from(k) * 0.37;
        while ta < t_max {
            a.step(&mut sys.clone(), &mut ta, &mut ya, t_max).unwrap();
            if exact {
                b.step(&mut sys.clone(), &mut tb, &mut yb, t_max).unwrap();
                assert_eq!((ta.to_bits(), ya.map(f64::to_bits)), (tb.to_bits(), yb.map(f64::to_bits)));
                assert_eq!(a.locate_component(0, 0.3).unwrap(), b.locate_component(0, 0.3).unwrap());
            }
        }
        while tb < t_max {
            b.step(&mut sys.clone(), &mut tb, &mut yb, t_max).unwrap();
        }
        assert_eq!(ta, tb);
        for i in 0..3 {
            assert!((ya[i] - yb[i]).abs() <= 1e-9 * (1.0 + ya[i].abs()), "{ya:?} vs {yb:?}");
        }
    }
    if exact {
        assert_eq!(a.stats(), b.stats());
    }
}

fn midway() -> (Dop853, f64, [f64; 3]) {
    let sys = Driven::LIGHT;
    let mut a = Dop853::new(3, 1e-10, 1e-12).unwrap();
    let (mut t, mut y) = (0.0, sys.y0());
    for k in 1..=40 {
        a.step(&mut sys.clone(), &mut t, &mut y, f64::from(k) * 0.37).unwrap();
    }
    (a, t, y)
}

/// Checkpoint: the serialised state is complete. Through a lossless serde data model
/// (`serde_json::Value` keeps every f64 exactly) the resumed run is identical bit for bit,
/// counters included (scratch buffers are not serialised and are re-allocated on first use).
#[test]
fn serde_roundtrip_resumes_identically() {
    let (mut a, t, y) = midway();
    let v = serde_json::to_value(&a).unwrap();
    let mut b: Dop853 = serde_json::from_value(v.clone()).unwrap();
    assert_eq!(serde_json::to_value(&b).unwrap(), v);
    run_pair(&mut a, &mut b, t, y, true);
}

/// Through JSON *text*, serde_json (without its `float_roundtrip` feature, as in this crate's
/// Cargo.toml today) may parse a float 1 ulp off (e.g. the step-size proposal), so the
/// resumed run takes slightly different steps and agrees only to the tolerance.
/// Bit-exact text checkpoints need `serde_json = { features = ["float_roundtrip"] }`.
#[test]
fn serde_json_text_roundtrip_is_close() {
    let (mut a, t, y) = midway();
    let json = serde_json::to_string(&a).unwrap();
    let mut b: Dop853 = serde_json::from_str(&json).unwrap();
    run_pair(&mut a, &mut b, t, y, false);
}

/// A corrupt checkpoint is a deserialisation error, not a panic later.
#[test]
fn corrupt_checkpoint_is_rejected() {
    let (a, _, _) = midway();
    let mut v = serde_json::to_value(&a).unwrap();
    v["cont"].as_array_mut().unwrap().pop();
    let e = serde_json::from_value::<Dop853>(v).unwrap_err().to_string();
    assert!(e.contains("vector lengths"), "{e}");
    let mut v = serde_json::to_value(&a).unwrap();
    v["h_prop"] = serde_json::json!(-1.0);
    assert!(serde_json::from_value::<Dop853>(v).is_err());
    let mut v = serde_json::to_value(&a).unwrap();
    v["cfg"]["atol"] = serde_json::json!(0.0);
    assert!(serde_json::from_value::<Dop853>(v).is_err());
}

/// `h_max` bounds every step, whatever the proposal (initial, set by hand, or grown).
#[test]
fn h_max_bounds_every_step() {
    let cfg = stickslip::ode::Dop853Config { h_max: Some(0.05), h_init: Some(1.0), ..Default::default() };
    let mut ode = Dop853::with_config(3, cfg).unwrap();
    let sys = Driven::PLATE;
    let (mut t, mut y) = (0.0, sys.y0());
    for k in 0..200 {
        if k == 100 {
            ode.set_h_proposal(10.0);
        }
        ode.step(&mut sys.clone(), &mut t, &mut y, 1e3).unwrap();
        let (a, b) = ode.last_step().unwrap();
        assert!(b - a <= 0.05 * (1.0 + 1e-12), "step {k}: {}", b - a);
    }
}
