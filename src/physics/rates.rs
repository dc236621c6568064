//! Rupture and formation rates (docs/model.md, "Equations", items 6 and 7). Pure functions.

use serde::{Deserialize, Serialize};

/// A bond kind, chosen once per run: strong-bond scenes run no weak-bond code.
pub trait Bond: Copy + Send + Sync + std::fmt::Debug + 'static {
    /// `true` when the rupture rate depends on the tension.
    const IS_WEAK: bool;
    /// Rupture rate `k_off(f)` at tension `f >= 0`. May be `+inf`, never NaN.
    fn k_off(&self, tension: f64) -> f64;
}

/// Strong bonds: `k_off = k0`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Strong {
    pub k0: f64,
}

impl Bond for Strong {
    const IS_WEAK: bool = false;
    #[inline]
    fn k_off(&self, _tension: f64) -> f64 {
        self.k0
    }
}

/// Weak bonds: `k_off = k0 exp(beta dx f)`, `beta dx = dx / temperature`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Weak {
    pub k0: f64,
    /// `beta dx`.
    pub beta_dx: f64,
}

impl Bond for Weak {
    const IS_WEAK: bool = true;
    /// Overflow gives `+inf` (immediate rupture); `k0 = 0` gives 0, never `0 * inf = NaN`.
    #[inline]
    fn k_off(&self, tension: f64) -> f64 {
        if self.k0 == 0.0 {
            return 0.0;
        }
        self.k0 * (self.beta_dx * tension).exp()
    }
}

/// Formation kinetics: `k_on = kon0 g(v)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Formation {
    pub kon0: f64,
    /// Critical velocity `V0 = alpha / tau0`.
    pub v0: f64,
}

impl Formation {
    /// `g(v) = 1` for `|v| <= V0`, `sin(pi V0 / (2 |v|))` above; `0 <= g <= 1`.
    #[inline]
    pub fn g(&self, v: f64) -> f64 {
        let s = v.abs();
        if s <= self.v0 { 1.0 } else { (std::f64::consts::FRAC_PI_2 * (self.v0 / s)).sin() }
    }
    /// `k_on(v) = kon0 g(v)`.
    #[inline]
    pub fn k_on(&self, v: f64) -> f64 {
        self.kon0 * self.g(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn g_is_one_below_v0_and_fades_above() {
        let f = Formation { kon0: 0.1, v0: 0.5 };
        assert_eq!(f.g(0.0), 1.0);
        assert_eq!(f.g(-0.5), 1.0);
        assert!((f.g(1.0) - (std::f64::consts::PI / 4.0).sin()).abs() < 1e-15);
        assert!(f.g(1e12) > 0.0 && f.g(1e12) < 1e-11);
        assert_eq!(f.g(f64::INFINITY), 0.0);
        let mut last = 1.0;
        for i in 0..1000 {
            let g = f.g(0.5 + i as f64 * 0.01);
            assert!((0.0..=1.0).contains(&g) && g <= last);
            last = g;
        }
    }

    #[test]
    fn weak_rate_never_nan() {
        let w = Weak { k0: 0.1, beta_dx: 1.0 };
        assert_eq!(w.k_off(0.0), 0.1);
        assert_eq!(w.k_off(1e6), f64::INFINITY);
        assert_eq!(Weak { k0: 0.0, beta_dx: 1.0 }.k_off(1e6), 0.0);
    }
}
