//! [`Exact`]: an exact engine, the [`Core`] composed with a [`Stepper`] and a
//! [`RuptureModel`], and the one event loop of every exact engine.

use serde::{Deserialize, Serialize};

use super::junctions::{after_event, form, horizon, maybe_rebase, rebase, refresh_clocks, rupture};
use super::state::{Core, FORMATION, HORIZON, RUPTURE};
use crate::engine::exact::rupture::{RuptureModel, stalled, thin};
use crate::engine::exact::stepper::contract::{Moved, Stepper, Target, WeakRuptures};
use crate::engine::{Counters, Engine, EngineError};
use crate::observe::{Observer, Sample};
use crate::scene::EngineKind;

/// An exact event-driven engine: the shared [`Core`], the plate stepper `S` of its method and
/// the rupture model `R` of its bonds.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct Exact<S: Stepper, R: RuptureModel> {
    pub(crate) core: Core<S::Queue>,
    pub(crate) stepper: S,
    pub(crate) rupture: R,
}

impl<S: Stepper, R: RuptureModel> Exact<S, R> {
    /// The engine from its core at `t = 0`, its stepper and its rupture model: the initial
    /// junctions registered with both (unstretched: no rate overflows), the first piece
    /// opened ([`Stepper::start`]) and every clock set.
    pub fn start(mut core: Core<S::Queue>, mut stepper: S, mut rupture: R) -> Self {
        for slot in 0..core.bags.n_attached() {
            let c = core.bags.attached[slot].c;
            stepper.attached(&mut core, slot, c);
            rupture.attached(&mut core.bags.attached, slot, c, 0.0);
        }
        stepper.start(&mut core);
        refresh_clocks(&mut core, &mut stepper, &mut rupture, None);
        Exact { core, stepper, rupture }
    }
}

impl<S: Stepper, R: RuptureModel> Engine for Exact<S, R> {
    const KIND: EngineKind = EngineKind::Exact;
    const WEAK_BONDS: bool = R::IS_WEAK;

    fn time(&self) -> f64 {
        self.core.time()
    }

    fn time_step(&self) -> Option<f64> {
        None
    }

    /// The event loop: the plate moves towards the first of the next candidate and the stop
    /// ([`Stepper::step`]; weak bonds thinned over a plate step by the model); a due candidate
    /// is thinned (formation: `g(|v|)`; rupture: the model's pick), and an accepted one closes
    /// the piece, changes the junctions and renews the clocks; at the stop, or the end of a
    /// thinning horizon, the piece is closed and a new one opened.
    fn advance<O: Observer>(&mut self, t_stop: f64, obs: &mut O) -> Result<(), EngineError> {
        let Exact { core, stepper: s, rupture: r } = self;
        s.begin(core, obs);
        loop {
            // In the local frame, which a re-basing inside this loop moves.
            let tau_stop = core.frame.local(t_stop).max(core.tau);
            let (ch, t_next) = core.channels.first();
            // A NaN time is never due (it would stop the loop, not spin it).
            let due = t_next <= tau_stop;
            let to = Target { tau: t_next.min(tau_stop), due, ch };
            let mut moved = s.step(core, to, obs)?;
            if let Moved::Stepped(step) = moved {
                let hit = if R::IS_WEAK {
                    let (mut cands, law, att) = (0, s.rate(), &core.bags.attached);
                    let (span, bounds) = ((step.s0, step.s1), (step.y_lo, step.y_hi));
                    let hit = thin(r, &mut core.rng, span, bounds, att, &law, |t| s.position(t), &mut cands)?;
                    let total = core.counters.candidates.get_or_insert(0);
                    *total += cands;
                    let (total, events) = (*total, core.counters.ruptures + core.counters.formations);
                    if stalled(total, events) {
                        let t = core.frame.time(step.s1);
                        return Err(EngineError::ThinningStalled { t, candidates: total, events });
                    }
                    hit
                } else {
                    None
                };
                moved = s.finish(core, &step, hit, r.upcoming(), to)?;
            }
            match moved {
                Moved::There | Moved::Stepped(_) => {}
                Moved::Short => continue,
                Moved::Rebase => {
                    let now = core.tau;
                    s.close(core, now, obs)?;
                    rebase(core, s, r, obs);
                    s.open_piece(core);
                    continue;
                }
                Moved::Ruptured(slot) => {
                    let now = core.tau;
                    s.close(core, now, obs)?;
                    rupture(core, s, r, slot, obs);
                    after_event(core, s, r, None, obs);
                    continue;
                }
            }
            if !due {
                s.close(core, tau_stop, obs)?;
                s.stopped(core, obs);
                maybe_rebase(core, s, r, obs);
                restart(core, s, r);
                return Ok(());
            }
            core.count_candidate();
            match ch {
                FORMATION => {
                    if s.formation(core, t_next, obs)? {
                        let c = form(core, s, r, obs);
                        after_event(core, s, r, Some((FORMATION, c)), obs);
                    } else {
                        core.channels.redraw(FORMATION, t_next, &mut core.rng);
                    }
                }
                HORIZON if horizon::<S, R>() => {
                    // End of a thinning horizon: restart the piece, renew the bound.
                    s.close(core, t_next, obs)?;
                    maybe_rebase(core, s, r, obs);
                    restart(core, s, r);
                }
                _ => {
                    let law = s.rate();
                    match r.pick(&mut core.rng, &core.bags.attached, &law, || s.position(t_next).unwrap_or(f64::NAN)) {
                        Some(slot) => {
                            s.close(core, t_next, obs)?;
                            let c = rupture(core, s, r, slot, obs);
                            after_event(core, s, r, Some((RUPTURE, c)), obs);
                        }
                        None => core.channels.redraw(RUPTURE, t_next, &mut core.rng),
                    }
                }
            }
        }
    }

    fn sample(&self) -> Sample {
        let (core, s) = (&self.core, &self.stepper);
        let y = s.y(core);
        let bond_force = s.bond_force(core);
        Sample {
            t: core.time(),
            x: core.frame.position(y),
            v: s.velocity(core),
            friction: if S::KINEMATIC { bond_force } else { -core.plate.k * s.lag(core) },
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

/// A new piece where no event happened (a stop, the end of a horizon); a closed-form piece
/// renews its rupture bound and clocks over it.
#[inline]
fn restart<S: Stepper, R: RuptureModel>(core: &mut Core<S::Queue>, s: &mut S, r: &mut R) {
    s.open_piece(core);
    if matches!(S::WEAK_RUPTURES, WeakRuptures::Horizon) {
        refresh_clocks(core, s, r, None);
    }
}
