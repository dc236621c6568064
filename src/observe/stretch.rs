//! [`Stretch`]: consecutive pieces of a trajectory summed by the engine that made them, and
//! reported once per advance ([`super::Observer::stretch`]) in place of one report per piece.
//!
//! The friction's integrals are the [`ShiftedSums`] of the pieces (about the friction at the
//! stretch's start); the bond and viscous forces' integrals follow from the plate equation
//! `M X'' + eta X' = F - F_b` over the whole stretch (no sum per piece):
//!
//! ```text
//!     int eta X' dt = eta (X1 - X0),        int F_b dt = int F dt - eta (X1 - X0) - M (X1' - X0'),
//! ```
//!
//! with `X0, X0'` and `X1, X1'` the plate's state at the stretch's start and end.

use super::shifted::ShiftedSums;

/// The time integrals of the observables over the pieces `[t0, t1]` an engine summed (the
/// pieces tile it).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stretch {
    /// Absolute start and end times (`t0 = t1` and `friction.weight = 0` for an empty
    /// stretch: nothing summed, only the time reached).
    pub t0: f64,
    pub t1: f64,
    /// The friction's shifted sums (`weight` the time covered).
    pub friction: ShiftedSums,
    /// `int F_b dt`.
    pub bond: f64,
    /// `int eta X' dt`.
    pub viscous: f64,
    /// `int N_att dt`.
    pub attached: f64,
    /// `int (N - N_att) dt`.
    pub detached: f64,
}
