//! Rupture models of the exact engine: how attached junctions rupture, chosen once per run
//! and composed by the core with any plate stepper ([`super::stepper`]).
//!
//! - [`StrongRupture`] (`strong`): every attached junction ruptures at `k0`, so the channel
//!   rate is `k0 N_att` and the junction is a uniform pick. Each candidate is an event.
//! - [`TreeRupture`] (`tree`) and [`BinnedRupture`] (`binned`): weak bonds, junction `i`
//!   rupturing at `r_i(t) = k0 exp(beta dx f(y(t) - c_i))`, bounded by the envelope
//!   `k0 exp(a |y - c_i|)` (`a = beta dx c`, `c` the law's thinning slope, `f <= c |x|`).
//!   Sampled exactly by *thinning*: while the plate stays within proven bounds
//!   `y_lo <= y <= y_hi`, every rate is bounded by
//!   `b_i = k0 (exp(a (y_hi - c_i)) + exp(a (c_i - y_lo)))`; candidates arrive at the constant
//!   total rate `B = k0 (exp(a y_hi) W- + exp(-a y_lo) W+)` (`W-`, `W+` sums of weights
//!   `exp(-a c_i)`, `exp(a c_i)`, or of the bins' bounds on them); a candidate at time `s` picks
//!   junction `i` with probability `b_i / B` and is accepted with probability `r_i(s) / b_i`
//!   ([`RuptureRate`], what the law supplies). Accepted candidates are exactly the rupture
//!   events of the time-dependent rates (Lewis & Shedler 1979; Ogata 1981). The bounds come
//!   from a closed-form plate over a thinning horizon (`horizon`, candidates on a channel) or
//!   from each step of a stepped plate ([`thin`]). The tree draws the junction from a sum
//!   tree of the weights (`sumtree`); the bins a uniform member of a bin of anchors.
//! - [`Hazard`] (`hazard`): weak bonds whose stepper integrates the total rupture rate and
//!   finds the ruptures itself (the direct stepper).
//!
//! The acceptance `r_i / b_i` is first squeezed between bounds read from the junction's
//! weights ([`Bracket::squeeze`]), which decides most candidates without the plate's
//! position or an exponential.

pub mod binned;
pub mod hazard;
pub mod horizon;
pub mod rate;
pub mod strong;
pub mod sumtree;
pub mod thin;
pub mod tree;

use serde::{Serialize, de::DeserializeOwned};

use super::core::bags::Attached;
use crate::rng::Pcg64;

pub use binned::BinnedRupture;
pub use hazard::Hazard;
pub use rate::{LinearRate, RuptureRate, TiltedRate};
pub use strong::StrongRupture;
pub use thin::thin;
pub use tree::TreeRupture;

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

/// Rupture rate of the candidate channel until the next restart, and how long it holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plan {
    pub rate: f64,
    pub horizon: f64,
}

/// How attached junctions rupture (docs/engines.md, "Adding a rupture model"). The core calls
/// it at fixed points of its event loop; the plate is seen only through the bounds and the
/// position the stepper gives.
pub trait RuptureModel: Clone + std::fmt::Debug + Serialize + DeserializeOwned + Send + 'static {
    /// `true` for force-dependent rates (weak bonds).
    const IS_WEAK: bool;
    /// A junction was attached into `slot` of `attached` with anchor `c`, the plate at `y`
    /// (the model may keep a handle in its record, [`Attached::bin`]). Returns `false` when
    /// its rate is beyond [`EXPONENT_CAP`] (it must rupture at once).
    fn attached(&mut self, attached: &mut [Attached], slot: usize, c: f64, y: f64) -> bool;
    /// The junction `a` was removed from `slot` by `swap_remove` (the one in the last slot
    /// `last` moved into it, unless `slot == last`).
    fn detached(&mut self, attached: &mut [Attached], slot: usize, last: usize, a: &Attached);
    /// The candidate rate from now on, for `n_att` attached junctions, and how long it holds;
    /// `bounds(h)` gives proven bounds `(y_lo, y_hi)` of the plate over the next `h`.
    fn plan(&mut self, bounds: impl FnMut(f64) -> (f64, f64), n_att: usize) -> Plan;
    /// Weak bonds thinned over a plate step: sets the bounds `y_lo <= y <= y_hi` and returns
    /// the total candidate rate under them (may be `+inf`).
    #[inline]
    fn bound(&mut self, _y_lo: f64, _y_hi: f64) -> f64 {
        0.0
    }
    /// A candidate now: the slot that ruptures, or `None` if rejected; `law` decides the
    /// acceptance from the plate position `y()` at the candidate's time.
    fn pick<L: RuptureRate>(
        &mut self,
        rng: &mut Pcg64,
        attached: &[Attached],
        law: &L,
        y: impl FnOnce() -> f64,
    ) -> Option<usize>;
    /// The coordinates were re-based: recompute everything from `attached`. Returns the
    /// slots whose rate is beyond [`EXPONENT_CAP`].
    fn rebuild(&mut self, _attached: &mut [Attached]) -> Vec<usize> {
        Vec::new()
    }
    /// Whether the frame must be re-based now: `a |y|` too large for the weights, or
    /// a thinning horizon too short to be resolved at the local time `tau`.
    #[inline]
    fn needs_rebase(&self, _y: f64, _tau: f64) -> bool {
        false
    }
    /// Prefetches the memory the next pick will touch.
    #[inline]
    fn prefetch(&self, _attached: &[Attached]) {}
}

/// What a candidate's weights `w = [w0, w1]` (`w0 >= exp(-a c)`, `w1 >= exp(a c)`) say of
/// `e^{a |y - c|}` for every plate position `y_lo <= y <= y_hi` (factors `e_hi = exp(a y_hi)`,
/// `e_lo = exp(-a y_lo)`): it lies between `max(w0 / e_lo, w1 / e_hi)` and
/// `max(e_hi w0, e_lo w1)`.
#[inline]
pub fn bracket(w: [f64; 2], e_hi: f64, e_lo: f64) -> (f64, f64) {
    ((w[0] / e_lo).max(w[1] / e_hi), (e_hi * w[0]).max(e_lo * w[1]))
}

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

/// Relative margins of the acceptance squeeze: `1 -+ 1e-9`.
const SQUEEZE_LO: f64 = 1.0 - 1e-9;
const SQUEEZE_HI: f64 = 1.0 + 1e-9;

/// The thinning test `U b < r` of a candidate with weights `w = [w0, w1]` (`w0 >= exp(-a c)`,
/// `w1 >= exp(a c)` up to round-off, `w0 w1 = 1` for the sum tree's exact weights) under the
/// factors `e_hi = exp(a y_hi)`, `e_lo = exp(-a y_lo)`, given `ub = U b`: `r = e^{a |y - c|}
/// = max(exp(a y) w0, w1 / exp(a y))` (units of `k0`, `ey()` giving `exp(a y)` at the
/// candidate's time). Squeezed first: with `y_lo <= y <= y_hi`, `r` lies between
/// `max(w0 / e_lo, w1 / e_hi)` and `max(e_hi w0, e_lo w1)`, and a uniform outside decides
/// without the plate's position and its exponential (the margins of [`squeeze`]
/// make both tests agree with the exact one). All factors stay finite: `|a y| <=
/// FRAME_EXPONENT_LIMIT` and `|a c| <= EXPONENT_CAP`.
#[inline]
pub fn accept(ub: f64, w: [f64; 2], e_hi: f64, e_lo: f64, ey: impl FnOnce() -> f64) -> bool {
    let (lo, hi) = bracket(w, e_hi, e_lo);
    match squeeze(ub, lo, hi) {
        Some(decided) => decided,
        None => {
            let ey = ey();
            ub < (ey * w[0]).max(w[1] / ey)
        }
    }
}
