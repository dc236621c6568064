//! A junction that yields: `f^x = kappa l0 tanh(x / l0)`.

use serde::{Deserialize, Serialize};

use super::{Direct, ForceLaw, LawParams, ParamError, check_kappa};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Saturating {
    pub kappa: f64,
    pub l0: f64,
}

impl ForceLaw for Saturating {
    const NAME: &'static str = "saturating";
    const STIFFNESS_NOTE: &'static str = "a yielding junction's stiffness never exceeds kappa";
    // Any law runs on the exact engine's direct method. IS_LINEAR defaults to false.
    type Exact = Direct;

    fn new(p: &LawParams) -> Result<Self, ParamError> {
        Ok(Saturating { kappa: check_kappa(p)?, l0: p.l0 })
    }
    fn tension(&self, x: f64) -> f64 {
        self.force_x(x).abs()
    }
    fn force_x(&self, x: f64) -> f64 {
        self.kappa * self.l0 * (x / self.l0).tanh()
    }
    /// `kappa / cosh^2(x/l0)`.
    fn stiffness_x(&self, x: f64) -> f64 {
        let c = (x / self.l0).cosh();
        self.kappa / (c * c)
    }
    /// `|tanh u| <= |u|`.
    fn thinning_slope(&self) -> f64 {
        self.kappa
    }
    fn stiffness_range(&self) -> (f64, f64) {
        (0.0, self.kappa)
    }
}
