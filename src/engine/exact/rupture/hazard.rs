//! Ruptures at the bond's own rate `k_off(f)`, for any law and bond kind (the direct
//! stepper's model): weak bonds' ruptures are found by the stepper, which integrates the
//! hazard `int sum_i r_i` to a unit exponential (no channel, no candidates; the model only says
//! when a newly attached junction's rate overflows); strong bonds rupture on the channel at
//! `k0 N_att`, the junction a uniform pick.

use serde::{Deserialize, Serialize};

use super::contract::{Plan, RuptureModel};
use super::rate::RuptureRate;
use crate::engine::exact::core::bags::Attached;
use crate::engine::exact::core::bags::count;
use crate::physics::{Bond, ForceLaw};
use crate::rng::{Pcg64, below};

/// `e^EXPONENT_CAP`: the rate cap relative to `k0`.
pub const CAP_RATE_FACTOR: f64 = 3.7730203009299397e260;

/// Ruptures at the rate of bond kind `B` under law `L`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct Hazard<L: ForceLaw, B: Bond> {
    pub law: L,
    pub bond: B,
}

impl<L: ForceLaw, B: Bond> Hazard<L, B> {
    /// `k0 e^EXPONENT_CAP`: rates are capped here so the hazard stays finite.
    #[inline]
    pub fn rate_cap(&self) -> f64 {
        CAP_RATE_FACTOR * self.bond.k_off(0.0)
    }
}

impl<L: ForceLaw, B: Bond> RuptureModel for Hazard<L, B> {
    const IS_WEAK: bool = B::IS_WEAK;
    /// Whether the junction's rupture rate at extension `y - c` stays below the cap.
    #[inline]
    fn attached(&mut self, _attached: &mut [Attached], _slot: usize, c: f64, y: f64) -> bool {
        !(B::IS_WEAK && self.bond.k_off(self.law.tension(y - c)) > self.rate_cap())
    }
    #[inline]
    fn detached(&mut self, _attached: &mut [Attached], _slot: usize, _last: usize, _a: &Attached) {}
    /// Strong bonds: `k0 N_att` on the channel (weak bonds use none: the stepper finds them).
    #[inline]
    fn plan(&mut self, _bounds: impl FnMut(f64) -> (f64, f64), n_att: usize) -> Plan {
        Plan { rate: if B::IS_WEAK { 0.0 } else { self.bond.k_off(0.0) * count(n_att) }, horizon: f64::INFINITY }
    }
    /// A uniform pick (strong bonds; weak bonds have no candidates).
    #[inline]
    fn pick<R: RuptureRate>(
        &mut self,
        rng: &mut Pcg64,
        att: &[Attached],
        _: &R,
        _: impl FnOnce() -> f64,
    ) -> Option<usize> {
        Some(below(rng, att.len()))
    }
}
