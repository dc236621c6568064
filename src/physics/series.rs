//! The tilted law's total bond force `S(y) = sum_i f^x(y - c_i)` as an O(1)-per-event series.
//!
//! FIRST CUT: the public API with a direct O(N) body (anchors stored); the series follows.

use serde::{Deserialize, Serialize};

use super::force::{ForceLaw, Tilted};

/// Taylor coefficients of the tilted law's horizontal force about `x`:
/// `out[k] = (d^k f^x/dx^k)(x) / k!` for `k = 0..out.len()`.
///
/// `f^x = kappa x + phi`, `phi = -kappa l0 x h`, `h = (x^2 + l0^2)^(-1/2)`;
/// `h_k = R^-(k+1) P_k(-x/R)` (Legendre, `R = sqrt(x^2 + l0^2)`), by the recurrence
/// `k P_k = (2k - 1) t P_(k-1) - (k - 1) P_(k-2)`; `(x h)_k = x h_k + h_(k-1)`.
pub fn tilted_taylor(law: &Tilted, x: f64, out: &mut [f64]) {
    let n = out.len();
    if n == 0 {
        return;
    }
    let r = x.hypot(law.l0);
    let t = -x / r;
    let inv_r = 1.0 / r;
    let a = -law.kappa * law.l0;
    // (x h)_k = R^-k [ (x/R) P_k + P_(k-1) ] = R^-k [ P_(k-1) - t P_k ].
    let (mut p_prev, mut p) = (1.0, t); // P_0, P_1
    let mut scale = 1.0; // R^-k
    for (k, o) in out.iter_mut().enumerate() {
        let xh = if k == 0 {
            -t
        } else {
            if k >= 2 {
                let kf = k as f64;
                let next = ((2.0 * kf - 1.0) * t * p - (kf - 1.0) * p_prev) / kf;
                p_prev = p;
                p = next;
            }
            scale *= inv_r;
            scale * (p_prev - t * p)
        };
        *o = a * xh;
    }
    out[0] += law.kappa * x;
    if n > 1 {
        out[1] += law.kappa;
    }
}

/// The bond force of a set of junctions under the tilted law, kept about a base point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SeriesSum {
    law: Tilted,
    rtol: f64,
    base: f64,
    anchors: Vec<f64>,
    live: Vec<bool>,
    free: Vec<u32>,
    n: usize,
}

impl SeriesSum {
    /// Empty set of anchors, base point 0.
    pub fn new(law: Tilted, rtol: f64) -> SeriesSum {
        SeriesSum { law, rtol, base: 0.0, anchors: Vec::new(), live: Vec::new(), free: Vec::new(), n: 0 }
    }
    pub fn len(&self) -> usize {
        self.n
    }
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
    /// Base point `y0` of the series.
    pub fn base(&self) -> f64 {
        self.base
    }
    /// The series is valid for `|y - base| <= radius()`.
    pub fn radius(&self) -> f64 {
        self.law.l0 / 8.0
    }
    /// A junction with anchor `c` attached. Returns a handle to pass to `remove`.
    pub fn add(&mut self, c: f64) -> u32 {
        self.n += 1;
        if let Some(h) = self.free.pop() {
            self.anchors[h as usize] = c;
            self.live[h as usize] = true;
            h
        } else {
            self.anchors.push(c);
            self.live.push(true);
            (self.anchors.len() - 1) as u32
        }
    }
    /// The junction with anchor `c` and handle `h` detached.
    pub fn remove(&mut self, _c: f64, h: u32) {
        assert!(self.live[h as usize], "SeriesSum::remove: handle {h} is not attached");
        self.live[h as usize] = false;
        self.free.push(h);
        self.n -= 1;
    }
    /// New base point `y0`.
    pub fn rebase(&mut self, y0: f64) {
        self.base = y0;
    }
    /// The coordinate frame moved: every anchor `c -> c - dy` and the base `-> base - dy`.
    pub fn shift(&mut self, dy: f64) {
        self.base -= dy;
        for c in &mut self.anchors {
            *c -= dy;
        }
    }
    fn live_anchors(&self) -> impl Iterator<Item = f64> + '_ {
        self.anchors.iter().zip(&self.live).filter(|(_, l)| **l).map(|(c, _)| *c)
    }
    /// `S(y)`.
    pub fn force(&self, y: f64) -> f64 {
        self.live_anchors().map(|c| self.law.force_x(y - c)).sum()
    }
    /// `(S(y), dS/dy(y))`.
    pub fn force_and_stiffness(&self, y: f64) -> (f64, f64) {
        self.live_anchors()
            .map(|c| (self.law.force_x(y - c), self.law.stiffness_x(y - c)))
            .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
    }
    /// `int_{y0}^{y1} S(y) dy`: the antiderivative of `f^x` is `kappa (x^2/2 - l0 (l - l0))`.
    pub fn integral(&self, y0: f64, y1: f64) -> f64 {
        let (k, l0) = (self.law.kappa, self.law.l0);
        let g = |x: f64| k * (0.5 * x * x - l0 * (x * x / (x.hypot(l0) + l0)));
        self.live_anchors().map(|c| g(y1 - c) - g(y0 - c)).sum()
    }
    /// Bound on `|S(y) - S_true(y)|` (round-off of the direct sum).
    pub fn error_bound(&self) -> f64 {
        let m = self.live_anchors().map(|c| (self.base - c).abs()).fold(0.0, f64::max);
        8.0 * f64::EPSILON * (self.n as f64 + 2.0) * self.law.kappa * (m + self.radius() + self.law.l0)
    }
    /// Same for `dS/dy`.
    pub fn stiffness_error_bound(&self) -> f64 {
        8.0 * f64::EPSILON * (self.n as f64 + 2.0) * self.law.kappa
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Low coefficients against the closed forms `f^x`, `d f^x/dx` and a central difference
    /// of `d f^x/dx` for `f''/2`.
    #[test]
    fn taylor_low_orders_match_closed_forms() {
        let law = Tilted { kappa: 0.3, l0: 0.7 };
        for &x in &[-40.0, -2.0, -0.3, 0.0, 1e-9, 0.5, 3.0, 1e4] {
            let mut c = [0.0; 4];
            tilted_taylor(&law, x, &mut c);
            assert!((c[0] - law.force_x(x)).abs() <= 1e-15 * (1.0 + law.force_x(x).abs()), "x = {x}");
            assert!((c[1] - law.stiffness_x(x)).abs() <= 1e-15, "x = {x}: {} vs {}", c[1], law.stiffness_x(x));
            let h = 1e-5;
            let fd = (law.stiffness_x(x + h) - law.stiffness_x(x - h)) / (2.0 * h) / 2.0;
            assert!((c[2] - fd).abs() <= 1e-8, "x = {x}: {} vs {fd}", c[2]);
        }
    }
}
