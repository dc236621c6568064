//! Strong bonds: a force-independent rupture rate.

use serde::{Deserialize, Serialize};

use super::contract::{Bond, BondParams, check_k0};
use crate::physics::force::ParamError;

/// Strong bonds: `k_off = k0`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Strong {
    pub k0: f64,
}

impl Bond for Strong {
    const NAME: &'static str = "strong";
    const IS_WEAK: bool = false;
    fn new(p: &BondParams) -> Result<Strong, ParamError> {
        Ok(Strong { k0: check_k0(p)? })
    }
    #[inline]
    fn k_off(&self, _tension: f64) -> f64 {
        self.k0
    }
    fn k0(&self) -> f64 {
        self.k0
    }
    fn force_sensitivity(&self) -> f64 {
        0.0
    }
}
