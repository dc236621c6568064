//! What a force law supplies to the weak-bond rupture models: the acceptance of a candidate
//! under the envelope `k0 exp(a |x|)` (`a = beta dx c`, `c` the law's thinning slope), given
//! the candidate's weights and the envelope's factors.
//!
//! - [`LinearRate`]: `f = kappa |x|`, the rate is the envelope itself,
//!   `r / k0 = e^{a |y - c|} = max(exp(a y) w0, w1 / exp(a y))` ([`accept`]).
//! - [`TiltedRate`]: `f(x) = kappa (sqrt(x^2 + l0^2) - l0)`, so `|x| - l0 <= f / kappa <= |x|`
//!   and `max(1, e^{-a l0} lo) <= r / k0 <= hi` with `lo`, `hi` the envelope's [`bracket`]:
//!   the squeeze decides most candidates without the plate's position, the junction or an
//!   exponential; the rest take `exp(beta dx f(y - c))`.

use serde::{Deserialize, Serialize};

use super::accept::{EXPONENT_CAP, accept, bracket, squeeze};
use crate::physics::{ForceLaw, Tilted};

/// The acceptance of a weak-bond rupture candidate (units of `k0`).
pub trait RuptureRate: Copy + std::fmt::Debug {
    /// `U b < r / k0` for a candidate with weights `w = [w0, w1]` under the factors `e_hi =
    /// exp(a y_hi)`, `e_lo = exp(-a y_lo)`, given `ub = U b`; `y()` is the plate position and
    /// `c()` the junction's anchor (each asked for only if needed). An overflowing rate
    /// (exponent beyond [`EXPONENT_CAP`]) is accepted.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn accept(
        &self,
        ub: f64,
        w: [f64; 2],
        e_hi: f64,
        e_lo: f64,
        a: f64,
        y: impl FnOnce() -> f64,
        c: impl FnOnce() -> f64,
    ) -> bool {
        self.accept_within(ub, [w, w], e_hi, e_lo, a, y, c, || w)
    }

    /// [`RuptureRate::accept`] for a candidate whose weights are known only within bounds
    /// `w_lo <= w <= w_hi` (`bounds = [w_lo, w_hi]`, each component), and exactly from `w()`,
    /// asked for only if the bounds do not decide: the same decision.
    #[allow(clippy::too_many_arguments)]
    fn accept_within(
        &self,
        ub: f64,
        bounds: [[f64; 2]; 2],
        e_hi: f64,
        e_lo: f64,
        a: f64,
        y: impl FnOnce() -> f64,
        c: impl FnOnce() -> f64,
        w: impl FnOnce() -> [f64; 2],
    ) -> bool;
}

/// The linear law: the rate is the envelope.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LinearRate;

impl RuptureRate for LinearRate {
    #[inline(always)]
    fn accept_within(
        &self,
        ub: f64,
        bounds: [[f64; 2]; 2],
        e_hi: f64,
        e_lo: f64,
        a: f64,
        y: impl FnOnce() -> f64,
        _c: impl FnOnce() -> f64,
        w: impl FnOnce() -> [f64; 2],
    ) -> bool {
        accept(ub, bounds, e_hi, e_lo, || (a * y()).exp(), w)
    }
}

/// Above this bound of `e^{a |x|}` (`e^{EXPONENT_CAP} / 4`) a candidate is decided by the
/// exact test alone (its exponent may pass [`EXPONENT_CAP`]).
const SQUEEZE_RATE_MAX: f64 = 9.4e259;

/// The tilted law with bond sensitivity `beta dx`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TiltedRate {
    pub law: Tilted,
    pub beta_dx: f64,
    /// `e^{-a l0}` (0 if it underflows or is not finite).
    shrink: f64,
}

impl TiltedRate {
    pub fn new(law: Tilted, beta_dx: f64) -> TiltedRate {
        let f = (-beta_dx * law.kappa * law.l0).exp();
        TiltedRate { law, beta_dx, shrink: if f.is_finite() { f } else { 0.0 } }
    }
}

impl RuptureRate for TiltedRate {
    #[inline(always)]
    fn accept_within(
        &self,
        ub: f64,
        [w_lo, w_hi]: [[f64; 2]; 2],
        e_hi: f64,
        e_lo: f64,
        _a: f64,
        y: impl FnOnce() -> f64,
        c: impl FnOnce() -> f64,
        _w: impl FnOnce() -> [f64; 2],
    ) -> bool {
        let (lo, hi) = bracket(w_lo, w_hi, e_hi, e_lo);
        if hi <= SQUEEZE_RATE_MAX {
            if let Some(decided) = squeeze(ub, (self.shrink * lo).max(1.0), hi) {
                return decided;
            }
        }
        let exponent = self.beta_dx * self.law.tension(y() - c());
        exponent > EXPONENT_CAP || ub < exponent.exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{UniformSource, pcg};

    /// The tilted squeeze's bracket holds the rate for every plate position within the
    /// bounds, `max(1, e^{-a l0} lo) <= r / k0 <= hi` (`a l0` from 0.05 to 5), so it decides
    /// as the exact test does: with the uniform below the lower end the exact test accepts,
    /// above the upper end it rejects.
    #[test]
    fn tilted_bracket_holds_the_rate() {
        let mut rng = pcg(11);
        for (beta_dx, kappa, l0) in [(1.0, 0.1, 0.5), (2.0, 0.5, 1.0), (1.0, 1.0, 5.0), (0.3, 2.0, 0.2)] {
            let r = TiltedRate::new(Tilted { kappa, l0 }, beta_dx);
            let a = beta_dx * kappa;
            for _ in 0..2000 {
                let c = (rng.uniform() - 0.5) * 8.0 / a;
                let e = (a * c).exp();
                let w = [1.0 / e, e];
                let y_lo = (rng.uniform() - 0.5) * 4.0 / a;
                let y_hi = y_lo + rng.uniform() / a;
                let (e_hi, e_lo) = ((a * y_hi).exp(), (-a * y_lo).exp());
                let (lo, hi) = bracket(w, w, e_hi, e_lo);
                for j in 0..=16 {
                    let y = y_lo + (y_hi - y_lo) * j as f64 / 16.0;
                    let rate = (beta_dx * r.law.tension(y - c)).exp();
                    let tol = 1.0 + 1e-12;
                    assert!((r.shrink * lo).max(1.0) <= rate * tol && rate <= hi * tol, "y {y} c {c}: {rate}");
                    let below = 0.999 * (r.shrink * lo).max(1.0);
                    assert!(r.accept(below, w, e_hi, e_lo, a, || y, || c));
                    assert!(!r.accept(1.001 * hi, w, e_hi, e_lo, a, || y, || c));
                }
            }
        }
    }
}
