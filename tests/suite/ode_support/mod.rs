//! Test problems with closed-form solutions, shared by the `ode_*` integration tests.
#![allow(dead_code)]

use stickslip::ode::OdeSystem;

/// A non-autonomous nonlinear system with known solution:
/// `y0' = -2 t y0^2` (`y0 = 1/(1 + t^2)`, poles at `t = ±i`), `y1' = y1 cos t`
/// (`y1 = exp(sin t)`), `y2' = y3, y3' = -y2` (`y2 = sin t, y3 = cos t`),
/// `y4' = y4^2 exp(-t)` (`y4 = exp(t)`, entire).
pub struct Mixed;

impl Mixed {
    pub fn exact(t: f64) -> [f64; 5] {
        [1.0 / (1.0 + t * t), t.sin().exp(), t.sin(), t.cos(), t.exp()]
    }
}

impl OdeSystem for Mixed {
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = -2.0 * t * y[0] * y[0];
        d[1] = y[1] * t.cos();
        d[2] = y[3];
        d[3] = -y[2];
        d[4] = y[4] * y[4] * (-t).exp();
    }
}

/// Damped driven linear oscillator `M X'' + eta X' + k X = a + b t` (underdamped), with the
/// quadrature `Q' = X` (like the engine's time integrals of observables).
/// State `[X, X', Q]`.
#[derive(Clone, Copy, Debug)]
pub struct Driven {
    pub m: f64,
    pub eta: f64,
    pub k: f64,
    pub a: f64,
    pub b: f64,
    pub x0: f64,
    pub v0: f64,
}

impl Driven {
    /// Light damping: about 32 periods on [0, 50], amplitude decays by e^-2.5.
    pub const LIGHT: Driven = Driven { m: 1.0, eta: 0.1, k: 4.0, a: 0.5, b: 0.02, x0: 1.0, v0: 0.0 };
    /// The letter's plate (M = 75, eta = 75, k = 150) pulled at V = 0.5 (a + b t = k V t),
    /// started off the steady state.
    pub const PLATE: Driven = Driven { m: 75.0, eta: 75.0, k: 150.0, a: 0.0, b: 75.0, x0: 1.0, v0: 2.0 };

    pub fn y0(&self) -> [f64; 3] {
        [self.x0, self.v0, 0.0]
    }

    /// Exact `[X, X', Q]` at `t`.
    pub fn exact(&self, t: f64) -> [f64; 3] {
        let Driven { m, eta, k, a, b, x0, v0 } = *self;
        let g = eta / (2.0 * m);
        let w = (k / m - g * g).sqrt();
        assert!(w.is_finite() && w > 0.0, "underdamped parameters expected");
        // Particular solution X_p = (a + b t)/k - eta b / k^2.
        let xp = |t: f64| (a + b * t) / k - eta * b / (k * k);
        let c1 = x0 - xp(0.0);
        let c2 = (v0 - b / k + g * c1) / w;
        let (s, c) = (w * t).sin_cos();
        let e = (-g * t).exp();
        let x = xp(t) + e * (c1 * c + c2 * s);
        let v = b / k + e * ((-g * c1 + w * c2) * c + (-g * c2 - w * c1) * s);
        // Q = int_0^t X: particular part + transient part.
        let qp = (a * t + 0.5 * b * t * t) / k - eta * b * t / (k * k);
        let den = g * g + w * w;
        let ic = |t: f64| (-t * g).exp() * (-g * (w * t).cos() + w * (w * t).sin()) / den;
        let is = |t: f64| (-t * g).exp() * (-g * (w * t).sin() - w * (w * t).cos()) / den;
        let q = qp + c1 * (ic(t) - ic(0.0)) + c2 * (is(t) - is(0.0));
        [x, v, q]
    }
}

impl OdeSystem for Driven {
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = y[1];
        d[1] = (self.a + self.b * t - self.eta * y[1] - self.k * y[0]) / self.m;
        d[2] = y[0];
    }
}

/// Least-squares slope of log(err) against log(h).
pub fn slope(hs: &[f64], errs: &[f64]) -> f64 {
    let n = hs.len() as f64;
    let xs: Vec<f64> = hs.iter().map(|h| h.ln()).collect();
    let ys: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let mx = xs.iter().sum::<f64>() / n;
    let my = ys.iter().sum::<f64>() / n;
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

pub fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// `[1.23e-4, ...]` for messages.
pub fn sci(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:.3e}")).collect();
    format!("[{}]", parts.join(", "))
}
