//! [`Exact`]: an exact engine, the [`Core`] plus a [`Kernel`], and the one event loop of
//! every exact engine.

use serde::{Deserialize, Serialize};

use super::junctions::{after_event, form, maybe_rebase, refresh_clocks, rupture};
use super::{Core, FORMATION, HORIZON, Kernel, Moved, RUPTURE, Target};
use crate::engine::{Counters, Engine, EngineError};
use crate::observe::{Observer, Sample};
use crate::scene::EngineKind;

/// An exact event-driven engine: the shared [`Core`] and the kernel `K` of its method.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct Exact<K: Kernel> {
    pub(crate) core: Core<K::Queue>,
    pub(crate) kernel: K,
}

impl<K: Kernel> Exact<K> {
    /// The engine from its core at `t = 0` and its kernel: the first piece opened
    /// ([`Kernel::start`]) and every clock set.
    pub fn start(mut core: Core<K::Queue>, mut kernel: K) -> Self {
        kernel.start(&mut core);
        refresh_clocks(&mut core, &mut kernel, None);
        Exact { core, kernel }
    }
}

impl<K: Kernel> Engine for Exact<K> {
    const KIND: EngineKind = EngineKind::Exact;
    const WEAK_BONDS: bool = K::IS_WEAK;

    fn time(&self) -> f64 {
        self.core.time()
    }

    fn time_step(&self) -> Option<f64> {
        None
    }

    /// The event loop: the plate moves towards the first of the next candidate and the stop
    /// ([`Kernel::step`]); a due candidate is thinned (formation: `g(|v|)`; rupture: the
    /// kernel's pick), and an accepted one closes the piece, changes the junctions and
    /// renews the clocks; at the stop the piece is closed and a new one opened.
    fn advance<O: Observer>(&mut self, t_stop: f64, obs: &mut O) -> Result<(), EngineError> {
        let Exact { core, kernel: k } = self;
        loop {
            // In the local frame, which a re-basing inside this loop moves.
            let tau_stop = core.frame.local(t_stop).max(core.tau);
            let (ch, t_next) = core.channels.first();
            // A NaN time is never due (it would stop the loop, not spin it).
            let due = t_next <= tau_stop;
            match k.step(core, Target { tau: t_next.min(tau_stop), due, ch }, obs)? {
                Moved::There => {}
                Moved::Short => continue,
                Moved::Ruptured(slot) => {
                    let now = core.tau;
                    k.close(core, now, obs)?;
                    rupture(core, k, slot, obs);
                    after_event(core, k, None, obs);
                    continue;
                }
            }
            if !due {
                k.close(core, tau_stop, obs)?;
                k.stopped(core, obs);
                maybe_rebase(core, k, obs);
                k.restart(core);
                return Ok(());
            }
            core.count_candidate();
            match ch {
                FORMATION => {
                    if k.formation(core, t_next, obs)? {
                        form(core, k, obs);
                        after_event(core, k, Some(FORMATION), obs);
                    } else {
                        core.channels.redraw(FORMATION, t_next, &mut core.rng);
                    }
                }
                HORIZON if K::HORIZON => {
                    // End of a thinning horizon: restart the piece, renew the bound.
                    k.close(core, t_next, obs)?;
                    maybe_rebase(core, k, obs);
                    k.restart(core);
                }
                _ => match k.pick_rupture(core, t_next) {
                    Some(slot) => {
                        k.close(core, t_next, obs)?;
                        rupture(core, k, slot, obs);
                        after_event(core, k, Some(RUPTURE), obs);
                    }
                    None => core.channels.redraw(RUPTURE, t_next, &mut core.rng),
                },
            }
        }
    }

    fn sample(&self) -> Sample {
        let (core, k) = (&self.core, &self.kernel);
        let y = k.y(core);
        let bond_force = k.bond_force(core);
        Sample {
            t: core.time(),
            x: core.frame.position(y),
            v: k.velocity(core),
            friction: if K::KINEMATIC { bond_force } else { -core.plate.k * k.lag(core) },
            bond_force,
            attached: core.bags.n_attached() as u64,
            n: core.n as u64,
        }
    }

    /// The core's counters, with `events` the ruptures and formations so far (summed here,
    /// not after every event).
    fn counters(&self) -> Counters {
        let c = &self.core.counters;
        Counters { events: Some(c.ruptures + c.formations), ..c.clone() }
    }
}
