//! Weak bonds by thinning against each junction's own bound, the junction drawn from a sum
//! tree of its weights `[exp(-a c), exp(a c)]` (O(log N) per candidate; the tree stays in the
//! processor's caches below [`BINNED_FROM`](super::binned::BINNED_FROM) junctions). Over a
//! closed-form plate its bounds hold for a horizon ([`Horizon`]); over a stepped plate for
//! one step ([`RuptureModel::bound`]).

use serde::{Deserialize, Serialize};

use super::accept::{anchor_overflows, overflows};
use super::contract::{Plan, RuptureModel};
use super::horizon::Horizon;
use super::rate::RuptureRate;
use super::sumtree::SumTree2;
use crate::engine::alloc::AllocError;
use crate::engine::exact::core::bags::Attached;
use crate::rng::{Pcg64, UniformSource};

/// A junction's weights `[exp(-a c), exp(a c)]`, the two terms of its rate bound.
#[inline]
fn weights(a: f64, c: f64) -> [f64; 2] {
    let e = (a * c).exp();
    [1.0 / e, e]
}

/// Weak bonds: thinning against each junction's own bound, sum-tree selection.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TreeRupture {
    pub k0: f64,
    /// `a = beta dx c` (the bond's force sensitivity times the law's thinning slope).
    pub a: f64,
    /// Weights `[exp(-a c), exp(a c)]` per attached slot.
    tree: SumTree2,
    /// The current horizon's bounds and their factors.
    h: Horizon,
}

impl TreeRupture {
    pub fn new(k0: f64, a: f64, n: usize) -> TreeRupture {
        Self::try_new(k0, a, n).unwrap_or_else(|e| panic!("{e}"))
    }
    /// [`TreeRupture::new`], with its sum tree reserved fallibly.
    pub fn try_new(k0: f64, a: f64, n: usize) -> Result<TreeRupture, AllocError> {
        Ok(TreeRupture { k0, a, tree: SumTree2::try_new(n)?, h: Horizon::default() })
    }
    /// `exp(a y_hi) W-` and `exp(-a y_lo) W+`.
    #[inline]
    fn terms(&self) -> (f64, f64) {
        self.h.terms(self.tree.total())
    }
}

impl RuptureModel for TreeRupture {
    const IS_WEAK: bool = true;
    /// Weighs the junction in `slot` with anchor `c`, the plate at `y`; `false` (and no
    /// weight) when its rate is beyond [`EXPONENT_CAP`](super::EXPONENT_CAP).
    #[inline]
    fn attached(&mut self, _attached: &mut [Attached], slot: usize, c: f64, y: f64) -> bool {
        if overflows(self.a, c, y) {
            self.tree.set(slot, [0.0; 2]);
            return false;
        }
        self.tree.set(slot, weights(self.a, c));
        true
    }
    #[inline]
    fn detached(&mut self, _attached: &mut [Attached], slot: usize, last: usize, _a: &Attached) {
        self.tree.swap_remove(slot, last);
    }
    fn plan(&mut self, bounds: impl FnMut(f64) -> (f64, f64), n_att: usize) -> Plan {
        self.h.plan(bounds, n_att, self.k0, self.a, self.tree.total())
    }
    /// The tree's totals are kept up to date by every change: only the bounds are checked.
    #[inline]
    fn replan(&mut self, reach: impl FnOnce(f64, f64) -> f64, n_att: usize) -> Option<f64> {
        let total = self.tree.total();
        self.h.replan(reach, n_att, self.k0, || total)
    }
    #[inline]
    fn bound(&mut self, y_lo: f64, y_hi: f64) -> f64 {
        self.h.set_grid_bounds(self.a, y_lo, y_hi);
        let (m, p) = self.terms();
        self.k0 * (m + p)
    }
    #[inline]
    fn pick<L: RuptureRate>(
        &mut self,
        rng: &mut Pcg64,
        attached: &[Attached],
        law: &L,
        y: impl FnOnce() -> f64,
    ) -> Option<usize> {
        if self.h.immediate {
            return Some(attached.len() - 1);
        }
        let (m, p) = self.terms();
        let (e_hi, e_lo) = (self.h.e_hi, self.h.e_lo);
        let u = rng.uniform() * (m + p);
        let slot = if u < m {
            self.tree.find_prefetching(0, u / e_hi, attached)
        } else {
            self.tree.find_prefetching(1, (u - m) / e_lo, attached)
        };
        // The descent has requested the junction's record (read only if the candidate is
        // accepted).
        let slot = slot.min(attached.len() - 1);
        // Accept with r_i / b_i = exp(a|y-c|) / (exp(a(y_hi-c)) + exp(a(c-y_lo))), from the
        // leaf weights [exp(-a c), exp(a c)] just read by the descent (no access to the
        // junction, at most one exponential).
        let w = self.tree.get(slot);
        let ub = rng.uniform() * (e_hi * w[0] + e_lo * w[1]);
        law.accept(ub, w, e_hi, e_lo, self.a, y, || attached[slot].c).then_some(slot)
    }
    /// Every weight recomputed from `attached`; the slots whose rate is beyond
    /// [`EXPONENT_CAP`](super::EXPONENT_CAP) (weighed zero).
    fn rebuild(&mut self, attached: &mut [Attached]) -> Vec<usize> {
        let a = self.a;
        let over: Vec<usize> = (0..attached.len()).filter(|&s| anchor_overflows(a, attached[s].c)).collect();
        self.tree.rebuild(attached.iter().map(|j| if anchor_overflows(a, j.c) { [0.0; 2] } else { weights(a, j.c) }));
        self.h.forget();
        over
    }
    #[inline]
    fn needs_rebase(&self, y: f64, tau: f64) -> bool {
        self.h.needs_rebase(self.a, y, tau)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::exact::stepper::linear::Drive;

    /// After an event, the plan is kept while its bounds, widened by the event's reach, stay
    /// within its limits, at the rate of the junctions attached then under the plan's
    /// factors; a reach past the limits, a reach that is not a number, or a re-base (which
    /// forgets the plan) plans anew.
    #[test]
    fn a_plan_is_kept_while_the_plate_stays_within_its_limits() {
        let (a, n) = (3.0, 64);
        let mut rng = crate::rng::pcg(8);
        let mut w = TreeRupture::new(1.0, a, n);
        let mut records = Vec::new();
        for slot in 0..n / 2 {
            let c = (rng.uniform() - 0.5) * 4.0;
            assert!(w.attached(&mut [], slot, c, 0.0));
            records.push(Attached { c, id: slot as u32, bin: 0 });
        }
        let drive = Drive { y0: 0.3, v: 0.7 };
        let plan = w.plan(|h| drive.bounds(h), n / 2);
        assert_eq!(w.replan(|_, _| 0.0, n / 2), Some(plan.rate));
        assert!(w.attached(&mut [], n / 2, 0.1, 0.3));
        let (m, p) = w.terms();
        assert_eq!(w.replan(|_, _| 1e-9, n / 2 + 1), Some(m + p));
        assert_eq!(w.replan(|_, _| f64::NAN, n / 2 + 1), None);
        w.plan(|h| drive.bounds(h), n / 2 + 1);
        assert_eq!(w.replan(|_, _| 10.0, n / 2 + 1), None);
        w.plan(|h| drive.bounds(h), n / 2);
        w.rebuild(&mut records);
        assert_eq!(w.replan(|_, _| 0.0, n / 2), None, "a re-base forgets the plan");
    }

    /// A plan bounds every junction's rate over its whole horizon (`b_i >= r_i`: the
    /// acceptance never exceeds 1), and the acceptance squeeze of `pick` brackets the rate:
    /// `max(w0 / e_lo, w1 / e_hi) <= r_i <= max(e_hi w0, e_lo w1) <= b_i`.
    #[test]
    fn plan_bounds_every_rate_over_its_horizon() {
        let a = 3.0;
        let n = 64;
        let mut rng = crate::rng::pcg(4);
        let mut w = TreeRupture::new(1.0, a, n);
        let anchors: Vec<f64> = (0..n).map(|_| (rng.uniform() - 0.5) * 4.0).collect();
        for (slot, &c) in anchors.iter().enumerate() {
            assert!(w.attached(&mut [], slot, c, 0.0));
        }
        for drive in [Drive { y0: 0.3, v: 0.7 }, Drive { y0: -0.5, v: -2.0 }, Drive { y0: 1.1, v: 1e-9 }] {
            let plan = w.plan(|h| drive.bounds(h), n);
            assert!(plan.rate.is_finite() && plan.horizon > 0.0);
            for k in 0..=200 {
                let s = plan.horizon * k as f64 / 200.0;
                let y = drive.position(s);
                for (slot, &c) in anchors.iter().enumerate() {
                    let r = (a * (y - c).abs()).exp();
                    let wt = w.tree.get(slot);
                    let (e_hi, e_lo) = (w.h.e_hi, w.h.e_lo);
                    let b = e_hi * wt[0] + e_lo * wt[1];
                    let lo = (wt[0] / e_lo).max(wt[1] / e_hi);
                    let hi = (e_hi * wt[0]).max(e_lo * wt[1]);
                    let tol = 1.0 + 1e-12;
                    assert!(lo <= r * tol && r <= hi * tol && hi <= b, "y {y} c {c}: {lo} {r} {hi} {b}");
                }
            }
        }
    }
}
