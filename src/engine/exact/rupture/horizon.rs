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
    /// (at least `exp(x)`, up to the exponential's own round-off, as `exp(x)` itself).
    /// Always inlined, its table built out of line ([`ExpGrid::build`]): in the `release`
    /// build an out-of-line version would be a call per bound.
    #[inline(always)]
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
            self.build();
        }
        self.0[(g + GRID_MAX as i64) as usize]
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
    /// [`CANDIDATES_PER_HORIZON`], because the bound is renewed at every event anyway.
    last_rate: f64,
    /// The rates cannot be bounded over even the shortest horizon (`HORIZON_MIN`): every
    /// attached junction ruptures at once, one candidate each, all accepted.
    pub immediate: bool,
    /// The last plan bounded attached junctions (its horizon is meaningful).
    bounding: bool,
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
            grid: ExpGrid::default(),
        }
    }
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
        self.y_lo = y_lo;
        self.y_hi = y_hi;
        self.e_hi = self.grid.exp_up(a * y_hi);
        self.e_lo = self.grid.exp_up(-a * y_lo);
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
        self.plan_with(bounds, n_att, k0, a, |_, _| w)
    }
    /// [`Horizon::plan`] with weight sums that depend on the final bounds: `w(y_lo, y_hi)`,
    /// asked once (the bins' terms in force, [`super::BinnedRupture`]).
    #[inline(always)]
    pub fn plan_with(
        &mut self,
        mut bounds: impl FnMut(f64) -> (f64, f64),
        n_att: usize,
        k0: f64,
        a: f64,
        w: impl FnOnce(f64, f64) -> [f64; 2],
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
            let (m, p) = self.terms(w(0.0, 0.0));
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
        self.set_grid_bounds(a, b.0, b.1);
        self.bounding = true;
        let (m, p) = self.terms(w(b.0, b.1));
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
            let (e, exact) = (g.exp_up(x), x.exp());
            assert!(e >= exact, "x {x}: {e} < {exact}");
            assert!(e <= exact * (1.0 / GRID).exp() * (1.0 + 1e-14), "x {x}: {e} vs {exact}");
        }
        assert_eq!(g.exp_up(0.0), 1.0);
    }
}
