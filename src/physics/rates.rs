//! Formation rate (docs/model.md, "Equations", item 7). Pure functions. Rupture rates are
//! the bond kinds of [`crate::physics::bond`].

use serde::{Deserialize, Serialize};

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
}
