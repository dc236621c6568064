//! The exact engine for the `linear` force law.
//!
//! With `f^x = kappa x` and attached junctions moving with the plate (`x_i = y - c_i`),
//! the bond force is `F_b = kappa (N_att y - C)`, `C = sum c_i`, so between events the plate
//! obeys the linear ODE `M y'' + eta y' + (K + kappa N_att) y = a + b s` and moves in closed
//! form ([`crate::engine::exact::linear::propagator`]). Events:
//! - formation candidates at rate `kon0 N_det`, accepted with probability `g(|y'|)` at the
//!   candidate time (thinning: exact because `g <= 1`), then a uniform detached junction;
//! - ruptures as chosen by the [`RuptureModel`] (strong: rate `k0 N_att`; weak: thinning);
//! - the end of a thinning horizon (weak bonds), and the runner's stop time.
//!
//! The trajectory restarts (a new closed-form solution from the current state) at every
//! event, horizon end and stop; each restart reports the exact time integrals of the
//! observables over the finished piece as a [`Segment`].
//!
//! With a kinematic plate (type parameter [`Kinematic`](super::motion::Kinematic), `plate.kinematic = true`) there is
//! no plate equation: `y = V tau` in local coordinates (so the lag `X - V t` is exactly 0),
//! `y' = V`, and `F_b = kappa (N_att V tau - C)` is linear in time between events, so a
//! segment's mean is `F_b` at its midpoint and `int (F_b - mean)^2 = (kappa N_att V)^2 h^3 / 12`.
//! Formation has the constant acceptance `g(V)`, folded into the candidate rate (every
//! candidate is an event). Weak bonds bound their rates over a horizon from
//! `y_lo = y(tau)`, `y_hi = y(tau + H)` ([`Drive`]). The friction reported is `F_b`.

use serde::{Deserialize, Serialize};

use crate::engine::alloc::AllocError;
use crate::engine::exact::bags::Bags;
use crate::engine::exact::clocks::{ChannelQueue, Channels};
use crate::engine::exact::core::{REBASE, emit, reattached_extension};
use crate::engine::exact::frame::Frame;
use crate::engine::exact::linear::propagator::{Integrals, LinearPlate, Trajectory};
use crate::engine::exact::motion::{Drive, Dynamic, PlateMotion};
use crate::engine::exact::pick::Pick;
use crate::engine::exact::rupture::RuptureModel;
use crate::engine::{Counters, Engine, EngineError};
use crate::observe::{EventKind, Observer, Sample, Segment};
use crate::physics::{Formation, LinearLaw, Plate};
use crate::rng::{Pcg64, UniformSource, pcg};
use crate::scene::{EngineKind, Reattach, Scene};

/// Channel of formation candidates.
const FORMATION: usize = 0;
/// Channel of ruptures (strong) or rupture candidates (weak).
const RUPTURE: usize = 1;
/// End of the current thinning horizon.
const HORIZON: usize = 2;
const CHANNELS: usize = 3;

/// The current closed-form piece of the plate trajectory.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Piece {
    /// Local start time.
    tau0: f64,
    /// State at the start.
    y0: f64,
    v0: f64,
    traj: Trajectory,
}

/// Exact event-driven engine, linear force law, rupture kinetics `R`, event queue `Q`, plate
/// motion `M` (the plate equation, or a kinematic plate).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct ExactLinear<R: RuptureModel, Q: ChannelQueue, M: PlateMotion = Dynamic> {
    n: usize,
    plate: Plate,
    kappa: f64,
    lambda: f64,
    reattach: Reattach,
    formation: Formation,
    frame: Frame,
    /// Current local time and plate state at it.
    tau: f64,
    y: f64,
    yd: f64,
    piece: Piece,
    bags: Bags,
    rupture: R,
    channels: Channels<Q>,
    rng: Pcg64,
    /// The next uniform pick of a detached junction.
    next_formation: Pick,
    counters: Counters,
    events_since_rebase: u64,
    #[serde(skip)]
    plates: PlateCache,
    #[serde(skip)]
    motion: std::marker::PhantomData<M>,
}

/// Classified plates `M y'' + eta y' + (K + kappa n) y` for recent attached counts `n`: the
/// count moves by one per event, so a small direct-mapped cache saves the classification
/// (a square root and several divisions) on almost every event.
#[derive(Clone, Debug, Default)]
struct PlateCache {
    /// `(n, plate)`; `n = usize::MAX` marks an empty slot (no count reaches it).
    entries: Vec<(usize, LinearPlate)>,
}

impl PlateCache {
    const SLOTS: usize = 64;
    #[inline]
    fn get(&mut self, p: &Plate, kappa: f64, n_att: usize) -> &LinearPlate {
        if self.entries.len() != Self::SLOTS {
            self.entries = vec![(usize::MAX, LinearPlate::new(1.0, 1.0, 1.0)); Self::SLOTS];
        }
        let slot = &mut self.entries[n_att % Self::SLOTS];
        if slot.0 != n_att {
            *slot = (n_att, LinearPlate::new(p.mass, p.eta, p.k + kappa * n_att as f64));
        }
        &slot.1
    }
}

impl<R: RuptureModel, Q: ChannelQueue, M: PlateMotion> ExactLinear<R, Q, M> {
    /// The engine at `t = 0` for `scene` under the linear law `law` (its slope is the
    /// engine's `kappa`), with rupture kinetics made by `rupture` (after the initial state
    /// has been drawn from the generator).
    ///
    /// Panics if the junction buffers cannot be allocated; [`ExactLinear::try_new`] reports it.
    pub fn new<L: LinearLaw>(scene: &Scene, law: &L, rupture: impl FnOnce(&mut Pcg64) -> R) -> Self {
        Self::try_new(scene, law, |rng| Ok(rupture(rng))).unwrap_or_else(|e| panic!("{e}"))
    }

    /// [`ExactLinear::new`] with the junction buffers (bags, and the rupture model's, built by
    /// `rupture`) reserved fallibly.
    pub fn try_new<L: LinearLaw>(
        scene: &Scene,
        law: &L,
        rupture: impl FnOnce(&mut Pcg64) -> Result<R, AllocError>,
    ) -> Result<Self, AllocError> {
        let j = &scene.junctions;
        let mut rng = pcg(scene.run.seed);
        let bags = Bags::initial(j, &mut rng)?;
        let plate = Plate::from_scene(scene);
        let rupture = rupture(&mut rng)?;
        let next_formation = Pick::draw(&mut rng);
        let mut e = ExactLinear {
            n: j.n,
            plate,
            kappa: law.slope(),
            lambda: j.lambda,
            reattach: j.reattach,
            formation: Formation::from_scene(scene),
            frame: Frame::new(plate.v),
            tau: 0.0,
            y: 0.0,
            yd: 0.0,
            piece: Piece {
                tau0: 0.0,
                y0: 0.0,
                v0: 0.0,
                traj: LinearPlate::new(1.0, 1.0, 1.0).trajectory(0.0, 0.0, 0.0, 0.0),
            },
            bags,
            rupture,
            channels: Channels::new(CHANNELS),
            rng,
            next_formation,
            counters: Counters { events: Some(0), candidates: Some(0), rebases: Some(0), ..Default::default() },
            events_since_rebase: 0,
            plates: PlateCache::default(),
            motion: std::marker::PhantomData,
        };
        let attached = std::mem::take(&mut e.bags.attached);
        for (slot, a) in attached.iter().enumerate() {
            e.rupture.attached(slot, a.c, 0.0);
        }
        e.bags.attached = attached;
        e.open_piece();
        // At rest at t = 0; for M = 0 the velocity follows from the forces. A kinematic
        // plate moves at V from the start.
        e.yd = if M::KINEMATIC { e.plate.v } else { e.piece.traj.at(0.0).1 };
        e.refresh_clocks(None);
        Ok(e)
    }

    /// Starts a new closed-form piece at the current time and state.
    fn open_piece(&mut self) {
        if M::KINEMATIC {
            self.piece.tau0 = self.tau;
            self.piece.y0 = self.y;
            self.piece.v0 = self.yd;
            return;
        }
        let p = &self.plate;
        // M y'' + eta y' + k y = K (V (tau + s) - lag_ref) + kappa C.
        let a = p.k * (p.v * self.tau - self.frame.lag_ref) + self.kappa * self.bags.anchor_sum();
        let b = p.k * p.v;
        let plate = self.plates.get(p, self.kappa, self.bags.n_attached());
        self.piece.traj.restart(plate, self.y, self.yd, a, b);
        self.piece.tau0 = self.tau;
        self.piece.y0 = self.y;
        self.piece.v0 = self.yd;
    }

    /// Moves along the piece to local time `tau1` and reports `[piece.tau0, tau1]` as a
    /// segment. Returns the plate state at `tau1`.
    fn close_piece<O: Observer>(&mut self, tau1: f64, obs: &mut O) -> (f64, f64) {
        if M::KINEMATIC {
            return self.close_kinematic(tau1, obs);
        }
        let h = (tau1 - self.piece.tau0).max(0.0);
        let (y1, v1, ints) = self.piece.traj.at_maybe_integrals(h, self.plate.v, O::SEGMENTS);
        self.report_piece(tau1, y1, v1, ints, obs);
        (y1, v1)
    }

    /// Reports `[piece.tau0, tau1]` given the state and integrals at `tau1`, and moves there.
    fn report_piece<O: Observer>(&mut self, tau1: f64, y1: f64, v1: f64, ints: Integrals, obs: &mut O) {
        let pc = &self.piece;
        let h = tau1 - pc.tau0;
        if h > 0.0 {
            let p = &self.plate;
            // Lag w.r.t. the driver: lag(s) = lag0 + (y(s) - y0 - V s).
            let lag0 = self.frame.lag(pc.y0, pc.tau0);
            let inv_h = 1.0 / h;
            let w1 = ints.i1 - 0.5 * p.v * h * h;
            let mean_lag = lag0 + w1 * inv_h;
            let m2 = (ints.i2 - w1 * w1 * inv_h).max(0.0);
            let n_att = self.bags.n_attached();
            let bond = self.kappa * (n_att as f64 * (pc.y0 + ints.i1 * inv_h) - self.bags.anchor_sum());
            obs.segment(&Segment {
                t0: self.frame.time(pc.tau0),
                t1: self.frame.time(tau1),
                friction: -p.k * mean_lag,
                friction_m2: p.k * p.k * m2,
                bond_force: bond,
                viscous: p.eta * (y1 - pc.y0) * inv_h,
                attached: n_att as u64,
            });
        }
        self.tau = tau1;
        self.y = y1;
        self.yd = v1;
    }

    /// Kinematic plate: reports `[piece.tau0, tau1]` (friction = `F_b`, linear in time) and
    /// moves to `y = V tau1`.
    fn close_kinematic<O: Observer>(&mut self, tau1: f64, obs: &mut O) -> (f64, f64) {
        let pc = &self.piece;
        let v = self.plate.v;
        let y1 = v * tau1;
        let h = tau1 - pc.tau0;
        if h > 0.0 {
            let n_att = self.bags.n_attached() as f64;
            // F_b(s) = kappa (N y(s) - C): its mean is its midpoint value, and
            // int (F_b - mean)^2 ds = (kappa N V)^2 h^3 / 12.
            let bond = self.kappa * (n_att * (0.5 * (pc.y0 + y1)) - self.bags.anchor_sum());
            let slope = self.kappa * n_att * v;
            obs.segment(&Segment {
                t0: self.frame.time(pc.tau0),
                t1: self.frame.time(tau1),
                friction: bond,
                friction_m2: slope * slope * h * h * h / 12.0,
                bond_force: bond,
                viscous: 0.0,
                attached: n_att as u64,
            });
        }
        self.tau = tau1;
        self.y = y1;
        self.yd = v;
        (y1, v)
    }

    /// The plate along the current piece, as a kinematic drive.
    #[inline]
    fn drive(&self) -> Drive {
        Drive { y0: self.piece.y0, v: self.plate.v }
    }

    /// Sets every channel's rate after a change of state; channel `fired` draws afresh.
    fn refresh_clocks(&mut self, fired: Option<usize>) {
        let now = self.tau;
        let n_att = self.bags.n_attached();
        let (plan, accept) = if M::KINEMATIC {
            // Constant g(V): folded into the formation rate, every candidate is an event.
            (self.rupture.plan(&self.drive(), n_att), self.formation.g(self.plate.v))
        } else {
            (self.rupture.plan(&self.piece.traj, n_att), 1.0)
        };
        let rates = [self.formation.kon0 * accept * self.bags.n_detached() as f64, plan.rate];
        self.channels.set_rates(now, rates, fired, &mut self.rng);
        self.channels.set_time(HORIZON, if R::IS_WEAK { now + plan.horizon } else { f64::INFINITY });
    }

    #[inline]
    fn emit<O: Observer>(&self, obs: &mut O, kind: EventKind, id: u32, x: f64) {
        emit(obs, self.frame.time(self.tau), kind, id, x, |x| self.kappa * x.abs());
    }

    /// Ruptures the attached junction in `slot` now.
    fn rupture_slot<O: Observer>(&mut self, slot: usize, obs: &mut O) {
        let last = self.bags.n_attached() - 1;
        let a = self.bags.take_attached(slot);
        let moved = (slot != last).then(|| self.bags.attached[slot].c);
        self.rupture.detached(slot, last, moved);
        let x = self.y - a.c;
        self.bags.detached.push(crate::engine::exact::bags::Detached { x, t: self.tau, id: a.id });
        self.counters.ruptures += 1;
        self.emit(obs, EventKind::Rupture, a.id, x);
    }

    /// Attaches a uniformly chosen detached junction now; if its rupture rate overflows
    /// (weak bonds), it ruptures at once.
    fn form_one<O: Observer>(&mut self, obs: &mut O) {
        // Weak bonds: the new anchor's weights exp(+-a c) must be representable. With no
        // junction attached there is no horizon, so the plate may have moved far since the
        // last re-basing (a |y| > EXPONENT_CAP would make `attached` refuse the junction as
        // if its own rate, which depends only on x = y - c, had overflowed): re-base first.
        if self.rupture.needs_rebase(self.y, self.tau) {
            self.maybe_rebase(obs);
        }
        let slot = self.next_formation.take(self.bags.n_detached(), &mut self.rng);
        let d = self.bags.take_detached(slot);
        let x = reattached_extension(self.reattach, self.lambda, &d, self.tau);
        let c = self.y - x;
        self.bags.attach(c, d.id);
        self.counters.formations += 1;
        self.emit(obs, EventKind::Formation, d.id, x);
        let slot = self.bags.n_attached() - 1;
        if !self.rupture.attached(slot, c, self.y) {
            self.rupture_slot(slot, obs);
        }
    }

    /// Re-bases the frame if positions or times have grown (amortised O(1) per event).
    #[inline]
    fn maybe_rebase<O: Observer>(&mut self, obs: &mut O) {
        let forced = self.rupture.needs_rebase(self.y, self.tau);
        if !REBASE.due(self.y, self.tau, self.events_since_rebase, self.n, forced) {
            return;
        }
        let (dtau, dy) = (self.tau, self.y);
        self.frame.shift(dtau, dy);
        self.bags.rebase(dtau, dy);
        self.channels.shift(dtau);
        self.tau = 0.0;
        self.y = 0.0;
        self.piece.tau0 = 0.0;
        self.piece.y0 = 0.0;
        self.events_since_rebase = 0;
        *self.counters.rebases.as_mut().expect("set at construction") += 1;
        // Junctions whose rate overflowed in the new frame rupture at once (highest slot
        // first, so swap_remove does not disturb the slots still to do).
        let mut over = self.rupture.rebuild(&self.bags.attached);
        over.sort_unstable_by(|a, b| b.cmp(a));
        for slot in over {
            self.rupture_slot(slot, obs);
        }
    }

    /// After an event at the current time: new piece, new rates.
    fn after_event<O: Observer>(&mut self, fired: Option<usize>, obs: &mut O) {
        self.events_since_rebase += 1;
        *self.counters.events.as_mut().expect("set at construction") =
            self.counters.ruptures + self.counters.formations;
        self.maybe_rebase(obs);
        self.open_piece();
        self.refresh_clocks(fired);
        self.next_formation.prefetch(&self.bags.detached);
        self.rupture.prefetch(&self.bags.attached);
    }

    #[inline]
    fn count_candidate(&mut self) {
        *self.counters.candidates.as_mut().expect("set at construction") += 1;
    }
}

impl<R: RuptureModel, Q: ChannelQueue, M: PlateMotion> Engine for ExactLinear<R, Q, M> {
    const KIND: EngineKind = EngineKind::Exact;
    const WEAK_BONDS: bool = R::IS_WEAK;

    fn time(&self) -> f64 {
        self.frame.time(self.tau)
    }

    fn time_step(&self) -> Option<f64> {
        None
    }

    fn advance<O: Observer>(&mut self, t_stop: f64, obs: &mut O) -> Result<(), EngineError> {
        loop {
            // In the local frame, which a re-basing inside this loop moves.
            let tau_stop = self.frame.local(t_stop).max(self.tau);
            let (ch, t_next) = self.channels.first();
            // A NaN time is never due (it would stop the loop, not spin it).
            let due = t_next <= tau_stop;
            if !due {
                let (y, v) = self.close_piece(tau_stop, obs);
                self.check(y, v)?;
                self.maybe_rebase(obs);
                self.open_piece();
                self.refresh_clocks(None);
                return Ok(());
            }
            self.count_candidate();
            match ch {
                FORMATION if M::KINEMATIC => {
                    let (y, v) = self.close_kinematic(t_next, obs);
                    self.check(y, v)?;
                    self.form_one(obs);
                    self.after_event(Some(FORMATION), obs);
                }
                RUPTURE if M::KINEMATIC => {
                    let drive = self.drive();
                    match self.rupture.pick(&mut self.rng, &drive, t_next - self.piece.tau0, &self.bags.attached) {
                        Some(slot) => {
                            let (y, v) = self.close_kinematic(t_next, obs);
                            self.check(y, v)?;
                            self.rupture_slot(slot, obs);
                            self.after_event(Some(RUPTURE), obs);
                        }
                        None => self.channels.redraw(RUPTURE, t_next, &mut self.rng),
                    }
                }
                FORMATION => {
                    // The state (and, if accepted, the piece's integrals) at the candidate.
                    let h = t_next - self.piece.tau0;
                    let (y, v, ints) = self.piece.traj.at_maybe_integrals(h, self.plate.v, O::SEGMENTS);
                    let g = self.formation.g(v);
                    if g >= 1.0 || self.rng.uniform() < g {
                        self.report_piece(t_next, y, v, ints, obs);
                        self.check(y, v)?;
                        self.form_one(obs);
                        self.after_event(Some(FORMATION), obs);
                    } else {
                        self.channels.redraw(FORMATION, t_next, &mut self.rng);
                    }
                }
                RUPTURE => match self.rupture.pick(
                    &mut self.rng,
                    &self.piece.traj,
                    t_next - self.piece.tau0,
                    &self.bags.attached,
                ) {
                    Some(slot) => {
                        let (y, v) = self.close_piece(t_next, obs);
                        self.check(y, v)?;
                        self.rupture_slot(slot, obs);
                        self.after_event(Some(RUPTURE), obs);
                    }
                    None => self.channels.redraw(RUPTURE, t_next, &mut self.rng),
                },
                _ => {
                    // End of a thinning horizon: restart the piece, recompute the bound.
                    let (y, v) = self.close_piece(t_next, obs);
                    self.check(y, v)?;
                    self.maybe_rebase(obs);
                    self.open_piece();
                    self.refresh_clocks(None);
                }
            }
        }
    }

    fn sample(&self) -> Sample {
        let n_att = self.bags.n_attached();
        let bond_force = self.kappa * (n_att as f64 * self.y - self.bags.anchor_sum());
        Sample {
            t: self.time(),
            x: self.frame.position(self.y),
            v: self.yd,
            friction: if M::KINEMATIC { bond_force } else { -self.plate.k * self.frame.lag(self.y, self.tau) },
            bond_force,
            attached: n_att as u64,
            n: self.n as u64,
        }
    }

    fn counters(&self) -> Counters {
        self.counters.clone()
    }
}

impl<R: RuptureModel, Q: ChannelQueue, M: PlateMotion> ExactLinear<R, Q, M> {
    /// Non-finite plate state is an error, never an output.
    #[inline]
    fn check(&self, y: f64, v: f64) -> Result<(), EngineError> {
        if !y.is_finite() {
            return Err(EngineError::NonFinite { t: self.time(), quantity: "X", value: y });
        }
        if !v.is_finite() {
            return Err(EngineError::NonFinite { t: self.time(), quantity: "Xd", value: v });
        }
        Ok(())
    }
}
