//! Small rules every exact engine follows: when the frame is re-based ([`REBASE`]), the
//! extension of a re-formed junction ([`reattached_extension`]) and how an event is
//! reported ([`emit`]).

use super::bags::Detached;
use crate::observe::{EventKind, JunctionEvent, Observer};
use crate::scene::Reattach;

/// When an exact engine moves its local origin to the current time and position, so that
/// positions and times keep their digits on long runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RebasePolicy {
    /// Soft limits of `|y|` and `|tau|`: beyond them the origin is moved once enough events
    /// have passed since the last move to pay for its O(N) cost (a quarter of `N`).
    pub soft_y: f64,
    pub soft_tau: f64,
    /// Hard limits: beyond them the origin is moved whatever the cost.
    pub hard_y: f64,
    pub hard_tau: f64,
}

/// The re-base policy of every exact engine.
pub const REBASE: RebasePolicy =
    RebasePolicy { soft_y: 4096.0, soft_tau: 1048576.0, hard_y: 1.0737418e9, hard_tau: 4.2949673e9 };

impl RebasePolicy {
    /// Whether to re-base at local `(y, tau)`, `events` events after the last re-base of an
    /// engine of `n` junctions; `forced` is the engine's own reason (its rupture kinetics'
    /// weights about to overflow).
    ///
    /// Within the soft limits (almost always) only `forced` is read: the hard limits lie
    /// beyond the soft ones ([`REBASE`]; a policy whose hard limit is below its soft one
    /// is checked in full).
    #[inline]
    pub fn due(&self, y: f64, tau: f64, events: u64, n: usize, forced: bool) -> bool {
        let (ya, ta) = (y.abs(), tau.abs());
        let beyond_soft = ya > self.soft_y || ta > self.soft_tau;
        if !beyond_soft && self.hard_y >= self.soft_y && self.hard_tau >= self.soft_tau {
            return forced;
        }
        let hard = ya > self.hard_y || ta > self.hard_tau || forced;
        let soft = beyond_soft && events >= (n as u64 / 4).max(1);
        hard || soft
    }
}

/// The extension a detached junction `d` has when it forms at local time `tau`: its
/// residual extension relaxed at rate `lambda` since it ruptured, or 0
/// (`junctions.reattach`).
#[inline]
pub fn reattached_extension(reattach: Reattach, lambda: f64, d: &Detached, tau: f64) -> f64 {
    match reattach {
        Reattach::Residual => d.x * (-lambda * (tau - d.t)).exp(),
        Reattach::Unstretched => 0.0,
    }
}

/// Reports a junction event at absolute time `t` to `obs`, if it takes events of its kind
/// (formations only if [`Observer::FORMATIONS`]); `tension` is the law's `f(x)`, evaluated
/// only then.
#[inline]
pub fn emit<O: Observer>(obs: &mut O, t: f64, kind: EventKind, id: u32, x: f64, tension: impl FnOnce(f64) -> f64) {
    if O::EVENTS && (O::FORMATIONS || kind == EventKind::Rupture) {
        obs.event(&JunctionEvent { t, junction: id, kind, extension: x, tension: tension(x) });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hard limits re-base at once; soft limits once a quarter of `N` events have passed.
    #[test]
    fn rebase_policy() {
        let p = REBASE;
        assert!(!p.due(4000.0, 1e6, 0, 100, false));
        assert!(p.due(0.0, 0.0, 0, 100, true));
        assert!(p.due(2e9, 0.0, 0, 100, false));
        assert!(p.due(0.0, 5e9, 0, 100, false));
        assert!(!p.due(5000.0, 0.0, 24, 100, false));
        assert!(p.due(5000.0, 0.0, 25, 100, false));
        assert!(p.due(0.0, 2e6, 1, 1, false));
    }
}
