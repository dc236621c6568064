//! Adaptive accuracy on the damped driven oscillator `M X'' + eta X' + k X = a + b t` (plus
//! the quadrature `Q' = X`) against its closed form, over t in [0, 50]: free steps, steps cut
//! short every 0.03 by `t_max` (the engine's pattern), the same with `reset` at each limit,
//! and a forcing that jumps at each limit (a real discontinuity, handled by `reset`).

use crate::ode_support;

use ode_support::Driven;
use stickslip::ode::{Dop853, Dop853Config, OdeStats};

const T_END: f64 = 50.0;
const EVENT_DT: f64 = 0.03;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    Free,
    Limited,
    LimitedReset,
}

/// Result of one run: scaled global errors `max_i max_t |y_i - exact_i| / (atol + rtol
/// max_t |exact_i|)` at the step ends and at three dense points inside every step, the
/// largest relative error `max_i max_t |y_i - exact_i| / max_t |exact_i|`, and the counters.
struct Outcome {
    end: f64,
    dense: f64,
    rel: f64,
    stats: OdeStats,
}

fn run(sys: Driven, rtol: f64, h_max: Option<f64>, mode: Mode) -> Outcome {
    let atol = rtol * 1e-2;
    let mut ode = Dop853::with_config(3, Dop853Config { rtol, atol, h_max, ..Dop853Config::default() }).unwrap();
    let mut y = sys.y0();
    let mut t = 0.0;
    let mut scale = [0.0f64; 3];
    let mut err_end = [0.0f64; 3];
    let mut err_dense = [0.0f64; 3];
    let record = |t: f64, y: &[f64], errs: &mut [f64; 3], scale: &mut [f64; 3]| {
        let ex = sys.exact(t);
        for i in 0..3 {
            scale[i] = scale[i].max(ex[i].abs());
            errs[i] = errs[i].max((y[i] - ex[i]).abs());
        }
    };
    let mut k = 1u32;
    let mut out = [0.0; 3];
    let mut guard = 0;
    while t < T_END {
        let t_max = match mode {
            Mode::Free => T_END,
            _ => (f64::from(k) * EVENT_DT).min(T_END),
        };
        ode.step(&mut sys.clone(), &mut t, &mut y, t_max).unwrap();
        let (t_old, t_new) = ode.last_step().unwrap();
        for s in [0.2, 0.5, 0.8] {
            let ts = t_old + s * (t_new - t_old);
            ode.dense(ts, &mut out).unwrap();
            record(ts, &out, &mut err_dense, &mut scale);
        }
        record(t, &y, &mut err_end, &mut scale);
        if t == t_max && mode != Mode::Free {
            k += 1;
            if mode == Mode::LimitedReset {
                ode.reset();
            }
        }
        guard += 1;
        assert!(guard < 1_000_000);
    }
    assert_eq!(t, T_END);
    let ratio = |errs: &[f64; 3]| (0..3).map(|i| errs[i] / (atol + rtol * scale[i])).fold(0.0, f64::max);
    let rel = (0..3).map(|i| err_end[i].max(err_dense[i]) / scale[i]).fold(0.0, f64::max);
    Outcome { end: ratio(&err_end), dense: ratio(&err_dense), rel, stats: ode.stats() }
}

fn check(sys: Driven, name: &str, h_max: Option<f64>) {
    for mode in [Mode::Free, Mode::Limited, Mode::LimitedReset] {
        let mut prev_rel = f64::INFINITY;
        for rtol in [1e-6, 1e-8, 1e-10] {
            let o = run(sys, rtol, h_max, mode);
            let st = o.stats;
            eprintln!(
                "{name} {mode:?} rtol {rtol:e}: error/tol at step ends {:.3}, dense {:.3}; relative {:.2e}; accepted {}, rejected {}, rhs {}",
                o.end, o.dense, o.rel, st.accepted, st.rejected, st.rhs_evals
            );
            assert!(o.end < 3.0, "{name} {mode:?} rtol {rtol:e}: global error {} x tolerance at step ends", o.end);
            assert!(
                o.dense < 5.0,
                "{name} {mode:?} rtol {rtol:e}: global error {} x tolerance in dense output",
                o.dense
            );
            // Decreases with rtol until round-off (Limited modes: steps of <= 0.03 are exact to
            // round-off at every tolerance).
            assert!(o.rel <= (0.1 * prev_rel).max(1e-13), "{name} {mode:?}: error does not decrease with rtol");
            prev_rel = o.rel;
        }
    }
}

#[test]
fn light_damping_oscillator_meets_tolerance() {
    check(Driven::LIGHT, "light", None);
}

/// The plate parameters: once the transient has decayed below the tolerance the step size is
/// limited by stability (|h lambda| ~ 9 with h ~ 6), where the step ends stay accurate but the
/// dense output inside the step does not (up to ~30 x tol, see `docs/ode.md`). With
/// `h_max = 2` (a few times the plate's time scale sqrt(M/k) = 0.71) it is within tolerance.
#[test]
fn plate_parameters_meet_tolerance() {
    check(Driven::PLATE, "plate", Some(2.0));
}

#[test]
fn plate_without_h_max_dense_output_degrades_at_the_stability_limit() {
    let o = run(Driven::PLATE, 1e-6, None, Mode::Free);
    eprintln!("plate, no h_max: end {:.3}, dense {:.3}", o.end, o.dense);
    assert!(o.end < 3.0);
    // Documented limitation: the dense output is not error-controlled.
    assert!(o.dense > 5.0 && o.dense < 100.0, "{}", o.dense);
}

/// A forcing `a_j` that jumps at every `t_j = j dt`: the integrator is restarted with
/// `reset` at each jump; the reference is the closed form propagated segment by segment.
/// `dt = 0.03` (the engine's event spacing: one step per segment) and `dt = 1.7` (several
/// adaptive steps per segment). Without `reset` the stale FSAL derivative spoils the result.
#[test]
fn restart_after_discontinuities() {
    let base = Driven::LIGHT;
    let forcing = |j: u32| 0.5 + 0.4 * (f64::from(j) * 0.7).sin();
    for (dt, segments) in [(EVENT_DT, 400u32), (1.7, 30)] {
        for rtol in [1e-8, 1e-10] {
            for do_reset in [true, false] {
                let mut ode = Dop853::new(3, rtol, rtol * 1e-2).unwrap();
                let mut y = base.y0();
                let mut exact = base.y0();
                let mut t = 0.0;
                let mut worst: f64 = 0.0;
                for j in 0..segments {
                    let t_j = f64::from(j) * dt;
                    let t_next = f64::from(j + 1) * dt;
                    // Segment dynamics: forcing a_j + b t = (a_j + b t_j) + b s in local time s.
                    let seg = Driven { a: forcing(j) + base.b * t_j, x0: exact[0], v0: exact[1], ..base };
                    let mut rhs = |tt: f64, yy: &[f64], d: &mut [f64]| {
                        d[0] = yy[1];
                        d[1] = (forcing(j) + base.b * tt - base.eta * yy[1] - base.k * yy[0]) / base.m;
                        d[2] = yy[0];
                    };
                    if do_reset {
                        ode.reset();
                    }
                    while t < t_next {
                        ode.step(&mut rhs, &mut t, &mut y, t_next).unwrap();
                    }
                    assert_eq!(t, t_next);
                    let e = seg.exact(t_next - t_j);
                    exact = [e[0], e[1], exact[2] + e[2]];
                    worst = worst.max((y[0] - exact[0]).abs()).max((y[1] - exact[1]).abs());
                }
                let st = ode.stats();
                eprintln!(
                    "jumps dt {dt} rtol {rtol:e} reset {do_reset}: max error {worst:.3e}, accepted {}, rejected {}, restarts {}",
                    st.accepted, st.rejected, st.restarts
                );
                if do_reset {
                    assert!(worst < 3.0 * rtol, "rtol {rtol:e}: {worst:e}");
                    assert_eq!(st.restarts, u64::from(segments));
                } else {
                    assert!(worst > 10.0 * rtol, "stale derivative went unnoticed: {worst:e}");
                }
            }
        }
    }
}
