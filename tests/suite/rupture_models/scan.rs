//! Weak bonds whose candidate is drawn by scanning the attached junctions' weights: O(N) per
//! candidate, no tree and no bins, the thinning bound from the crate's `Horizon`.

use serde::{Deserialize, Serialize};
use stickslip::engine::exact::core::bags::Attached;
use stickslip::engine::exact::rupture::horizon::Horizon;
use stickslip::engine::exact::rupture::{Plan, RuptureModel, RuptureRate, anchor_overflows, overflows};
use stickslip::rng::{Pcg64, UniformSource};

/// Weak bonds under the envelope `k0 exp(a |x|)`: each attached junction weighs
/// `[exp(-a c), exp(a c)]`, by slot of the attached bag.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Scan {
    pub k0: f64,
    pub a: f64,
    w: Vec<[f64; 2]>,
    h: Horizon,
}

impl Scan {
    pub fn new(k0: f64, a: f64) -> Scan {
        Scan { k0, a, w: Vec::new(), h: Horizon::default() }
    }
    fn weights(&self, c: f64) -> [f64; 2] {
        let e = (self.a * c).exp();
        [1.0 / e, e]
    }
    fn totals(&self) -> [f64; 2] {
        self.w.iter().fold([0.0; 2], |s, w| [s[0] + w[0], s[1] + w[1]])
    }
}

impl RuptureModel for Scan {
    const IS_WEAK: bool = true;
    fn attached(&mut self, _: &mut [Attached], slot: usize, c: f64, y: f64) -> bool {
        assert_eq!(slot, self.w.len(), "a junction attaches into the last slot");
        let ok = !overflows(self.a, c, y);
        self.w.push(if ok { self.weights(c) } else { [0.0; 2] });
        ok
    }
    fn detached(&mut self, _: &mut [Attached], slot: usize, _last: usize, _: &Attached) {
        self.w.swap_remove(slot);
    }
    fn plan(&mut self, bounds: impl FnMut(f64) -> (f64, f64), n_att: usize) -> Plan {
        let w = self.totals();
        self.h.plan(bounds, n_att, self.k0, self.a, w)
    }
    fn bound(&mut self, y_lo: f64, y_hi: f64) -> f64 {
        self.h.set_bounds(self.a, y_lo, y_hi);
        let (m, p) = self.h.terms(self.totals());
        self.k0 * (m + p)
    }
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
        let (e_hi, e_lo) = (self.h.e_hi, self.h.e_lo);
        let b = |w: &[f64; 2]| e_hi * w[0] + e_lo * w[1];
        let mut u = rng.uniform() * self.w.iter().map(b).sum::<f64>();
        let slot = self.w.iter().position(|w| {
            u -= b(w);
            u < 0.0
        });
        let slot = slot.unwrap_or(self.w.len() - 1);
        let w = self.w[slot];
        let ub = rng.uniform() * b(&w);
        law.accept(ub, w, e_hi, e_lo, self.a, y, || attached[slot].c).then_some(slot)
    }
    fn rebuild(&mut self, attached: &mut [Attached]) -> Vec<usize> {
        self.w =
            attached.iter().map(|j| if anchor_overflows(self.a, j.c) { [0.0; 2] } else { self.weights(j.c) }).collect();
        (0..attached.len()).filter(|&s| anchor_overflows(self.a, attached[s].c)).collect()
    }
    fn needs_rebase(&self, y: f64, tau: f64) -> bool {
        self.h.needs_rebase(self.a, y, tau)
    }
}
