//! The junction bookkeeping of every exact engine, written once over its [`Kernel`]:
//! rupture and formation (with re-attachment and event emission), the frame's re-base, and
//! what follows an event (counters, re-base, a new piece, the clocks renewed).

use super::{Core, HORIZON, Kernel, REBASE, emit, reattached_extension};
use crate::engine::exact::core::bags::{Detached, count};
use crate::observe::{EventKind, Observer};

/// Ruptures the attached junction in `slot` now.
#[inline]
pub fn rupture<K: Kernel, O: Observer>(core: &mut Core<K::Queue>, k: &mut K, slot: usize, obs: &mut O) {
    let last = core.bags.n_attached() - 1;
    let a = core.bags.take_attached(slot);
    k.detached(core, slot, last, &a);
    let x = k.y(core) - a.c;
    core.bags.detached.push(Detached { x, t: core.tau, id: a.id });
    core.counters.ruptures += 1;
    emit(obs, core.time(), EventKind::Rupture, a.id, x, |x| k.tension(x));
}

/// Attaches a detached junction ([`Kernel::formation_slot`]) now, with its re-attached
/// extension; if its rupture rate overflows (weak bonds), it ruptures at once. A kernel that
/// needs it re-bases first ([`Kernel::forced_rebase`]: with no junction attached the plate
/// may have moved far since the last re-base, and the new anchor's weights must be
/// representable).
#[inline]
pub fn form<K: Kernel, O: Observer>(core: &mut Core<K::Queue>, k: &mut K, obs: &mut O) {
    if k.forced_rebase(core) {
        rebase(core, k, obs);
    }
    let slot = k.formation_slot(&mut core.rng, core.bags.n_detached());
    let d = core.bags.take_detached(slot);
    let x = reattached_extension(core.reattach, core.lambda, &d, core.tau);
    let y = k.y(core);
    let c = y - x;
    let bin = k.bin(core, c);
    core.bags.attach_in_bin(c, d.id, bin);
    core.counters.formations += 1;
    emit(obs, core.time(), EventKind::Formation, d.id, x, |x| k.tension(x));
    let slot = core.bags.n_attached() - 1;
    if !k.attached(core, slot, c, x, y) {
        rupture(core, k, slot, obs);
    }
}

/// Re-bases the frame if positions or times have grown ([`REBASE`]; amortised O(1) per event).
/// Always inlined: the test runs after every event, the re-base itself is a call.
#[inline(always)]
pub fn maybe_rebase<K: Kernel, O: Observer>(core: &mut Core<K::Queue>, k: &mut K, obs: &mut O) {
    let y = k.y(core);
    if REBASE.due(y, core.tau, core.events_since_rebase, core.n, k.forced_rebase(core)) {
        rebase(core, k, obs);
    }
}

/// Moves the local origin to the current time and position (at a piece boundary). The
/// junctions whose rate overflows in the new frame rupture at once (highest slot first, so
/// `swap_remove` does not disturb the slots still to do). Rare (amortised over a quarter
/// of `N` events): kept out of the event loop's code.
#[cold]
#[inline(never)]
pub fn rebase<K: Kernel, O: Observer>(core: &mut Core<K::Queue>, k: &mut K, obs: &mut O) {
    let (dtau, dy) = (core.tau, k.y(core));
    core.shift(dtau, dy);
    k.shifted(core, dtau, dy);
    let mut over = k.rebuild(&mut core.bags.attached);
    over.sort_unstable_by(|a, b| b.cmp(a));
    for slot in over {
        rupture(core, k, slot, obs);
    }
}

/// After an event at the current time (`fired`: the channel that fired, if one did):
/// re-base, a new piece, new rates. Always inlined: it runs after every event,
/// its call cost a twentieth of one, and inlined `fired` is a constant.
#[inline(always)]
pub fn after_event<K: Kernel, O: Observer>(core: &mut Core<K::Queue>, k: &mut K, fired: Option<usize>, obs: &mut O) {
    core.events_since_rebase += 1;
    maybe_rebase(core, k, obs);
    k.open_piece(core);
    refresh_clocks(core, k, fired);
    k.prefetch(core);
}

/// Sets every channel's rate after a change of state (formation `kon0 N_det`, times the
/// kernel's acceptance; rupture and horizon from [`Kernel::rupture_plan`]); channel `fired`
/// draws afresh. Always inlined (it runs after every event).
#[inline(always)]
pub fn refresh_clocks<K: Kernel>(core: &mut Core<K::Queue>, k: &mut K, fired: Option<usize>) {
    let now = core.tau;
    let (rupture_rate, horizon_end) = k.rupture_plan(core);
    let formation_rate = core.formation.kon0 * k.formation_acceptance(core) * count(core.bags.n_detached());
    core.channels.set_rates(now, [formation_rate, rupture_rate], fired, &mut core.rng);
    if K::HORIZON {
        core.channels.set_time(HORIZON, horizon_end);
    }
}
