//! Rupture kinetics of the exact engine for the `linear` force law, chosen once per run.
//!
//! - [`StrongRupture`]: every attached junction ruptures at `k0`, so the channel rate is
//!   `k0 N_att` and the junction is a uniform pick. Each candidate is an event.
//! - [`WeakRupture`]: junction `i` ruptures at `r_i(t) = k0 exp(a |y(t) - c_i|)` with
//!   `a = beta dx kappa`, which changes with every movement of the plate. Sampled exactly
//!   by *thinning*: over a horizon `[tau, tau + H]` on which the plate stays within proven
//!   bounds `y_lo <= y <= y_hi` (from the closed-form trajectory), every rate is bounded by
//!   `b_i = k0 (exp(a (y_hi - c_i)) + exp(a (c_i - y_lo))) >= k0 exp(a |y - c_i|)`.
//!   Candidates arrive at the constant total rate
//!   `B = k0 (exp(a y_hi) W- + exp(-a y_lo) W+)`, `W- = sum exp(-a c_i)`, `W+ = sum exp(a c_i)`;
//!   a candidate at time `s` picks junction `i` with probability `b_i / B` (one of the two
//!   terms, then a slot from the sum tree of that component) and is accepted with
//!   probability `r_i(s) / b_i`. Accepted candidates are exactly the rupture events of the
//!   time-dependent rates (Lewis & Shedler 1979; Ogata 1981). The horizon is chosen so
//!   that `a (y_hi - y_lo) <= 1`, which keeps the acceptance probability above
//!   `exp(-1) / 2`. Cost per candidate: O(log N). A plan rounds the exponents `a y_hi` and
//!   `-a y_lo` up to a grid of `1/GRID` (its two factors read from a table, the bound at
//!   most `exp(1/GRID)` looser per side), and the acceptance is first squeezed between
//!   `max(exp(a (y_lo - c_i)), exp(a (c_i - y_hi))) <= r_i <= max(exp(a (y_hi - c_i)), exp(a (c_i - y_lo)))`,
//!   which needs neither the plate's position nor an exponential.

use serde::{Deserialize, Serialize, de::DeserializeOwned};

pub mod binned;
pub mod horizon;
pub mod path;
pub mod sumtree;

use super::core::bags::{Attached, count};
use super::core::pick::Pick;
use crate::engine::alloc::AllocError;
use crate::rng::{Pcg64, UniformSource};
use horizon::Horizon;
use path::PlatePath;
use sumtree::SumTree2;

/// Rates whose exponent `a |x|` exceeds this are treated as infinite: the junction
/// ruptures at once (docs/model.md, "Equations", item 6: a rate that overflows means
/// immediate rupture).
pub const EXPONENT_CAP: f64 = 600.0;
/// Re-base the coordinates before `a |y|` exceeds this, so weights stay finite.
pub const FRAME_EXPONENT_LIMIT: f64 = 64.0;
/// Whether the rate of a junction with anchor `c` overflows with the plate at `y`: its
/// exponent `a |y - c|` or its weight's `a |c|` beyond [`EXPONENT_CAP`] (it ruptures at once).
#[inline]
pub fn overflows(a: f64, c: f64, y: f64) -> bool {
    a * (y - c).abs() > EXPONENT_CAP || anchor_overflows(a, c)
}

/// Whether the weights of anchor `c` overflow: `a |c|` beyond [`EXPONENT_CAP`].
#[inline]
pub fn anchor_overflows(a: f64, c: f64) -> bool {
    a * c.abs() > EXPONENT_CAP
}

/// A junction's weights `[exp(-a c), exp(a c)]`, the two terms of its rate bound.
#[inline]
fn weights(a: f64, c: f64) -> [f64; 2] {
    let e = (a * c).exp();
    [1.0 / e, e]
}

/// Rupture rate of the candidate channel until the next restart, and how long it holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plan {
    pub rate: f64,
    pub horizon: f64,
}

/// How the closed-form engine samples the ruptures of a bond kind ([`crate::physics::Bond`]):
/// its channel clock, envelope and sum tree (machinery, not a second kind of bond).
pub trait RuptureModel: Clone + std::fmt::Debug + Serialize + DeserializeOwned + Send + 'static {
    /// `true` for force-dependent rates.
    const IS_WEAK: bool;
    /// A junction was attached into `slot` of `attached` with anchor `c`, the plate at `y`
    /// (the model may keep a handle in its record). Returns `false` when its rate is beyond
    /// [`EXPONENT_CAP`] (it must rupture at once).
    fn attached(&mut self, attached: &mut [Attached], slot: usize, c: f64, y: f64) -> bool;
    /// The junction `a` was removed from `slot` by `swap_remove` (the one in the last slot
    /// `last` moved into it, unless `slot == last`).
    fn detached(&mut self, attached: &mut [Attached], slot: usize, last: usize, a: &Attached);
    /// The candidate rate over the trajectory that starts now, and its horizon.
    fn plan<P: PlatePath>(&mut self, traj: &P, n_att: usize) -> Plan;
    /// A candidate at time `s` on the piece `traj`: the slot that ruptures, or `None` if
    /// rejected.
    fn pick<P: PlatePath>(&mut self, rng: &mut Pcg64, traj: &P, s: f64, attached: &[Attached]) -> Option<usize>;
    /// The coordinates were re-based: recompute everything from `attached`. Returns the
    /// slots whose rate is beyond [`EXPONENT_CAP`].
    fn rebuild(&mut self, attached: &mut [Attached]) -> Vec<usize>;
    /// Whether the frame must be re-based now: `a |y|` too large for the weights, or
    /// (weak bonds) a thinning horizon too short to be resolved at the local time `tau`.
    fn needs_rebase(&self, y: f64, tau: f64) -> bool;
    /// Prefetches the memory the next pick will touch.
    #[inline]
    fn prefetch(&self, _attached: &[Attached]) {}
}

/// Strong bonds: constant rate `k0`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrongRupture {
    pub k0: f64,
    /// The next uniform pick of an attached junction.
    next: Pick,
}

impl StrongRupture {
    pub fn new(k0: f64, rng: &mut Pcg64) -> StrongRupture {
        StrongRupture { k0, next: Pick::draw(rng) }
    }
}

impl RuptureModel for StrongRupture {
    const IS_WEAK: bool = false;
    #[inline]
    fn attached(&mut self, _attached: &mut [Attached], _slot: usize, _c: f64, _y: f64) -> bool {
        true
    }
    #[inline]
    fn detached(&mut self, _attached: &mut [Attached], _slot: usize, _last: usize, _a: &Attached) {}
    #[inline]
    fn plan<P: PlatePath>(&mut self, _traj: &P, n_att: usize) -> Plan {
        Plan { rate: self.k0 * count(n_att), horizon: f64::INFINITY }
    }
    #[inline]
    fn pick<P: PlatePath>(&mut self, rng: &mut Pcg64, _traj: &P, _s: f64, attached: &[Attached]) -> Option<usize> {
        Some(self.next.take(attached.len(), rng))
    }
    #[inline(always)]
    fn prefetch(&self, attached: &[Attached]) {
        self.next.prefetch(attached);
    }
    fn rebuild(&mut self, _attached: &mut [Attached]) -> Vec<usize> {
        Vec::new()
    }
    #[inline]
    fn needs_rebase(&self, _y: f64, _tau: f64) -> bool {
        false
    }
}

/// Weak bonds with the linear law: thinning against a proven bound, sum-tree selection.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WeakRupture {
    pub k0: f64,
    /// `a = beta dx kappa`.
    pub a: f64,
    /// Weights `[exp(-a c), exp(a c)]` per attached slot.
    tree: SumTree2,
    /// The current horizon's bounds and their factors.
    h: Horizon,
}

/// Relative margins of the acceptance squeeze in [`WeakRupture::pick`]: `1 -+ 1e-9`.
const SQUEEZE_LO: f64 = 1.0 - 1e-9;
const SQUEEZE_HI: f64 = 1.0 + 1e-9;

impl WeakRupture {
    pub fn new(k0: f64, a: f64, n: usize) -> WeakRupture {
        Self::try_new(k0, a, n).unwrap_or_else(|e| panic!("{e}"))
    }
    /// [`WeakRupture::new`], with its sum tree reserved fallibly.
    pub fn try_new(k0: f64, a: f64, n: usize) -> Result<WeakRupture, AllocError> {
        Ok(WeakRupture { k0, a, tree: SumTree2::try_new(n)?, h: Horizon::default() })
    }
    /// Weighs the junction in `slot` with anchor `c`, the plate at `y`; `false` (and no
    /// weight) when its rate is beyond [`EXPONENT_CAP`].
    #[inline]
    pub fn weigh(&mut self, slot: usize, c: f64, y: f64) -> bool {
        if overflows(self.a, c, y) {
            self.tree.set(slot, [0.0; 2]);
            return false;
        }
        self.tree.set(slot, weights(self.a, c));
        true
    }
    /// The junction in `slot` left by `swap_remove` (the last slot `last` moved into it).
    #[inline]
    pub fn unweigh(&mut self, slot: usize, last: usize) {
        self.tree.swap_remove(slot, last);
    }
    /// Every weight recomputed from `attached`; the slots whose rate is beyond
    /// [`EXPONENT_CAP`] (weighed zero).
    pub fn reweigh(&mut self, attached: &[Attached]) -> Vec<usize> {
        let a = self.a;
        let over: Vec<usize> = (0..attached.len()).filter(|&s| anchor_overflows(a, attached[s].c)).collect();
        self.tree.rebuild(attached.iter().map(|j| if anchor_overflows(a, j.c) { [0.0; 2] } else { weights(a, j.c) }));
        over
    }
    /// The anchor of `slot` from its weight `exp(a c)` (tests).
    #[cfg(test)]
    pub(crate) fn anchor_of(&self, slot: usize) -> f64 {
        self.tree.get(slot)[1].ln() / self.a
    }
    /// `exp(a y_hi) W-` and `exp(-a y_lo) W+`.
    #[inline]
    fn terms(&self) -> (f64, f64) {
        self.h.terms(self.tree.total())
    }
    /// The envelope for any plate path with `y_lo <= y <= y_hi` (tilted law,
    /// [`crate::engine::exact::stepper::series`]): sets the bounds and returns the total candidate
    /// rate `B / k0 = exp(a y_hi) W- + exp(-a y_lo) W+` (in units of `k0`; may be `+inf`).
    #[inline]
    pub fn envelope(&mut self, y_lo: f64, y_hi: f64) -> f64 {
        self.h.set_bounds(self.a, y_lo, y_hi);
        let (m, p) = self.terms();
        m + p
    }
    /// A candidate of the envelope last set by [`WeakRupture::envelope`]: the slot, drawn
    /// with probability `b_i / B`, and its [`Bracket`] (from its leaf weights, which the
    /// descent has just read: no access to the junction).
    #[inline]
    pub fn envelope_candidate(&self, rng: &mut Pcg64, n_att: usize) -> (usize, Bracket) {
        let (m, p) = self.terms();
        let u = rng.uniform() * (m + p);
        let (e_hi, e_lo) = (self.h.e_hi, self.h.e_lo);
        let slot = if u < m { self.tree.find(0, u / e_hi) } else { self.tree.find(1, (u - m) / e_lo) };
        let slot = slot.min(n_att - 1);
        let w = self.tree.get(slot);
        let (hi0, hi1) = (e_hi * w[0], e_lo * w[1]);
        let bracket = Bracket { b: hi0 + hi1, lo: (w[0] / e_lo).max(w[1] / e_hi), hi: hi0.max(hi1) };
        (slot, bracket)
    }
}

/// What a candidate's leaf weights say of `e^{a |x|}`, `x = y - c_i`, for every plate
/// position `y_lo <= y <= y_hi` of the envelope (in units of `k0`):
/// `lo = max(exp(a (y_lo - c_i)), exp(a (c_i - y_hi))) <= e^{a |x|} <= hi = max(exp(a (y_hi - c_i)), exp(a (c_i - y_lo)))`,
/// and the candidate's bound `b = exp(a (y_hi - c_i)) + exp(a (c_i - y_lo)) >= hi`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bracket {
    pub b: f64,
    pub lo: f64,
    pub hi: f64,
}

impl Bracket {
    /// Decides a candidate whose rate `r` (units of `k0`) lies in `[lo_r, hi_r]`, with the
    /// uniform product `ub = U b`, without the rate itself: `Some(true)` if `ub < lo_r`,
    /// `Some(false)` if `ub >= hi_r`, `None` in between. The margins (1e-9 relative, far above
    /// the round-off of the bounds and of the rate) make it agree with the exact test `ub < r`.
    #[inline]
    pub fn squeeze(ub: f64, lo_r: f64, hi_r: f64) -> Option<bool> {
        if ub < SQUEEZE_LO * lo_r {
            Some(true)
        } else if ub >= SQUEEZE_HI * hi_r {
            Some(false)
        } else {
            None
        }
    }
}

impl RuptureModel for WeakRupture {
    const IS_WEAK: bool = true;
    #[inline]
    fn attached(&mut self, _attached: &mut [Attached], slot: usize, c: f64, y: f64) -> bool {
        self.weigh(slot, c, y)
    }
    #[inline]
    fn detached(&mut self, _attached: &mut [Attached], slot: usize, last: usize, _a: &Attached) {
        self.tree.swap_remove(slot, last);
    }
    fn plan<P: PlatePath>(&mut self, traj: &P, n_att: usize) -> Plan {
        self.h.plan(traj, n_att, self.k0, self.a, self.tree.total())
    }
    #[inline]
    fn pick<P: PlatePath>(&mut self, rng: &mut Pcg64, traj: &P, s: f64, attached: &[Attached]) -> Option<usize> {
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
        accept(ub, w, e_hi, e_lo, || (self.a * traj.position(s)).exp()).then_some(slot)
    }
    fn rebuild(&mut self, attached: &mut [Attached]) -> Vec<usize> {
        self.reweigh(attached)
    }
    #[inline]
    fn needs_rebase(&self, y: f64, tau: f64) -> bool {
        self.h.needs_rebase(self.a, y, tau)
    }
}

/// The thinning test `U b < r` of a candidate with weights `w = [w0, w1]` (`w0 >= exp(-a c)`,
/// `w1 >= exp(a c)` up to round-off, `w0 w1 = 1` for the sum tree's exact weights) under the
/// factors `e_hi = exp(a y_hi)`, `e_lo = exp(-a y_lo)`, given `ub = U b`: `r = e^{a |y - c|}
/// = max(exp(a y) w0, w1 / exp(a y))` (units of `k0`, `ey()` giving `exp(a y)` at the
/// candidate's time). Squeezed first: with `y_lo <= y <= y_hi`, `r` lies between
/// `max(w0 / e_lo, w1 / e_hi)` and `max(e_hi w0, e_lo w1)`, and a uniform outside decides
/// without the plate's position and its exponential (the margins of [`Bracket::squeeze`]
/// make both tests agree with the exact one). All factors stay finite: `|a y| <=
/// FRAME_EXPONENT_LIMIT` and `|a c| <= EXPONENT_CAP`.
#[inline]
pub fn accept(ub: f64, w: [f64; 2], e_hi: f64, e_lo: f64, ey: impl FnOnce() -> f64) -> bool {
    match Bracket::squeeze(ub, (w[0] / e_lo).max(w[1] / e_hi), (e_hi * w[0]).max(e_lo * w[1])) {
        Some(decided) => decided,
        None => {
            let ey = ey();
            ub < (ey * w[0]).max(w[1] / ey)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::exact::rupture::path::Drive;

    /// A plan bounds every junction's rate over its whole horizon (`b_i >= r_i`: the
    /// acceptance never exceeds 1), and the acceptance squeeze of `pick` brackets the rate:
    /// `max(w0 / e_lo, w1 / e_hi) <= r_i <= max(e_hi w0, e_lo w1) <= b_i`.
    #[test]
    fn plan_bounds_every_rate_over_its_horizon() {
        let a = 3.0;
        let n = 64;
        let mut rng = crate::rng::pcg(4);
        let mut w = WeakRupture::new(1.0, a, n);
        let anchors: Vec<f64> = (0..n).map(|_| (rng.uniform() - 0.5) * 4.0).collect();
        for (slot, &c) in anchors.iter().enumerate() {
            assert!(w.weigh(slot, c, 0.0));
        }
        for drive in [Drive { y0: 0.3, v: 0.7 }, Drive { y0: -0.5, v: -2.0 }, Drive { y0: 1.1, v: 1e-9 }] {
            let plan = w.plan(&drive, n);
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
