//! The rupture-model contract: [`RuptureModel`], and the candidate channel's [`Plan`].

use serde::{Serialize, de::DeserializeOwned};

use super::rate::RuptureRate;
use crate::engine::exact::core::bags::Attached;
use crate::rng::Pcg64;

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
    /// its rate is beyond [`EXPONENT_CAP`](super::accept::EXPONENT_CAP) (it must rupture at once).
    fn attached(&mut self, attached: &mut [Attached], slot: usize, c: f64, y: f64) -> bool;
    /// The junction `a` was removed from `slot` by `swap_remove` (the one in the last slot
    /// `last` moved into it, unless `slot == last`).
    fn detached(&mut self, attached: &mut [Attached], slot: usize, last: usize, a: &Attached);
    /// The candidate rate from now on, for `n_att` attached junctions, and how long it holds;
    /// `bounds(h)` gives proven bounds `(y_lo, y_hi)` of the plate over the next `h`.
    fn plan(&mut self, bounds: impl FnMut(f64) -> (f64, f64), n_att: usize) -> Plan;
    /// After an event inside the current horizon: the candidate rate until the horizon's
    /// end for the `n_att` junctions attached now, if the plan's bounds still hold for the
    /// plate's new path, which `reach(y_lo, y_hi)` bounds in distance from a path within
    /// `[y_lo, y_hi]` (the plan's bounds as widened so far, [`Horizon::widen`]); `None`
    /// (the default): plan anew.
    ///
    /// [`Horizon::widen`]: super::horizon::Horizon::widen
    #[inline]
    fn replan(&mut self, _reach: impl FnOnce(f64, f64) -> f64, _n_att: usize) -> Option<f64> {
        None
    }
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
    /// slots whose rate is beyond [`EXPONENT_CAP`](super::accept::EXPONENT_CAP).
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
    /// The slot a later candidate is likely to pick, as far as the model knows it ahead
    /// (`usize::MAX`: not known): a hint for prefetching what a stepper keeps by slot.
    #[inline]
    fn upcoming(&self) -> usize {
        usize::MAX
    }
}
