//! Convergence of the plate integrators on the damped driven oscillator.
//!
//! With `kappa = 0` the junctions exert no force and the plate alone obeys
//! `M Xdd + eta Xd + K (X - V t) = 0`, `X(0) = Xd(0) = 0`. With the lag `u = X - V t`:
//! `M u'' + eta u' + K u = -eta V`, `u(0) = 0`, `u'(0) = -V`, so
//! `u = u_p + e^{-gamma t} (A cos(omega t) + B sin(omega t))` with `u_p = -eta V / K`,
//! `gamma = eta / (2M)`, `omega = sqrt(K/M - gamma^2)`, `A = -u_p`, `B = (gamma A - V) / omega`.
//! In the overdamped limit (`M = 0`): `u = u_p (1 - e^{-K t / eta})`.
//!
//! The error at fixed times must shrink by 2 per halving of `dt` for the first-order
//! integrators and by 4 for velocity Verlet; the observed order `log2(e(dt)/e(dt/2))` at the
//! two smallest steps must be within 0.1 of that (the next term of the error expansion is
//! `O(omega dt) ~ 2%` there).

use stickslip::runner::Simulation;
use stickslip_testkit::fixed_fig1 as scene;

const M: f64 = 75.0;
const ETA: f64 = 75.0;
const K: f64 = 150.0;
const V: f64 = 0.5;

fn exact(t: f64, mass: f64) -> f64 {
    let up = -ETA * V / K;
    let u = if mass == 0.0 {
        up * (1.0 - (-K * t / ETA).exp())
    } else {
        let gamma = ETA / (2.0 * mass);
        let omega = (K / mass - gamma * gamma).sqrt();
        let (a, b) = (-up, (gamma * -up - V) / omega);
        up + (-gamma * t).exp() * (a * (omega * t).cos() + b * (omega * t).sin())
    };
    u + V * t
}

/// Largest `|X(t) - X_exact(t)|` over `t = 0.5, 1, ..., 10` of a run of `scene`.
fn max_error(scene: &stickslip::Scene, mass: f64) -> f64 {
    let mut e = Simulation::new(scene).unwrap();
    (1..=20)
        .map(|k| {
            let t = k as f64 * 0.5;
            e.advance(t).unwrap();
            let s = e.sample();
            assert!((s.t - t).abs() < 1e-9);
            (s.x - exact(s.t, mass)).abs()
        })
        .fold(0.0, f64::max)
}

fn observed_orders(integrator: &str, mass: f64) -> Vec<f64> {
    let errors: Vec<f64> = [0.05, 0.025, 0.0125, 0.00625]
        .iter()
        .map(|dt| {
            let (i, m, d) =
                (format!("fixed.integrator={integrator}"), format!("plate.mass={mass}"), format!("fixed.dt={dt}"));
            let s = scene(&[
                &i,
                &m,
                &d,
                "junctions.kappa=0",
                "junctions.force_law=linear",
                "junctions.n=1",
                "run.t_end=10",
            ]);
            max_error(&s, mass)
        })
        .collect();
    eprintln!("{integrator}, M = {mass}: errors {errors:?}");
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

#[test]
fn semi_implicit_euler_is_first_order() {
    let p = observed_orders("semi-implicit-euler", M);
    assert!((p.last().unwrap() - 1.0).abs() < 0.1, "{p:?}");
}

#[test]
fn explicit_euler_is_first_order() {
    let p = observed_orders("explicit-euler", M);
    assert!((p.last().unwrap() - 1.0).abs() < 0.1, "{p:?}");
}

#[test]
fn velocity_verlet_is_second_order() {
    let p = observed_orders("velocity-verlet", M);
    assert!((p.last().unwrap() - 2.0).abs() < 0.1, "{p:?}");
}

#[test]
fn overdamped_euler_is_first_order() {
    let p = observed_orders("semi-implicit-euler", 0.0);
    assert!((p.last().unwrap() - 1.0).abs() < 0.1, "{p:?}");
}
