//! The thinning horizon of the weak-bond rupture models ([`TreeRupture`], [`BinnedRupture`])
//! over a closed-form plate: over a horizon `[tau, tau + H]` on which the plate stays within proven
//! bounds `y_lo <= y <= y_hi`, every rate `k0 exp(a |y - c_i|)` is at most
//! `k0 (exp(a y_hi) w0_i + exp(-a y_lo) w1_i)` for any weights `w0_i >= exp(-a c_i)`,
//! `w1_i >= exp(a c_i)`, so candidates at the constant rate
//! `B = k0 (exp(a y_hi) W0 + exp(-a y_lo) W1)` (`Wk` the sums of the weights) thinned by
//! `r_i / b_i` are exactly the ruptures. [`Horizon`] chooses `H` (the bound's spread
//! `a (y_hi - y_lo)` at most [`SPREAD`]), keeps the two factors, and says when the frame must
//! be re-based; the models keep the weights.
//!
//! [`TreeRupture`]: super::TreeRupture
//! [`BinnedRupture`]: super::binned::BinnedRupture

use serde::{Deserialize, Serialize};

use super::accept::FRAME_EXPONENT_LIMIT;
use super::contract::Plan;

/// Target spread of a thinning bound: the largest `a (y_hi - y_lo)` (dimensionless) over the
/// plate's proven bounds `[y_lo, y_hi]` within a horizon [`Horizon::plan`] chooses, or within
/// a plate step of a stepped plate, so the candidate rate exceeds every junction's rupture
/// rate there by at most a factor `e^SPREAD` per exponential term (a candidate's acceptance
/// stays above `e^-1 / 2`).
pub const SPREAD: f64 = 1.0;
/// Longest horizon (local time units).
const HORIZON_MAX: f64 = 1e6;
/// Shortest horizon: a plate that moves by more than `SPREAD / a` within it (the rates
/// change by more than a factor `e` within `1e-300` time units) ruptures every attached
/// junction at once, as an overflowing rate does.
const HORIZON_MIN: f64 = 1e-300;
/// Re-base the time origin when the horizon is shorter than this fraction of the local
/// time: `tau + horizon` must stay distinguishable from `tau` (2^-40, so 12 bits remain).
const TIME_RESOLUTION: f64 = 9.094947017729282e-13;

/// Grid steps per unit of the exponent `a y` on which [`Horizon::plan`] rounds its bounds
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
    /// (at least `exp(x)`, up to the exponential's own round-off, as `exp(x)` itself), and
    /// the largest exponent whose exponential it bounds: `g / GRID` on the table, `x` itself
    /// beyond it. Always inlined, its table built out of line ([`ExpGrid::build`]): in the
    /// `release` build an out-of-line version would be a call per bound.
    #[inline(always)]
    fn exp_up_to(&mut self, x: f64) -> (f64, f64) {
        let t = x * GRID;
        if t.is_nan() || t.abs() >= GRID_MAX as f64 {
            return (x.exp(), x);
        }
        // ceil(t) by truncation (`f64::ceil` is a library call without SSE4.1).
        let mut g = t as i64;
        if (g as f64) < t {
            g += 1;
        }
        if self.0.is_empty() {
            self.build();
        }
        (self.0[(g + GRID_MAX as i64) as usize], g as f64 / GRID)
    }
    /// The table, once.
    #[cold]
    #[inline(never)]
    fn build(&mut self) {
        self.0 = (0..=2 * GRID_MAX).map(|i| ((i as f64 - GRID_MAX as f64) / GRID).exp()).collect();
    }
}

/// A horizon longer than this many expected candidates only loosens the bound.
const CANDIDATES_PER_HORIZON: f64 = 32.0;

/// The bounds of the current horizon and their two factors, and the state of the search
/// for the next horizon.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Horizon {
    /// Bounds of the current horizon, and `exp(a y_hi)`, `exp(-a y_lo)` (for plans, rounded
    /// up to the grid of [`Horizon::set_grid_bounds`]).
    pub y_lo: f64,
    pub y_hi: f64,
    pub e_hi: f64,
    pub e_lo: f64,
    /// Last horizon length (the next search starts there).
    horizon: f64,
    /// Last candidate rate: the horizon need not cover many more candidates than
    /// [`CANDIDATES_PER_HORIZON`]: a longer horizon only loosens the bound.
    last_rate: f64,
    /// The rates cannot be bounded over even the shortest horizon (`HORIZON_MIN`): every
    /// attached junction ruptures at once, one candidate each, all accepted.
    pub immediate: bool,
    /// The last plan bounded attached junctions (its horizon is meaningful).
    bounding: bool,
    /// `[lo, hi]`: the plate positions within which the plan's factors (and a model's own
    /// limits, such as the bins' sides) still bound every rate, a little inside the exact
    /// ones for round-off ([`Horizon::widen`]). A checkpoint written without them restores
    /// none: its first event plans anew.
    #[serde(default = "no_limits")]
    limits: [f64; 2],
    /// `exp(g / GRID)` for the plans' bounds on the grid ([`Horizon::set_grid_bounds`]).
    #[serde(skip)]
    grid: ExpGrid,
}

impl Default for Horizon {
    fn default() -> Horizon {
        Horizon {
            y_lo: 0.0,
            y_hi: 0.0,
            e_hi: 1.0,
            e_lo: 1.0,
            horizon: 1.0,
            last_rate: 0.0,
            immediate: false,
            bounding: false,
            limits: no_limits(),
            grid: ExpGrid::default(),
        }
    }
}

/// Limits no position is within.
fn no_limits() -> [f64; 2] {
    [f64::INFINITY, f64::NEG_INFINITY]
}

/// `[lo, hi]` moved inwards by `1e-12` of their magnitude and of `1/a`: a position within
/// them is within the exact limits after the rounding of any product that tests it (none
/// for limits that are not finite).
#[inline]
fn inside(lo: f64, hi: f64, a: f64) -> [f64; 2] {
    let guard = 1e-12 * (lo.abs().max(hi.abs()) + 1.0 / a);
    if guard.is_finite() { [lo + guard, hi - guard] } else { no_limits() }
}

impl Horizon {
    /// Sets the bounds `[y_lo, y_hi]` and their factors `exp(a y_hi)`, `exp(-a y_lo)`.
    #[inline]
    pub fn set_bounds(&mut self, a: f64, y_lo: f64, y_hi: f64) {
        self.y_lo = y_lo;
        self.y_hi = y_hi;
        self.e_hi = (a * y_hi).exp();
        self.e_lo = (-a * y_lo).exp();
    }
    /// Sets bounds at least as wide as `[y_lo, y_hi]`, with the exponents `a y_hi` and
    /// `-a y_lo` rounded up to the grid `1/GRID` (tabulated: no exponential). Every rate
    /// bound `b_i` stays above `r_i` on `[y_lo, y_hi]`, at most `exp(1/GRID)` looser. Used by
    /// the plans and by the bound over a plate step alike.
    #[inline]
    pub fn set_grid_bounds(&mut self, a: f64, y_lo: f64, y_hi: f64) {
        self.grid_bounds(a, y_lo, y_hi);
    }
    /// [`Horizon::set_grid_bounds`], returning the largest exponents its two factors bound
    /// (`[x_lo, x_hi]`: `exp(-a y) <= e_lo` for `-a y <= x_lo`, `exp(a y) <= e_hi` for
    /// `a y <= x_hi`, `ExpGrid::exp_up_to`).
    #[inline(always)]
    fn grid_bounds(&mut self, a: f64, y_lo: f64, y_hi: f64) -> [f64; 2] {
        self.y_lo = y_lo;
        self.y_hi = y_hi;
        let (e_hi, x_hi) = self.grid.exp_up_to(a * y_hi);
        let (e_lo, x_lo) = self.grid.exp_up_to(-a * y_lo);
        (self.e_hi, self.e_lo) = (e_hi, e_lo);
        [x_lo, x_hi]
    }
    /// `exp(a y_hi) W0` and `exp(-a y_lo) W1` for the weight sums `w = [W0, W1]`.
    #[inline]
    pub fn terms(&self, w: [f64; 2]) -> (f64, f64) {
        (self.e_hi * w[0], self.e_lo * w[1])
    }
    /// The candidate rate `B = k0 (exp(a y_hi) W0 + exp(-a y_lo) W1)` over the plate's path
    /// from now (`bounds(h)`: its proven bounds over the next `h`), for `n_att` attached
    /// junctions whose weights sum to `w`, and its horizon: the longest (within a factor 2)
    /// whose spread `a (y_hi - y_lo)` is at most [`SPREAD`] and that covers about
    /// `CANDIDATES_PER_HORIZON` candidates at the last rate.
    #[inline(always)]
    pub fn plan(&mut self, bounds: impl FnMut(f64) -> (f64, f64), n_att: usize, k0: f64, a: f64, w: [f64; 2]) -> Plan {
        self.plan_with(bounds, n_att, k0, a, |_, _| (w, [f64::NEG_INFINITY, f64::INFINITY]))
    }
    /// [`Horizon::plan`] with weight sums that depend on the final bounds: `w(y_lo, y_hi)`,
    /// asked once (the bins' terms in force, [`super::BinnedRupture`]), which returns them
    /// with the positions `[lo, hi]` within which they hold (`[-inf, inf]`: everywhere).
    #[inline(always)]
    pub fn plan_with(
        &mut self,
        mut bounds: impl FnMut(f64) -> (f64, f64),
        n_att: usize,
        k0: f64,
        a: f64,
        w: impl FnOnce(f64, f64) -> ([f64; 2], [f64; 2]),
    ) -> Plan {
        self.immediate = false;
        self.bounding = false;
        if n_att == 0 || k0 == 0.0 {
            return Plan { rate: 0.0, horizon: f64::INFINITY };
        }
        if a == 0.0 {
            // Constant rate k0: the bound is exact up to the factor of its two terms (2 with
            // the tree's weights, about 2.2 with the bins' bounds).
            self.set_bounds(a, 0.0, 0.0);
            let (m, p) = self.terms(w(0.0, 0.0).0);
            return Plan { rate: k0 * (m + p), horizon: f64::INFINITY };
        }
        let cap =
            if self.last_rate > 0.0 { (CANDIDATES_PER_HORIZON / self.last_rate).min(HORIZON_MAX) } else { HORIZON_MAX };
        let mut h = self.horizon.min(cap).max(HORIZON_MIN);
        let mut b = bounds(h);
        // Halve until the spread is resolved (about 1000 halvings at most, from HORIZON_MAX
        // to HORIZON_MIN; usually none, the search starts from the last horizon).
        while a * (b.1 - b.0) > SPREAD && h > HORIZON_MIN {
            h = (h * 0.5).max(HORIZON_MIN);
            b = bounds(h);
        }
        while 2.0 * h <= cap {
            let b2 = bounds(2.0 * h);
            if a * (b2.1 - b2.0) > SPREAD {
                break;
            }
            h *= 2.0;
            b = b2;
        }
        self.horizon = h;
        let [x_lo, x_hi] = self.grid_bounds(a, b.0, b.1);
        self.bounding = true;
        let (weights, [lo, hi]) = w(b.0, b.1);
        self.limits = inside(lo.max(-x_lo / a), hi.min(x_hi / a), a);
        let (m, p) = self.terms(weights);
        let rate = k0 * (m + p);
        if a * (b.1 - b.0) > SPREAD || !rate.is_finite() {
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
    /// After an event inside the horizon, whose effect on the plate's path is at most
    /// `reach(y_lo, y_hi)` in position (for a path that was within the bounds), the bounds
    /// widened by it (and by the additions' rounding); whether they still lie within the
    /// plan's limits, so that the plan holds to the horizon's end. `false` when the last
    /// plan bounds nothing over a horizon (a constant rate, all rupturing at once) or the
    /// reach is not a number.
    #[inline]
    pub fn widen(&mut self, reach: impl FnOnce(f64, f64) -> f64) -> bool {
        if !self.bounding || self.immediate {
            return false;
        }
        let d = reach(self.y_lo, self.y_hi) + 4.0 * f64::EPSILON * (self.y_lo.abs() + self.y_hi.abs());
        self.y_lo -= d;
        self.y_hi += d;
        self.y_lo >= self.limits[0] && self.y_hi <= self.limits[1]
    }
    /// A model's [`RuptureModel::replan`](super::RuptureModel::replan) over this horizon:
    /// with `n_att` junctions attached, the plan's bounds widened by `reach` ([`Horizon::widen`]),
    /// and if they hold, the candidate rate `k0 (e_hi W0 + e_lo W1)` for the weight sums
    /// `weights()` of the junctions attached now, kept if it is a positive number (the next
    /// search's cap follows it).
    #[inline(always)]
    pub fn replan(
        &mut self,
        reach: impl FnOnce(f64, f64) -> f64,
        n_att: usize,
        k0: f64,
        weights: impl FnOnce() -> [f64; 2],
    ) -> Option<f64> {
        if n_att == 0 || !self.widen(reach) {
            return None;
        }
        let (m, p) = self.terms(weights());
        let rate = k0 * (m + p);
        (rate.is_finite() && rate > 0.0).then(|| {
            self.last_rate = rate;
            rate
        })
    }
    /// The plan no longer bounds anything (the frame moved): the next one is searched afresh.
    #[inline]
    pub fn forget(&mut self) {
        self.bounding = false;
    }
    /// Whether the frame must be re-based now: `a |y|` too large for the weights, or a
    /// thinning horizon too short to be resolved at the local time `tau`.
    #[inline]
    pub fn needs_rebase(&self, a: f64, y: f64, tau: f64) -> bool {
        a * y.abs() > FRAME_EXPONENT_LIMIT || (self.bounding && self.horizon < TIME_RESOLUTION * tau.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::UniformSource;

    /// The grid's factors bound the exponentials from above, within a factor `exp(1/GRID)`,
    /// inside the table and beyond it.
    #[test]
    fn grid_rounds_exponentials_up() {
        let mut g = ExpGrid::default();
        let mut rng = crate::rng::pcg(3);
        for i in 0..100_000 {
            let x = if i % 2 == 0 { (rng.uniform() - 0.5) * 200.0 } else { (rng.uniform() - 0.5) * 1e-3 };
            let (e, exact) = (g.exp_up_to(x).0, x.exp());
            assert!(e >= exact, "x {x}: {e} < {exact}");
            assert!(e <= exact * (1.0 / GRID).exp() * (1.0 + 1e-14), "x {x}: {e} vs {exact}");
        }
        assert_eq!(g.exp_up_to(0.0), (1.0, 0.0));
    }

    /// A plan's limits: at every position within them (ends included) its factors bound
    /// `exp(a y)` and `exp(-a y)` (to the exponential's own rounding); they contain the
    /// plan's bounds unless a bound sits within the round-off guard of a grid point, and
    /// lie within a grid step of them. Widening by nothing keeps a plan, by the distance to
    /// a limit does not, and a plan that bounds nothing is never kept.
    #[test]
    fn plans_hold_within_their_limits() {
        let mut rng = crate::rng::pcg(5);
        let mut kept = 0;
        for i in 0..20_000 {
            let a = [1e-3, 0.1, 1.0, 37.0][i % 4];
            let y_lo = (rng.uniform() - 0.5) * 2.0 * FRAME_EXPONENT_LIMIT / a;
            let y_hi = y_lo + rng.uniform() * SPREAD / a;
            let mut h = Horizon::default();
            let plan = h.plan(|_| (y_lo, y_hi), 10, 1.0, a, [1.0, 1.0]);
            assert!(plan.rate.is_finite() && h.bounding && !h.immediate);
            let [lo, hi] = h.limits;
            assert!(lo <= hi && lo > y_lo - 1.0 / (GRID * a) * 1.01 && hi < y_hi + 1.0 / (GRID * a) * 1.01);
            for k in 0..=8 {
                let y = lo + (hi - lo) * k as f64 / 8.0;
                let tol = 1.0 + 4.0 * f64::EPSILON;
                assert!((a * y).exp() <= h.e_hi * tol && (-a * y).exp() <= h.e_lo * tol, "a {a} y {y} in [{lo}, {hi}]");
            }
            if lo <= y_lo && y_hi <= hi {
                kept += 1;
                let mut widened = h.clone();
                assert!(widened.widen(|_, _| 0.0));
                let mut far = h.clone();
                assert!(!far.widen(|l, u| (hi - u).max(l - lo) * 1.5 + 1e-300));
                assert!(!h.clone().widen(|_, _| f64::NAN));
            }
        }
        assert!(kept > 19_000, "{kept} plans contain their bounds");
        let mut flat = Horizon::default();
        flat.plan(|_| (0.0, 1.0), 10, 1.0, 0.0, [1.0, 1.0]);
        assert!(!flat.widen(|_, _| 0.0), "a constant rate bounds nothing over a horizon");
    }
}
