//! The direct exact engine, for any force law (the O(N) reference for the tilted law,
//! `exact.tilted = "direct"`, and the engine of every law whose `ForceLaw::Exact` is `Direct`).
//!
//! The bond force `F_b(y) = sum_att f^x(y - c_i)` is in general nonlinear in the plate position, so
//! between events the plate is integrated by the adaptive DOP853 method ([`crate::ode`])
//! to the scene's tolerance (`exact.rtol`, `exact.atol`): **this is the engine's one
//! approximation**. The integrated state carries, besides the plate, the quadratures the
//! statistics need and, for weak bonds, the cumulative rupture hazard:
//!
//! - `L  = int (lag - lag0) ds`, `L2 = int (lag - lag0)^2 ds`, `B = int F_b ds` over the
//!   current piece (`lag = X - V t`, `lag0` its value at the piece's start);
//! - weak bonds: `H = int sum_i k0 exp(beta dx f_i) ds`. The next rupture happens when `H`
//!   reaches a unit exponential `E` drawn after the previous event (random time change of
//!   the total rate; exact up to the integrator's tolerance), located on the dense output;
//!   the junction is chosen with probability `r_i / sum r` at that instant.
//!
//! Formation candidates (rate `kon0 N_det`, accepted with `g(|Xd|)`) and strong-bond
//! ruptures (rate `k0 N_att`) come from channel clocks as in the linear engine; the
//! integrator never steps past the next candidate. Cost: O(N_att) per right-hand-side
//! evaluation.

use rand::RngExt;
use rand_distr::{Distribution, Exp1};
use serde::{Deserialize, Serialize};

use super::bags::{Bags, Detached};
use super::clocks::{ArrayQueue, Channels};
use super::core::{REBASE, emit, reattached_extension};
use super::frame::Frame;
use crate::engine::{Counters, Engine, EngineError};
use crate::observe::{EventKind, Observer, Sample, Segment};
use crate::ode::{Dop853, Dop853Config, OdeError, OdeSystem};
use crate::physics::{Bond, ForceLaw, Formation, Plate};
use crate::rng::{Pcg64, UniformSource, pcg};
use crate::scene::{EngineKind, Reattach, Scene};

/// Index of the plate's local position `y` in the integrated state (the linear engine's `y`).
const Y: usize = 0;
const FORMATION: usize = 0;
const RUPTURE: usize = 1;

/// Where each quantity sits in the integrated state.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct Layout {
    /// Velocity index (`None` for the overdamped plate, whose velocity follows the forces).
    vel: Option<usize>,
    l: usize,
    l2: usize,
    b: usize,
    /// Cumulative rupture hazard (weak bonds).
    h: Option<usize>,
    dim: usize,
}

impl Layout {
    fn new(overdamped: bool, weak: bool) -> Layout {
        let vel = (!overdamped).then_some(1);
        let l = if overdamped { 1 } else { 2 };
        let h = weak.then_some(l + 3);
        Layout { vel, l, l2: l + 1, b: l + 2, h, dim: l + 3 + weak as usize }
    }
}

/// The right-hand side: plate, quadratures, hazard.
struct System<'a, L: ForceLaw, B: Bond> {
    attached: &'a [super::bags::Attached],
    p: Params<L, B>,
}

/// Everything the right-hand side needs besides the attached junctions.
#[derive(Clone, Copy)]
struct Params<L: ForceLaw, B: Bond> {
    law: L,
    bond: B,
    plate: Plate,
    frame: Frame,
    lag0: f64,
    layout: Layout,
    /// `k0 e^EXPONENT_CAP`: rates are capped here so the hazard stays finite.
    rate_cap: f64,
}

impl<L: ForceLaw, B: Bond> std::ops::Deref for System<'_, L, B> {
    type Target = Params<L, B>;
    fn deref(&self) -> &Params<L, B> {
        &self.p
    }
}

impl<L: ForceLaw, B: Bond> System<'_, L, B> {
    /// `(F_b, total rupture rate)` at local position `y`. Rates are capped at
    /// `k0 e^EXPONENT_CAP` so the hazard stays finite.
    #[inline]
    fn forces(&self, y: f64) -> (f64, f64) {
        let (mut fb, mut rate) = (0.0, 0.0);
        for a in self.attached {
            let (f, fx) = self.law.tension_and_force_x(y - a.c);
            fb += fx;
            if B::IS_WEAK {
                rate += self.bond.k_off(f).min(self.rate_cap);
            }
        }
        (fb, rate)
    }
    /// Plate velocity of the overdamped plate, `-(F_b + K lag)/eta`.
    #[inline]
    fn overdamped_velocity(&self, fb: f64, lag: f64) -> f64 {
        self.plate.overdamped_velocity(lag, fb)
    }
}

/// `e^EXPONENT_CAP`: rate cap relative to `k0`.
const CAP_RATE_FACTOR: f64 = 3.7730203009299397e260;

impl<L: ForceLaw, B: Bond> OdeSystem for System<'_, L, B> {
    fn rhs(&mut self, tau: f64, s: &[f64], d: &mut [f64]) {
        let y = s[Y];
        let (fb, rate) = self.forces(y);
        let lag = self.frame.lag(y, tau);
        match self.layout.vel {
            Some(iv) => {
                d[Y] = s[iv];
                d[iv] = self.plate.acceleration(lag, s[iv], fb);
            }
            None => d[Y] = self.overdamped_velocity(fb, lag),
        }
        let dl = lag - self.lag0;
        d[self.layout.l] = dl;
        d[self.layout.l2] = dl * dl;
        d[self.layout.b] = fb;
        if let Some(ih) = self.layout.h {
            d[ih] = rate;
        }
    }
}

/// Exact event-driven engine for any force law `L` with bond kind `B`: `F_b` summed directly.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct ExactDirect<L: ForceLaw, B: Bond> {
    n: usize,
    plate: Plate,
    law: L,
    bond: B,
    lambda: f64,
    reattach: Reattach,
    formation: Formation,
    frame: Frame,
    layout: Layout,
    /// Local time and integrated state at it.
    tau: f64,
    state: Vec<f64>,
    /// Start of the current piece.
    tau0: f64,
    y0: f64,
    lag0: f64,
    /// Weak bonds: the hazard level of the next rupture.
    hazard_target: f64,
    bags: Bags,
    ode: Dop853,
    channels: Channels<ArrayQueue>,
    rng: Pcg64,
    counters: Counters,
    events_since_rebase: u64,
}

impl<L: ForceLaw, B: Bond> ExactDirect<L, B> {
    /// The engine for `scene` with the law and bond kind given (built by `scene::laws` for
    /// a scene's own; any [`ForceLaw`] works).
    pub fn new(scene: &Scene, law: L, bond: B) -> Result<Self, EngineError> {
        let j = &scene.junctions;
        let mut rng = pcg(scene.run.seed);
        let bags = Bags::initial(j, &mut rng)?;
        let plate = Plate::from_scene(scene);
        let layout = Layout::new(plate.mass == 0.0, B::IS_WEAK);
        let cfg = Dop853Config {
            rtol: scene.exact.rtol,
            atol: scene.exact.atol,
            h_max: step_cap(&plate, law, j.n),
            ..Dop853Config::default()
        };
        let ode = Dop853::with_config(layout.dim, cfg).map_err(|e| ode_error(e, 0.0, scene.exact.rtol))?;
        let mut e = ExactDirect {
            n: j.n,
            plate,
            law,
            bond,
            lambda: j.lambda,
            reattach: j.reattach,
            formation: Formation::from_scene(scene),
            frame: Frame::new(plate.v),
            layout,
            tau: 0.0,
            state: vec![0.0; layout.dim],
            tau0: 0.0,
            y0: 0.0,
            lag0: 0.0,
            hazard_target: 0.0,
            bags,
            ode,
            channels: Channels::new(2),
            rng,
            counters: Counters {
                events: Some(0),
                candidates: Some(0),
                rebases: Some(0),
                ode_steps: Some(0),
                ode_rejected: Some(0),
                ..Default::default()
            },
            events_since_rebase: 0,
        };
        e.open_piece();
        e.refresh_clocks(None);
        Ok(e)
    }

    fn system(&self) -> System<'_, L, B> {
        System { attached: &self.bags.attached, p: self.params() }
    }

    fn params(&self) -> Params<L, B> {
        Params {
            law: self.law,
            bond: self.bond,
            plate: self.plate,
            frame: self.frame,
            lag0: self.lag0,
            layout: self.layout,
            rate_cap: self.rate_cap(),
        }
    }

    fn rate_cap(&self) -> f64 {
        CAP_RATE_FACTOR * self.bond.k_off(0.0)
    }

    /// Plate velocity in state `s` at local time `tau`.
    fn velocity(&self, tau: f64, s: &[f64]) -> f64 {
        match self.layout.vel {
            Some(iv) => s[iv],
            None => {
                let sys = self.system();
                let fb = sys.forces(s[Y]).0;
                sys.overdamped_velocity(fb, self.frame.lag(s[Y], tau))
            }
        }
    }

    /// Starts a new piece at the current state: quadratures to zero, a fresh hazard level
    /// (weak bonds), and the integrator told the right-hand side has changed.
    fn open_piece(&mut self) {
        let l = self.layout;
        self.state[l.l] = 0.0;
        self.state[l.l2] = 0.0;
        self.state[l.b] = 0.0;
        self.tau0 = self.tau;
        self.y0 = self.state[Y];
        self.lag0 = self.frame.lag(self.y0, self.tau);
        if let Some(ih) = l.h {
            self.state[ih] = 0.0;
            self.hazard_target = Exp1.sample(&mut self.rng);
        }
        self.ode.reset();
    }

    /// Reports the piece up to the current time as a segment.
    fn close_piece<O: Observer>(&mut self, obs: &mut O) {
        let h = self.tau - self.tau0;
        if h <= 0.0 {
            return;
        }
        let l = self.layout;
        let s = &self.state;
        let (li, l2) = (s[l.l], s[l.l2]);
        let k = self.plate.k;
        obs.segment(&Segment {
            t0: self.frame.time(self.tau0),
            t1: self.frame.time(self.tau),
            friction: -k * (self.lag0 + li / h),
            friction_m2: k * k * (l2 - li * li / h).max(0.0),
            bond_force: s[l.b] / h,
            viscous: self.plate.eta * (s[Y] - self.y0) / h,
            attached: self.bags.n_attached() as u64,
        });
    }

    fn refresh_clocks(&mut self, fired: Option<usize>) {
        let strong_rate = if B::IS_WEAK { 0.0 } else { self.bond.k_off(0.0) * self.bags.n_attached() as f64 };
        let rates = [self.formation.kon0 * self.bags.n_detached() as f64, strong_rate];
        self.channels.set_rates(self.tau, rates, fired, &mut self.rng);
    }

    #[inline]
    fn emit<O: Observer>(&self, obs: &mut O, kind: EventKind, id: u32, x: f64) {
        emit(obs, self.frame.time(self.tau), kind, id, x, |x| self.law.tension(x));
    }

    fn rupture_slot<O: Observer>(&mut self, slot: usize, obs: &mut O) {
        let a = self.bags.take_attached(slot);
        let x = self.state[Y] - a.c;
        self.bags.detached.push(Detached { x, t: self.tau, id: a.id });
        self.counters.ruptures += 1;
        self.emit(obs, EventKind::Rupture, a.id, x);
    }

    /// Whether a junction at extension `x` has an overflowing rupture rate.
    fn overflows(&self, x: f64) -> bool {
        B::IS_WEAK && self.bond.k_off(self.law.tension(x)) > self.rate_cap()
    }

    fn form_one<O: Observer>(&mut self, obs: &mut O) {
        let slot = self.rng.random_range(0..self.bags.n_detached());
        let d = self.bags.take_detached(slot);
        let x = reattached_extension(self.reattach, self.lambda, &d, self.tau);
        self.bags.attach(self.state[Y] - x, d.id);
        self.counters.formations += 1;
        self.emit(obs, EventKind::Formation, d.id, x);
        if self.overflows(x) {
            let last = self.bags.n_attached() - 1;
            self.rupture_slot(last, obs);
        }
    }

    /// Weak bonds: the junction that ruptures now, chosen with probability `r_i / sum r`.
    fn pick_weak(&mut self) -> usize {
        let y = self.state[Y];
        let cap = self.rate_cap();
        let rate = |c: f64| self.bond.k_off(self.law.tension(y - c)).min(cap);
        let total: f64 = self.bags.attached.iter().map(|a| rate(a.c)).sum();
        let mut u = self.rng.uniform() * total;
        let last = self.bags.n_attached() - 1;
        for (slot, a) in self.bags.attached.iter().enumerate() {
            let r = rate(a.c);
            if u < r {
                return slot;
            }
            u -= r;
        }
        last
    }

    fn maybe_rebase<O: Observer>(&mut self, obs: &mut O) {
        if !REBASE.due(self.state[Y], self.tau, self.events_since_rebase, self.n, false) {
            return;
        }
        self.rebase();
        let _ = obs;
    }

    /// Moves the local origin to the current time and position. Only at the boundary of a
    /// piece: the caller closes the piece before and opens a new one after.
    fn rebase(&mut self) {
        let (dtau, dy) = (self.tau, self.state[Y]);
        self.frame.shift(dtau, dy);
        self.bags.rebase(dtau, dy);
        self.channels.shift(dtau);
        self.tau = 0.0;
        self.state[Y] = 0.0;
        self.events_since_rebase = 0;
        *self.counters.rebases.as_mut().expect("set") += 1;
    }

    fn after_event<O: Observer>(&mut self, fired: Option<usize>, obs: &mut O) {
        self.events_since_rebase += 1;
        *self.counters.events.as_mut().expect("set") = self.counters.ruptures + self.counters.formations;
        self.maybe_rebase(obs);
        self.open_piece();
        self.refresh_clocks(fired);
    }

    fn sync_ode_counters(&mut self) {
        let st = self.ode.stats();
        self.counters.ode_steps = Some(st.accepted);
        self.counters.ode_rejected = Some(st.rejected);
    }

    /// Moves the current state to `tau` inside the last accepted step (dense output).
    fn seek(&mut self, tau: f64) -> Result<(), EngineError> {
        let mut buf = std::mem::take(&mut self.state);
        self.ode.dense(tau, &mut buf).map_err(|e| ode_error(e, self.frame.time(tau), 0.0))?;
        self.state = buf;
        self.tau = tau;
        Ok(())
    }
}

/// Largest integrator step: twice the plate's fastest time scale with every junction
/// attached (`k = K + s N`, `s` the largest `|d f^x/dx|` of the law's stiffness range; `s =
/// kappa` for the tilted law), so the dense output used for event location stays within the
/// tolerance on long quiet stretches.
fn step_cap<L: ForceLaw>(plate: &Plate, law: L, n: usize) -> Option<f64> {
    let (lo, hi) = law.stiffness_range();
    let k = plate.k + hi.max(-lo) * n as f64;
    if k <= 0.0 {
        return None;
    }
    let t = if plate.mass > 0.0 { (plate.mass / k).sqrt() } else { plate.eta / k };
    Some(2.0 * t)
}

pub(crate) fn ode_error(e: OdeError, t: f64, rtol: f64) -> EngineError {
    match e {
        OdeError::StepSizeUnderflow { h, .. } => EngineError::StepSizeUnderflow { t, h, rtol },
        OdeError::NonFiniteRhs { .. } | OdeError::NonFiniteState { .. } | OdeError::NonFiniteStep { .. } => {
            EngineError::NonFinite { t, quantity: "plate state (adaptive integrator)", value: f64::NAN }
        }
        source => EngineError::Integrator { t, source },
    }
}

impl<L: ForceLaw, B: Bond> Engine for ExactDirect<L, B> {
    const KIND: EngineKind = EngineKind::Exact;
    const WEAK_BONDS: bool = B::IS_WEAK;

    fn time(&self) -> f64 {
        self.frame.time(self.tau)
    }

    fn time_step(&self) -> Option<f64> {
        None
    }

    fn advance<O: Observer>(&mut self, t_stop: f64, obs: &mut O) -> Result<(), EngineError> {
        let rtol = self.ode.config().rtol;
        loop {
            // In the local frame, which a re-basing inside this loop moves.
            let tau_stop = self.frame.local(t_stop).max(self.tau);
            let (ch, t_next) = self.channels.first();
            let target = t_next.min(tau_stop);
            if self.tau < target {
                let t_before = self.tau;
                let mut tau = self.tau;
                let mut state = std::mem::take(&mut self.state);
                let p = self.params();
                let mut sys = System { attached: &self.bags.attached, p };
                let result = self.ode.step(&mut sys, &mut tau, &mut state, target);
                self.state = state;
                if let Err(e) = result {
                    // Weak bonds: a rupture rate that grows on a time scale below the
                    // resolution of the local time (the step floor is 10 eps |tau|, and the
                    // step is rejected ever smaller near tau = 0) is
                    // resolved by moving the time origin here (a new piece; the hazard
                    // level is redrawn, which memorylessness allows). At tau = 0 it is
                    // beyond any resolution: as for an overflowing rate, the rupture is
                    // immediate (docs/model.md, "Equations", item 6), the junction chosen by its rate now.
                    let unresolved =
                        matches!(e, OdeError::StepSizeUnderflow { .. } | OdeError::TooManyRejections { .. });
                    if B::IS_WEAK && unresolved && self.bags.n_attached() > 0 {
                        self.check()?;
                        self.close_piece(obs);
                        if self.tau != 0.0 {
                            self.rebase();
                            self.open_piece();
                        } else {
                            *self.counters.candidates.as_mut().expect("set") += 1;
                            let slot = self.pick_weak();
                            self.rupture_slot(slot, obs);
                            self.after_event(None, obs);
                        }
                        continue;
                    }
                    return Err(ode_error(e, self.frame.time(t_before), rtol));
                }
                self.tau = tau;
                self.sync_ode_counters();
                // Weak bonds: did the hazard reach its level inside this step?
                if let Some(ih) = self.layout.h {
                    if self.state[ih] >= self.hazard_target {
                        let hit = self
                            .ode
                            .locate_component(ih, self.hazard_target)
                            .map_err(|e| ode_error(e, self.frame.time(t_before), rtol))?
                            .unwrap_or(self.tau);
                        self.seek(hit)?;
                        self.check()?;
                        *self.counters.candidates.as_mut().expect("set") += 1;
                        self.close_piece(obs);
                        let slot = self.pick_weak();
                        self.rupture_slot(slot, obs);
                        self.after_event(None, obs);
                        continue;
                    }
                }
                if self.tau < target {
                    continue;
                }
            }
            self.check()?;
            // A NaN time is never due (it would stop the loop, not spin it).
            let due = t_next <= tau_stop;
            if !due {
                self.close_piece(obs);
                self.maybe_rebase(obs);
                self.open_piece();
                return Ok(());
            }
            *self.counters.candidates.as_mut().expect("set") += 1;
            match ch {
                FORMATION => {
                    let g = self.formation.g(self.velocity(self.tau, &self.state));
                    if g >= 1.0 || self.rng.uniform() < g {
                        self.close_piece(obs);
                        self.form_one(obs);
                        self.after_event(Some(FORMATION), obs);
                    } else {
                        self.channels.redraw(FORMATION, self.tau, &mut self.rng);
                    }
                }
                _ => {
                    self.close_piece(obs);
                    let slot = self.rng.random_range(0..self.bags.n_attached());
                    self.rupture_slot(slot, obs);
                    self.after_event(Some(RUPTURE), obs);
                }
            }
        }
    }

    fn sample(&self) -> Sample {
        let y = self.state[Y];
        let sys = self.system();
        let fb = sys.forces(y).0;
        Sample {
            t: self.time(),
            x: self.frame.position(y),
            v: self.velocity(self.tau, &self.state),
            friction: -self.plate.k * self.frame.lag(y, self.tau),
            bond_force: fb,
            attached: self.bags.n_attached() as u64,
            n: self.n as u64,
        }
    }

    fn counters(&self) -> Counters {
        self.counters.clone()
    }
}

impl<L: ForceLaw, B: Bond> ExactDirect<L, B> {
    fn check(&self) -> Result<(), EngineError> {
        let y = self.state[Y];
        if !y.is_finite() {
            return Err(EngineError::NonFinite { t: self.time(), quantity: "X", value: y });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::exact::rupture::EXPONENT_CAP;

    #[test]
    fn cap_factor_is_e_to_the_cap() {
        assert!((CAP_RATE_FACTOR.ln() - EXPONENT_CAP).abs() < 1e-9);
    }

    #[test]
    fn layouts() {
        assert_eq!(Layout::new(false, false).dim, 5);
        assert_eq!(Layout::new(false, true).h, Some(5));
        assert_eq!(Layout::new(true, true).dim, 5);
        assert_eq!(Layout::new(true, false).vel, None);
    }
}
