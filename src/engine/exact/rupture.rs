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

use super::bags::{Attached, count};
use super::motion::PlatePath;
use super::pick::Pick;
use super::sumtree::SumTree2;
use crate::engine::alloc::AllocError;
use crate::rng::{Pcg64, UniformSource};

/// Rates whose exponent `a |x|` exceeds this are treated as infinite: the junction
/// ruptures at once (docs/model.md, "Equations", item 6: a rate that overflows means
/// immediate rupture).
pub const EXPONENT_CAP: f64 = 600.0;
/// Re-base the coordinates before `a |y|` exceeds this, so weights stay finite.
pub const FRAME_EXPONENT_LIMIT: f64 = 64.0;
/// Target spread `a (y_hi - y_lo)` of a thinning horizon.
const SPREAD: f64 = 1.0;
/// Longest horizon (local time units).
const HORIZON_MAX: f64 = 1e6;
/// Shortest horizon: a plate that moves by more than `SPREAD / a` within it (the rates
/// change by more than a factor `e` within `1e-300` time units) ruptures every attached
/// junction at once, as an overflowing rate does.
const HORIZON_MIN: f64 = 1e-300;
/// Re-base the time origin when the horizon is shorter than this fraction of the local
/// time: `tau + horizon` must stay distinguishable from `tau` (2^-40, so 12 bits remain).
const TIME_RESOLUTION: f64 = 9.094947017729282e-13;

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
    /// A junction was attached into `slot` with anchor `c`. Returns `false` when its rate
    /// is beyond [`EXPONENT_CAP`] (it must rupture at once).
    fn attached(&mut self, slot: usize, c: f64, y: f64) -> bool;
    /// The junction in `slot` was removed by `swap_remove`; `moved` is the anchor of the
    /// junction that moved from the last slot `last` into `slot`, if any.
    fn detached(&mut self, slot: usize, last: usize, moved: Option<f64>);
    /// The candidate rate over the trajectory that starts now, and its horizon.
    fn plan<P: PlatePath>(&mut self, traj: &P, n_att: usize) -> Plan;
    /// A candidate at time `s` on the piece `traj`: the slot that ruptures, or `None` if
    /// rejected.
    fn pick<P: PlatePath>(&mut self, rng: &mut Pcg64, traj: &P, s: f64, attached: &[Attached]) -> Option<usize>;
    /// The coordinates were re-based: recompute everything from `attached`. Returns the
    /// slots whose rate is beyond [`EXPONENT_CAP`].
    fn rebuild(&mut self, attached: &[Attached]) -> Vec<usize>;
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
    fn attached(&mut self, _slot: usize, _c: f64, _y: f64) -> bool {
        true
    }
    #[inline]
    fn detached(&mut self, _slot: usize, _last: usize, _moved: Option<f64>) {}
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
    fn rebuild(&mut self, _attached: &[Attached]) -> Vec<usize> {
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
    /// Bounds of the current horizon, and `exp(a y_hi)`, `exp(-a y_lo)` (for the linear
    /// engine's plans, rounded up to the grid of [`WeakRupture::set_grid_bounds`]).
    y_lo: f64,
    y_hi: f64,
    e_hi: f64,
    e_lo: f64,
    /// Last horizon length (the next search starts there).
    horizon: f64,
    /// Last candidate rate: the horizon need not cover many more candidates than
    /// [`CANDIDATES_PER_HORIZON`], because the bound is renewed at every event anyway.
    last_rate: f64,
    /// The rates cannot be bounded over even the shortest horizon ([`HORIZON_MIN`]): every
    /// attached junction ruptures at once, one candidate each, all accepted.
    #[serde(default)]
    immediate: bool,
    /// The last plan bounded attached junctions (its horizon is meaningful).
    #[serde(default)]
    bounding: bool,
    /// `exp(g / GRID)` for the plans' bounds on the grid ([`WeakRupture::set_grid_bounds`]).
    #[serde(skip)]
    grid: ExpGrid,
}

/// Grid steps per unit of the exponent `a y` on which [`WeakRupture::plan`] rounds its bounds
/// outwards: the bound loosens by at most a factor `exp(1/GRID)` per side, and its two
/// exponentials become table reads.
const GRID: f64 = 64.0;
/// Largest `|g|` in the table: `|a y| <= FRAME_EXPONENT_LIMIT` between re-bases, plus the
/// horizon's spread and a margin; bounds beyond it take `exp` itself.
const GRID_MAX: usize = (GRID as usize) * (FRAME_EXPONENT_LIMIT as usize + 8);

/// The table `exp(g / GRID)`, `g = -GRID_MAX ..= GRID_MAX`, built on first use (a function of
/// constants only: not serialized, and any two tables are equal).
#[derive(Clone, Debug, Default)]
struct ExpGrid(Vec<f64>);

impl PartialEq for ExpGrid {
    fn eq(&self, _: &ExpGrid) -> bool {
        true
    }
}

impl ExpGrid {
    /// `exp(x)` rounded up to the grid: `exp(g / GRID)` with the smallest integer `g >= GRID x`
    /// (at least `exp(x)`, up to the exponential's own round-off, as `exp(x)` itself).
    #[inline]
    fn exp_up(&mut self, x: f64) -> f64 {
        let t = x * GRID;
        if t.is_nan() || t.abs() >= GRID_MAX as f64 {
            return x.exp();
        }
        // ceil(t) by truncation (`f64::ceil` is a library call without SSE4.1).
        let mut g = t as i64;
        if (g as f64) < t {
            g += 1;
        }
        if self.0.is_empty() {
            self.0 = (0..=2 * GRID_MAX).map(|i| ((i as f64 - GRID_MAX as f64) / GRID).exp()).collect();
        }
        self.0[(g + GRID_MAX as i64) as usize]
    }
}

/// Relative margins of the acceptance squeeze in [`WeakRupture::pick`]: `1 -+ 1e-9`.
const SQUEEZE_LO: f64 = 1.0 - 1e-9;
const SQUEEZE_HI: f64 = 1.0 + 1e-9;

/// A horizon longer than this many expected candidates only loosens the bound.
const CANDIDATES_PER_HORIZON: f64 = 32.0;

impl WeakRupture {
    pub fn new(k0: f64, a: f64, n: usize) -> WeakRupture {
        Self::try_new(k0, a, n).unwrap_or_else(|e| panic!("{e}"))
    }
    /// [`WeakRupture::new`], with its sum tree reserved fallibly.
    pub fn try_new(k0: f64, a: f64, n: usize) -> Result<WeakRupture, AllocError> {
        Ok(WeakRupture {
            k0,
            a,
            tree: SumTree2::try_new(n)?,
            y_lo: 0.0,
            y_hi: 0.0,
            e_hi: 1.0,
            e_lo: 1.0,
            horizon: 1.0,
            last_rate: 0.0,
            immediate: false,
            bounding: false,
            grid: ExpGrid::default(),
        })
    }
    #[inline]
    fn weights(&self, c: f64) -> [f64; 2] {
        let e = (self.a * c).exp();
        [1.0 / e, e]
    }
    /// Sets the bounds of the horizon.
    #[inline]
    fn set_bounds(&mut self, y_lo: f64, y_hi: f64) {
        self.y_lo = y_lo;
        self.y_hi = y_hi;
        self.e_hi = (self.a * y_hi).exp();
        self.e_lo = (-self.a * y_lo).exp();
    }
    /// Sets bounds at least as wide as `[y_lo, y_hi]`, with the exponents `a y_hi` and
    /// `-a y_lo` rounded up to the grid `1/GRID` (tabulated: no exponential). Every rate
    /// bound `b_i` stays above `r_i` on `[y_lo, y_hi]`, at most `exp(1/GRID)` looser.
    #[inline]
    fn set_grid_bounds(&mut self, y_lo: f64, y_hi: f64) {
        self.y_lo = y_lo;
        self.y_hi = y_hi;
        self.e_hi = self.grid.exp_up(self.a * y_hi);
        self.e_lo = self.grid.exp_up(-self.a * y_lo);
    }
    /// The anchor of `slot` from its weight `exp(a c)` (tests).
    #[cfg(test)]
    pub(crate) fn anchor_of(&self, slot: usize) -> f64 {
        self.tree.get(slot)[1].ln() / self.a
    }
    /// `exp(a y_hi) W-` and `exp(-a y_lo) W+`.
    #[inline]
    fn terms(&self) -> (f64, f64) {
        let w = self.tree.total();
        (self.e_hi * w[0], self.e_lo * w[1])
    }
    /// The envelope for any plate path with `y_lo <= y <= y_hi` (tilted law,
    /// [`crate::engine::exact::series`]): sets the bounds and returns the total candidate
    /// rate `B / k0 = exp(a y_hi) W- + exp(-a y_lo) W+` (in units of `k0`; may be `+inf`).
    #[inline]
    pub fn envelope(&mut self, y_lo: f64, y_hi: f64) -> f64 {
        self.set_bounds(y_lo, y_hi);
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
        let slot = if u < m { self.tree.find(0, u / self.e_hi) } else { self.tree.find(1, (u - m) / self.e_lo) };
        let slot = slot.min(n_att - 1);
        let w = self.tree.get(slot);
        let (hi0, hi1) = (self.e_hi * w[0], self.e_lo * w[1]);
        let bracket = Bracket { b: hi0 + hi1, lo: (w[0] / self.e_lo).max(w[1] / self.e_hi), hi: hi0.max(hi1) };
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
    fn attached(&mut self, slot: usize, c: f64, y: f64) -> bool {
        if self.a * (y - c).abs() > EXPONENT_CAP || self.a * c.abs() > EXPONENT_CAP {
            self.tree.set(slot, [0.0; 2]);
            return false;
        }
        let w = self.weights(c);
        self.tree.set(slot, w);
        true
    }
    #[inline]
    fn detached(&mut self, slot: usize, last: usize, _moved: Option<f64>) {
        self.tree.swap_remove(slot, last);
    }
    fn plan<P: PlatePath>(&mut self, traj: &P, n_att: usize) -> Plan {
        self.immediate = false;
        self.bounding = false;
        if n_att == 0 || self.k0 == 0.0 {
            return Plan { rate: 0.0, horizon: f64::INFINITY };
        }
        if self.a == 0.0 {
            // Constant rate k0: the bound is exact up to the factor 2 of the two terms.
            self.set_bounds(0.0, 0.0);
            let (m, p) = self.terms();
            return Plan { rate: self.k0 * (m + p), horizon: f64::INFINITY };
        }
        // Longest horizon (within a factor 2) whose bound spread is at most SPREAD and that
        // covers about CANDIDATES_PER_HORIZON candidates at the last rate.
        let cap =
            if self.last_rate > 0.0 { (CANDIDATES_PER_HORIZON / self.last_rate).min(HORIZON_MAX) } else { HORIZON_MAX };
        let mut h = self.horizon.min(cap).max(HORIZON_MIN);
        let mut b = traj.bounds(h);
        // Halve until the spread is resolved (about 1000 halvings at most, from HORIZON_MAX
        // to HORIZON_MIN; usually none, the search starts from the last horizon).
        while self.a * (b.1 - b.0) > SPREAD && h > HORIZON_MIN {
            h = (h * 0.5).max(HORIZON_MIN);
            b = traj.bounds(h);
        }
        while 2.0 * h <= cap {
            let b2 = traj.bounds(2.0 * h);
            if self.a * (b2.1 - b2.0) > SPREAD {
                break;
            }
            h *= 2.0;
            b = b2;
        }
        self.horizon = h;
        self.set_grid_bounds(b.0, b.1);
        self.bounding = true;
        let (m, p) = self.terms();
        let rate = self.k0 * (m + p);
        if self.a * (b.1 - b.0) > SPREAD || !rate.is_finite() {
            // Not even HORIZON_MIN resolves the rates (the plate crosses more than 1/a in
            // 1e-300 time units), or the bound overflows: every attached junction's rate
            // passes k0 e^EXPONENT_CAP within the horizon, so all rupture now (docs/model.md,
            // "Equations", item 6: a rate that overflows means immediate rupture).
            self.immediate = true;
            self.last_rate = 0.0;
            return Plan { rate: f64::INFINITY, horizon: HORIZON_MIN };
        }
        self.last_rate = rate;
        Plan { rate, horizon: h }
    }
    #[inline]
    fn pick<P: PlatePath>(&mut self, rng: &mut Pcg64, traj: &P, s: f64, attached: &[Attached]) -> Option<usize> {
        if self.immediate {
            return Some(attached.len() - 1);
        }
        let (m, p) = self.terms();
        let u = rng.uniform() * (m + p);
        let slot = if u < m {
            self.tree.find_prefetching(0, u / self.e_hi, attached)
        } else {
            self.tree.find_prefetching(1, (u - m) / self.e_lo, attached)
        };
        // The descent has requested the junction's record (read only if the candidate is
        // accepted).
        let slot = slot.min(attached.len() - 1);
        // Accept with r_i / b_i = exp(a|y-c|) / (exp(a(y_hi-c)) + exp(a(c-y_lo))), from the
        // leaf weights [exp(-a c), exp(a c)] just read by the descent (no access to the
        // junction, at most one exponential): exp(a(y-c)) = exp(a y) w0, exp(a(c-y)) = w1 / exp(a y).
        // All factors stay finite: |a y| <= FRAME_EXPONENT_LIMIT and |a c| <= EXPONENT_CAP.
        let w = self.tree.get(slot);
        let b = self.e_hi * w[0] + self.e_lo * w[1];
        let ub = rng.uniform() * b;
        // Squeeze: with y_lo <= y <= y_hi, r_i lies between
        // r_min = max(w0 / e_lo, w1 / e_hi) = max(exp(a (y_lo - c)), exp(a (c - y_hi))) and
        // r_max = max(e_hi w0, e_lo w1); a uniform outside [r_min, r_max) decides without
        // the plate's position and its exponential. The margins (1e-9 relative, far above
        // the exponentials' round-off) make both tests agree with the exact one below.
        match Bracket::squeeze(ub, (w[0] / self.e_lo).max(w[1] / self.e_hi), (self.e_hi * w[0]).max(self.e_lo * w[1])) {
            Some(true) => return Some(slot),
            Some(false) => return None,
            None => {}
        }
        let y = traj.position(s);
        let ey = (self.a * y).exp();
        let r = (ey * w[0]).max(w[1] / ey);
        (ub < r).then_some(slot)
    }
    fn rebuild(&mut self, attached: &[Attached]) -> Vec<usize> {
        let over: Vec<usize> = (0..attached.len()).filter(|&s| self.a * attached[s].c.abs() > EXPONENT_CAP).collect();
        let (a, cap) = (self.a, EXPONENT_CAP);
        self.tree.rebuild(attached.iter().map(|j| {
            if a * j.c.abs() > cap {
                [0.0; 2]
            } else {
                let e = (a * j.c).exp();
                [1.0 / e, e]
            }
        }));
        over
    }
    #[inline]
    fn needs_rebase(&self, y: f64, tau: f64) -> bool {
        self.a * y.abs() > FRAME_EXPONENT_LIMIT || (self.bounding && self.horizon < TIME_RESOLUTION * tau.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::exact::motion::Drive;

    /// The grid's factors bound the exponentials from above, within a factor `exp(1/GRID)`,
    /// inside the table and beyond it.
    #[test]
    fn grid_rounds_exponentials_up() {
        let mut g = ExpGrid::default();
        let mut rng = crate::rng::pcg(3);
        for i in 0..100_000 {
            let x = if i % 2 == 0 { (rng.uniform() - 0.5) * 200.0 } else { (rng.uniform() - 0.5) * 1e-3 };
            let (e, exact) = (g.exp_up(x), x.exp());
            assert!(e >= exact, "x {x}: {e} < {exact}");
            assert!(e <= exact * (1.0 / GRID).exp() * (1.0 + 1e-14), "x {x}: {e} vs {exact}");
        }
        assert_eq!(g.exp_up(0.0), 1.0);
    }

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
            assert!(w.attached(slot, c, 0.0));
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
                    let b = w.e_hi * wt[0] + w.e_lo * wt[1];
                    let lo = (wt[0] / w.e_lo).max(wt[1] / w.e_hi);
                    let hi = (w.e_hi * wt[0]).max(w.e_lo * wt[1]);
                    let tol = 1.0 + 1e-12;
                    assert!(lo <= r * tol && r <= hi * tol && hi <= b, "y {y} c {c}: {lo} {r} {hi} {b}");
                }
            }
        }
    }
}
