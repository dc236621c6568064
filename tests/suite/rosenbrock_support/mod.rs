//! Test systems for the Rosenbrock integrator (`tests/suite/rosenbrock.rs`, `benches/rosenbrock.rs`),
//! each with its analytic Jacobian.
#![allow(dead_code)]

use stickslip::ode::{OdeSystem, StiffSystem};

/// Linear plate `M X'' + eta X' + k X = a + b t`; state `[X, X']` for `M > 0`, `[X]` for
/// `M = 0` (`eta X' = a + b t - k X`).
#[derive(Clone, Copy, Debug)]
pub struct LinPlate {
    pub m: f64,
    pub eta: f64,
    pub k: f64,
    pub a: f64,
    pub b: f64,
}

impl LinPlate {
    pub fn dim(&self) -> usize {
        if self.m > 0.0 { 2 } else { 1 }
    }
}

impl StiffSystem for LinPlate {
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        let force = self.a + self.b * t - self.k * y[0];
        if self.m > 0.0 {
            d[0] = y[1];
            d[1] = (force - self.eta * y[1]) / self.m;
        } else {
            d[0] = force / self.eta;
        }
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], j: &mut [f64], ft: &mut [f64]) {
        if self.m > 0.0 {
            j.copy_from_slice(&[0.0, 1.0, -self.k / self.m, -self.eta / self.m]);
            ft.copy_from_slice(&[0.0, self.b / self.m]);
        } else {
            j[0] = -self.k / self.eta;
            ft[0] = self.b / self.eta;
        }
    }
}

/// The engine's kind of plate, nonlinear: `M X'' + eta X' + K (X - V t) + S(X) = 0` with
/// `S(X) = kn X + c3 X^3` (`S' = kn + 3 c3 X^2 >= 0`), plus three quadratures `Q1' = X`,
/// `Q2' = S(X)`, `Q3' = X^2`. State `[X, X', Q1, Q2, Q3]` (`M > 0`) or `[X, Q1, Q2, Q3]`
/// (`M = 0`).
#[derive(Clone, Copy, Debug)]
pub struct CubicPlate {
    pub m: f64,
    pub eta: f64,
    pub k: f64,
    pub v: f64,
    pub kn: f64,
    pub c3: f64,
}

impl CubicPlate {
    pub fn dim(&self) -> usize {
        if self.m > 0.0 { 5 } else { 4 }
    }
    fn s(&self, x: f64) -> (f64, f64) {
        (self.kn * x + self.c3 * x * x * x, self.kn + 3.0 * self.c3 * x * x)
    }
}

impl StiffSystem for CubicPlate {
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        let x = y[0];
        let (s, _) = self.s(x);
        let force = -self.k * (x - self.v * t) - s;
        let q = if self.m > 0.0 {
            d[0] = y[1];
            d[1] = (force - self.eta * y[1]) / self.m;
            2
        } else {
            d[0] = force / self.eta;
            1
        };
        d[q] = x;
        d[q + 1] = s;
        d[q + 2] = x * x;
    }
    fn jacobian(&mut self, _t: f64, y: &[f64], j: &mut [f64], ft: &mut [f64]) {
        let x = y[0];
        let (s, ds) = self.s(x);
        let _ = s;
        let n = self.dim();
        j.fill(0.0);
        ft.fill(0.0);
        let q = if self.m > 0.0 {
            j[1] = 1.0;
            j[n] = -(self.k + ds) / self.m;
            j[n + 1] = -self.eta / self.m;
            ft[1] = self.k * self.v / self.m;
            2
        } else {
            j[0] = -(self.k + ds) / self.eta;
            ft[0] = self.k * self.v / self.eta;
            1
        };
        j[q * n] = 1.0;
        j[(q + 1) * n] = ds;
        j[(q + 2) * n] = 2.0 * x;
    }
}

/// The same cubic plate as an explicit system, for DOP853 references where non-stiff.
pub struct Explicit<S>(pub S);

impl<S: StiffSystem> OdeSystem for Explicit<S> {
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        self.0.rhs(t, y, d)
    }
}

/// Van der Pol in Hairer's scaled form: `y0' = y1`, `y1' = ((1 - y0^2) y1 - y0) / eps`.
#[derive(Clone, Copy, Debug)]
pub struct VanDerPol {
    pub eps: f64,
}

impl VanDerPol {
    /// Hairer's consistent initial value `(2, -2/3 + 10/81 eps - 292/2187 eps^2)`.
    pub fn y0(&self) -> [f64; 2] {
        let e = self.eps;
        [2.0, -2.0 / 3.0 + 10.0 / 81.0 * e - 292.0 / 2187.0 * e * e]
    }
}

impl StiffSystem for VanDerPol {
    fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = y[1];
        d[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / self.eps;
    }
    fn jacobian(&mut self, _t: f64, y: &[f64], j: &mut [f64], ft: &mut [f64]) {
        j[0] = 0.0;
        j[1] = 1.0;
        j[2] = (-2.0 * y[0] * y[1] - 1.0) / self.eps;
        j[3] = (1.0 - y[0] * y[0]) / self.eps;
        ft.fill(0.0);
    }
}

/// A non-autonomous nonlinear system with known solution (as `tests/suite/ode_support::Mixed`):
/// `y0 = 1/(1 + t^2)`, `y1 = exp(sin t)`, `(y2, y3) = (sin t, cos t)`, `y4 = exp(t)`.
pub struct Mixed;

impl Mixed {
    pub fn exact(t: f64) -> [f64; 5] {
        [1.0 / (1.0 + t * t), t.sin().exp(), t.sin(), t.cos(), t.exp()]
    }
}

impl StiffSystem for Mixed {
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = -2.0 * t * y[0] * y[0];
        d[1] = y[1] * t.cos();
        d[2] = y[3];
        d[3] = -y[2];
        d[4] = y[4] * y[4] * (-t).exp();
    }
    fn jacobian(&mut self, t: f64, y: &[f64], j: &mut [f64], ft: &mut [f64]) {
        j.fill(0.0);
        j[0] = -4.0 * t * y[0];
        j[6] = t.cos();
        j[2 * 5 + 3] = 1.0;
        j[3 * 5 + 2] = -1.0;
        j[4 * 5 + 4] = 2.0 * y[4] * (-t).exp();
        ft[0] = -2.0 * y[0] * y[0];
        ft[1] = -y[1] * t.sin();
        ft[2] = 0.0;
        ft[3] = 0.0;
        ft[4] = -y[4] * y[4] * (-t).exp();
    }
}
