//! Strong bonds: every attached junction ruptures at the constant rate `k0`, so the channel
//! rate is `k0 N_att` and the junction is a uniform pick; each candidate is an event.

use serde::{Deserialize, Serialize};

use super::contract::{Plan, RuptureModel};
use super::rate::RuptureRate;
use crate::engine::exact::core::bags::{Attached, count};
use crate::engine::exact::core::pick::Pick;
use crate::rng::{Pcg64, below};

/// Strong bonds at rate `k0`. `AHEAD`: the uniform picks are drawn [`Pick`]s ahead and their
/// junctions prefetched (the closed-form stepper, whose events are shorter than a memory
/// access at large `N`); otherwise each is drawn when used (the steppers that prefetch the
/// pick themselves during a plate step).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrongRupture<const AHEAD: bool = true> {
    pub k0: f64,
    /// The next uniform pick of an attached junction (`AHEAD`).
    next: Pick,
}

impl<const AHEAD: bool> StrongRupture<AHEAD> {
    /// The model at rate `k0`; with `AHEAD`, its first picks drawn from `rng`.
    pub fn new(k0: f64, rng: &mut Pcg64) -> Self {
        StrongRupture { k0, next: if AHEAD { Pick::draw(rng) } else { Pick::default() } }
    }
}

impl<const AHEAD: bool> RuptureModel for StrongRupture<AHEAD> {
    const IS_WEAK: bool = false;
    #[inline]
    fn attached(&mut self, _attached: &mut [Attached], _slot: usize, _c: f64, _y: f64) -> bool {
        true
    }
    #[inline]
    fn detached(&mut self, _attached: &mut [Attached], _slot: usize, _last: usize, _a: &Attached) {}
    #[inline]
    fn plan(&mut self, _bounds: impl FnMut(f64) -> (f64, f64), n_att: usize) -> Plan {
        Plan { rate: self.k0 * count(n_att), horizon: f64::INFINITY }
    }
    #[inline]
    fn pick<L: RuptureRate>(
        &mut self,
        rng: &mut Pcg64,
        attached: &[Attached],
        _: &L,
        _: impl FnOnce() -> f64,
    ) -> Option<usize> {
        let n = attached.len();
        Some(if AHEAD { self.next.take(n, rng) } else { below(rng, n) })
    }
    #[inline(always)]
    fn prefetch(&self, attached: &[Attached]) {
        if AHEAD {
            self.next.prefetch(attached);
        }
    }
}
