//! Weak bonds: a rupture rate that grows exponentially with the tension (Bell's law).

use serde::{Deserialize, Serialize};

use super::contract::{Bond, BondParams, check_k0};
use crate::physics::exp::exp;
use crate::physics::force::ParamError;

/// Weak bonds: `k_off = k0 exp(beta dx f)`, `beta dx = dx / temperature`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Weak {
    pub k0: f64,
    /// `beta dx`.
    pub beta_dx: f64,
}

impl Bond for Weak {
    const NAME: &'static str = "weak";
    const IS_WEAK: bool = true;
    fn new(p: &BondParams) -> Result<Weak, ParamError> {
        let k0 = check_k0(p)?;
        if !(p.dx.is_finite() && p.dx >= 0.0) {
            return Err(ParamError { field: "dx", value: p.dx, allowed: "must be a finite number >= 0".into() });
        }
        if !(p.temperature.is_finite() && p.temperature > 0.0) {
            return Err(ParamError {
                field: "temperature",
                value: p.temperature,
                allowed: "must be a finite number > 0".into(),
            });
        }
        Ok(Weak { k0, beta_dx: p.dx / p.temperature })
    }
    /// Overflow gives `+inf` (immediate rupture); `k0 = 0` gives 0, never `0 * inf = NaN`.
    #[inline]
    fn k_off(&self, tension: f64) -> f64 {
        if self.k0 == 0.0 {
            return 0.0;
        }
        self.k0 * exp(self.beta_dx * tension)
    }
    fn k0(&self) -> f64 {
        self.k0
    }
    fn force_sensitivity(&self) -> f64 {
        self.beta_dx
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weak_rate_never_nan() {
        let w = Weak { k0: 0.1, beta_dx: 1.0 };
        assert_eq!(w.k_off(0.0), 0.1);
        assert_eq!(w.k_off(1e6), f64::INFINITY);
        assert_eq!(Weak { k0: 0.0, beta_dx: 1.0 }.k_off(1e6), 0.0);
    }
}
