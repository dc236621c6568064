//! The Hookean shear spring: `f^x = kappa x`, `f = kappa |x|`.

use serde::{Deserialize, Serialize};

use super::law::{ClosedForm, ForceLaw, LawParams, LinearLaw, ParamError, check_kappa};

/// Hookean shear spring: `f^x = kappa x`, `f = kappa |x|`. The only law whose bond force is
/// linear in the plate position, so the exact engine moves the plate in closed form.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Linear {
    pub kappa: f64,
}

impl ForceLaw for Linear {
    const NAME: &'static str = "linear";
    const IS_LINEAR: bool = true;
    const STIFFNESS_NOTE: &'static str = "each junction adds kappa";
    type Exact = ClosedForm;

    fn new(p: &LawParams) -> Result<Linear, ParamError> {
        Ok(Linear { kappa: check_kappa(p)? })
    }
    #[inline]
    fn tension(&self, x: f64) -> f64 {
        self.kappa * x.abs()
    }
    #[inline]
    fn force_x(&self, x: f64) -> f64 {
        self.kappa * x
    }
    #[inline]
    fn stiffness_x(&self, _x: f64) -> f64 {
        self.kappa
    }
    /// `f = kappa |x|`: `c = kappa`, with equality.
    fn thinning_slope(&self) -> f64 {
        self.kappa
    }
    /// `d f^x/dx = kappa` everywhere.
    fn stiffness_range(&self) -> (f64, f64) {
        (self.kappa, self.kappa)
    }
}

impl LinearLaw for Linear {
    #[inline]
    fn slope(&self) -> f64 {
        self.kappa
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::force::law::check_law;

    #[test]
    fn linear_law() {
        let law = Linear { kappa: 0.5 };
        assert_eq!(law.force_x(-2.0), -1.0);
        assert_eq!(law.tension(-2.0), 1.0);
        check_law(&law, &[-3.0, -0.5, 0.0, 1e-9, 0.7, 40.0]).unwrap();
        assert_eq!(Linear::new(&LawParams { kappa: 0.5, l0: 1.0 }), Ok(law));
        assert_eq!(Linear::new(&LawParams { kappa: -1.0, l0: 1.0 }).unwrap_err().field, "kappa");
    }
}
