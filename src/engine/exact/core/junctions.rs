//! The junction bookkeeping of every exact engine, written once over its [`Stepper`] and
//! [`RuptureModel`]: rupture and formation (with re-attachment and event emission), the
//! frame's re-base, and what follows an event (counters, re-base, a new piece, the clocks
//! renewed).

use super::policy::{REBASE, emit, reattached_extension};
use super::state::{Core, HORIZON};
use crate::engine::exact::core::bags::{Detached, count};
use crate::engine::exact::rupture::RuptureModel;
use crate::engine::exact::stepper::contract::{Stepper, WeakRuptures};
use crate::observe::{EventKind, Observer};

/// Ruptures the attached junction in `slot` now; its anchor.
#[inline(always)]
pub fn rupture<S: Stepper, R: RuptureModel, O: Observer>(
    core: &mut Core<S::Queue>,
    s: &mut S,
    r: &mut R,
    slot: usize,
    obs: &mut O,
) -> f64 {
    let last = core.bags.n_attached() - 1;
    let a = core.bags.take_attached(slot);
    s.detached(core, slot, last, &a);
    r.detached(&mut core.bags.attached, slot, last, &a);
    let x = s.y(core) - a.c;
    core.bags.detached.push(Detached { x, t: core.tau, id: a.id });
    core.counters.ruptures += 1;
    emit(obs, core.time(), EventKind::Rupture, a.id, x, |x| s.tension(x));
    a.c
}

/// Attaches a detached junction ([`Stepper::formation_slot`]) now, with its re-attached
/// extension; if its rupture rate overflows (weak bonds), it ruptures at once. A model that
/// needs it re-bases first ([`RuptureModel::needs_rebase`]: with no junction attached the
/// plate may have moved far since the last re-base, and the new anchor's weights must be
/// representable). Its anchor.
#[inline]
pub fn form<S: Stepper, R: RuptureModel, O: Observer>(
    core: &mut Core<S::Queue>,
    s: &mut S,
    r: &mut R,
    obs: &mut O,
) -> f64 {
    if r.needs_rebase(s.y(core), core.tau) {
        rebase(core, s, r, obs);
    }
    let slot = s.formation_slot(&mut core.rng, core.bags.n_detached());
    let d = core.bags.take_detached(slot);
    let x = reattached_extension(core.reattach, core.lambda, &d, core.tau);
    let y = s.y(core);
    let c = y - x;
    core.bags.attach_in_bin(c, d.id, 0);
    core.counters.formations += 1;
    emit(obs, core.time(), EventKind::Formation, d.id, x, |x| s.tension(x));
    let slot = core.bags.n_attached() - 1;
    s.attached(core, slot, c);
    if !r.attached(&mut core.bags.attached, slot, c, y) {
        rupture(core, s, r, slot, obs);
    }
    c
}

/// Re-bases the frame if positions or times have grown ([`REBASE`]; amortised O(1) per event).
/// Always inlined: the test runs after every event, the re-base itself is a call.
#[inline(always)]
pub fn maybe_rebase<S: Stepper, R: RuptureModel, O: Observer>(
    core: &mut Core<S::Queue>,
    s: &mut S,
    r: &mut R,
    obs: &mut O,
) {
    let y = s.y(core);
    if REBASE.due(y, core.tau, core.events_since_rebase, core.n, r.needs_rebase(y, core.tau)) {
        rebase(core, s, r, obs);
    }
}

/// Moves the local origin to the current time and position (at a piece boundary). The
/// junctions whose rate overflows in the new frame rupture at once (highest slot first, so
/// `swap_remove` does not disturb the slots still to do). Rare (amortised over a quarter
/// of `N` events): kept out of the event loop's code.
#[cold]
#[inline(never)]
pub fn rebase<S: Stepper, R: RuptureModel, O: Observer>(core: &mut Core<S::Queue>, s: &mut S, r: &mut R, obs: &mut O) {
    let (dtau, dy) = (core.tau, s.y(core));
    core.shift(dtau, dy);
    s.shifted(core, dtau, dy);
    let mut over = r.rebuild(&mut core.bags.attached);
    // `sort_unstable` on `usize` is compiled once, not once per engine type.
    over.sort_unstable();
    for slot in over.into_iter().rev() {
        rupture(core, s, r, slot, obs);
    }
}

/// After an event at the current time (`fired`: the channel that fired, if one did, and the
/// anchor of the junction its event attached or detached): re-base, a new piece, new rates. Always inlined: it runs after every event,
/// its call cost a twentieth of one, and inlined `fired` is a constant.
#[inline(always)]
pub fn after_event<S: Stepper, R: RuptureModel, O: Observer>(
    core: &mut Core<S::Queue>,
    s: &mut S,
    r: &mut R,
    fired: Option<(usize, f64)>,
    obs: &mut O,
) {
    core.events_since_rebase += 1;
    maybe_rebase(core, s, r, obs);
    s.open_piece(core);
    refresh_clocks(core, s, r, fired);
    s.prefetch(core);
    r.prefetch(&core.bags.attached);
}

/// Whether the rupture channel carries candidates over a thinning horizon (weak bonds on a
/// closed-form plate).
#[inline(always)]
pub const fn horizon<S: Stepper, R: RuptureModel>() -> bool {
    R::IS_WEAK && matches!(S::WEAK_RUPTURES, WeakRuptures::Horizon)
}

/// Sets every channel's rate after a change of state (formation `kon0 N_det`, times the
/// stepper's acceptance; rupture and horizon from the model's [`RuptureModel::plan`] over the
/// stepper's bounds, or after an event the current horizon's plan kept
/// ([`RuptureModel::replan`]); none for weak bonds found inside plate steps); channel `fired`
/// draws afresh (with the anchor of the junction its event attached or detached). Always inlined (it runs after every event).
#[inline(always)]
pub fn refresh_clocks<S: Stepper, R: RuptureModel>(
    core: &mut Core<S::Queue>,
    s: &mut S,
    r: &mut R,
    fired: Option<(usize, f64)>,
) {
    let now = core.tau;
    // After an event inside a thinning horizon, its plan is kept while its bounds hold for
    // the plate's new path: the old path's widened by the event's reach.
    let kept = match fired {
        Some((_, c)) if horizon::<S, R>() => {
            let rest = core.channels.time(HORIZON) - now;
            r.replan(|lo, hi| s.reach(c, rest, lo, hi), core.bags.n_attached())
        }
        _ => None,
    };
    // The rupture rate, and the horizon's new end when it was planned anew.
    let (rate, end) = match kept {
        Some(rate) => (rate, None),
        None if R::IS_WEAK && !horizon::<S, R>() => (0.0, None),
        None => {
            let plan = r.plan(|h| s.bounds(core, h), core.bags.n_attached());
            (plan.rate, horizon::<S, R>().then_some(now + plan.horizon))
        }
    };
    let formation_rate = core.formation.kon0 * s.formation_acceptance(core) * count(core.bags.n_detached());
    core.channels.set_rates(now, [formation_rate, rate], fired.map(|(ch, _)| ch), &mut core.rng);
    if let Some(end) = end {
        core.channels.set_time(HORIZON, end);
    }
}
