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
//!   from each step of a stepped plate ([`thin()`]). The tree draws the junction from a sum
//!   tree of the weights (`sumtree`); the bins a uniform member of a bin of anchors.
//! - [`Hazard`] (`hazard`): weak bonds whose stepper integrates the total rupture rate and
//!   finds the ruptures itself (the direct stepper).
//!
//! The acceptance `r_i / b_i` is first squeezed between bounds read from the junction's
//! weights ([`accept::squeeze`]), which decides most candidates without the plate's
//! position or an exponential.

pub mod accept;
pub mod binned;
pub mod contract;
pub mod hazard;
pub mod horizon;
pub mod rate;
pub mod strong;
pub mod sumtree;
pub mod thin;
pub mod tree;

pub use accept::{EXPONENT_CAP, FRAME_EXPONENT_LIMIT, accept, anchor_overflows, bracket, overflows, squeeze};
pub use binned::BinnedRupture;
pub use contract::{Plan, RuptureModel};
pub use hazard::Hazard;
pub use rate::{LinearRate, RuptureRate, TiltedRate};
pub use strong::StrongRupture;
pub use thin::{stalled, thin};
pub use tree::TreeRupture;
