//! The exact engine for a linear law: the closed-form plate, as a [`Stepper`] of the exact
//! core ([`crate::engine::exact::core`]).
//!
//! With `f^x = kappa x` and attached junctions moving with the plate (`x_i = y - c_i`),
//! the bond force is `F_b = kappa (N_att y - C)`, `C = sum c_i`, so between events the plate
//! obeys the linear ODE `M y'' + eta y' + (K + kappa N_att) y = a + b s` and moves in closed
//! form ([`crate::engine::exact::stepper::linear::propagator`]). Events:
//! - formation candidates at rate `kon0 N_det`, accepted with probability `g(|y'|)` at the
//!   candidate time (thinning: exact because `g <= 1`), then a uniform detached junction;
//! - ruptures as chosen by the [`RuptureModel`] (strong: rate `k0 N_att`; weak: thinning
//!   over a horizon of the closed form, [`Stepper::bounds`]);
//! - the end of a thinning horizon (weak bonds), and the runner's stop time.
//!
//! The trajectory restarts (a new closed-form solution from the current state) at every
//! event, horizon end and stop; each restart reports the exact time integrals of the
//! observables over the finished piece as a [`Segment`].
//!
//! With a kinematic plate (type parameter [`Kinematic`](crate::engine::exact::Kinematic),
//! `plate.kinematic = true`) there is no plate equation: `y = V tau` in local coordinates
//! (so the lag `X - V t` is exactly 0), `y' = V`, and `F_b = kappa (N_att V tau - C)` is
//! linear in time between events, so a segment's mean is `F_b` at its midpoint and
//! `int (F_b - mean)^2 = (kappa N_att V)^2 h^3 / 12`. Formation has the constant acceptance
//! `g(V)`, folded into the candidate rate (every candidate is an event). Weak bonds bound
//! their rates over a horizon from `y_lo = y(tau)`, `y_hi = y(tau + H)` ([`Drive`]). The
//! friction reported is `F_b`.

use serde::{Deserialize, Serialize};

use super::motion::{Drive, Dynamic, PlateMotion};
use crate::engine::EngineError;
use crate::engine::alloc::AllocError;
use crate::engine::exact::core::clocks::ChannelQueue;
use crate::engine::exact::core::engine::Exact;
use crate::engine::exact::core::pick::Pick;
use crate::engine::exact::core::state::Core;
use crate::engine::exact::rupture::{LinearRate, RuptureModel};
use crate::engine::exact::stepper::contract::{Stepper, WeakRuptures};
use crate::engine::exact::stepper::linear::propagator::{LinearPlate, Terms, Trajectory};
use crate::engine::exact::stepper::linear::report;
use crate::observe::{Observer, Segment};
use crate::physics::{LinearLaw, Plate};
use crate::rng::Pcg64;
use crate::scene::Scene;

/// Exact event-driven engine, linear force law, rupture kinetics `R`, event queue `Q`, plate
/// motion `M` (the plate equation, or a kinematic plate).
pub type ExactLinear<R, Q, M = Dynamic> = Exact<LinearStepper<Q, M>, R>;

/// The current closed-form piece of the plate trajectory.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Piece {
    /// Local start time.
    tau0: f64,
    /// State at the start.
    y0: f64,
    v0: f64,
    traj: Trajectories,
}

/// The piece's trajectory, held in a small direct-mapped cache of trajectories by attached
/// count `n`, each on its classified plate `M y'' + eta y' + (K + kappa n) y`: the count
/// moves by one per event, so the classification (a square root and several divisions) is
/// saved on almost every event, and a restart writes only the new initial state and
/// forcing into the slot of its count (no copy of the plate). Written and read as the
/// current [`Trajectory`] alone (a trajectory read back sits in slot 0 under no count,
/// until the next restart).
#[derive(Clone)]
struct Trajectories {
    /// `(n, trajectory)` in slot `n % SLOTS`; `n = usize::MAX` marks no count (none reaches it).
    slots: Box<[(usize, Trajectory); Trajectories::SLOTS]>,
    /// The current slot (below `SLOTS`).
    cur: usize,
}

impl Trajectories {
    const SLOTS: usize = 256;

    /// Every slot empty, and `traj` the current trajectory.
    fn holding(traj: Trajectory) -> Trajectories {
        Trajectories { slots: Box::new([(usize::MAX, traj); Self::SLOTS]), cur: 0 }
    }

    /// The current trajectory.
    #[inline(always)]
    fn current(&self) -> &Trajectory {
        &self.slots[self.cur % Self::SLOTS].1
    }

    /// Makes the trajectory of `n_att` attached junctions current, its plate classified
    /// if its slot held another count, and returns it (its state is the caller's to set).
    #[inline(always)]
    fn select(&mut self, p: &Plate, kappa: f64, n_att: usize) -> &mut Trajectory {
        let i = n_att % Self::SLOTS;
        if self.slots[i].0 != n_att {
            self.fill(p, kappa, n_att);
        }
        self.cur = i;
        &mut self.slots[i].1
    }

    /// Classifies the plate for `n_att` into its slot.
    #[cold]
    #[inline(never)]
    fn fill(&mut self, p: &Plate, kappa: f64, n_att: usize) {
        let plate = LinearPlate::new(p.mass, p.eta, p.k + kappa * n_att as f64);
        self.slots[n_att % Self::SLOTS] = (n_att, plate.trajectory(0.0, 0.0, 0.0, 0.0));
    }
}

impl std::fmt::Debug for Trajectories {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.current().fmt(f)
    }
}

impl Serialize for Trajectories {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.current().serialize(s)
    }
}

impl<'de> Deserialize<'de> for Trajectories {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Trajectory::deserialize(d).map(Trajectories::holding)
    }
}

/// The closed-form plate of a linear law, and the uniform picks of detached junctions drawn
/// ahead ([`Pick`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct LinearStepper<Q: ChannelQueue, M: PlateMotion = Dynamic> {
    kappa: f64,
    /// The drive's velocity `V` (a kinematic plate's path).
    v: f64,
    /// Plate state at the core's local time.
    y: f64,
    yd: f64,
    piece: Piece,
    /// The next uniform pick of a detached junction.
    next_formation: Pick,
    /// The pieces summed for an observer that takes stretches (empty at the end of every
    /// advance, so never written).
    #[serde(skip)]
    sums: report::Sums,
    /// The observers' window, read at the start of every advance (so never written).
    #[serde(skip)]
    window: report::Window,
    #[serde(skip)]
    types: std::marker::PhantomData<(Q, M)>,
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
        let mut core = Core::new(scene, 3)?;
        let rupture = rupture(&mut core.rng)?;
        let next_formation = Pick::draw(&mut core.rng);
        let stepper = LinearStepper {
            kappa: law.slope(),
            v: core.plate.v,
            y: 0.0,
            yd: 0.0,
            piece: Piece {
                tau0: 0.0,
                y0: 0.0,
                v0: 0.0,
                traj: Trajectories::holding(LinearPlate::new(1.0, 1.0, 1.0).trajectory(0.0, 0.0, 0.0, 0.0)),
            },
            next_formation,
            sums: report::Sums::default(),
            window: report::Window::default(),
            types: std::marker::PhantomData,
        };
        Ok(Exact::start(core, stepper, rupture))
    }
}

impl<Q: ChannelQueue, M: PlateMotion> LinearStepper<Q, M> {
    /// Reports `[piece.tau0, tau1]` given the state and integrals' terms at `tau1` as raw integrals
    /// ([`report::piece`]: no division), or sums it for an observer that takes stretches
    /// ([`Observer::STRETCHES`]: inside the observers' [`report::Window`]; nothing before),
    /// and moves there.
    #[inline(always)]
    fn report_piece<O: Observer>(
        &mut self,
        core: &mut Core<Q>,
        tau1: f64,
        y1: f64,
        v1: f64,
        terms: Terms,
        obs: &mut O,
    ) {
        let pc = &self.piece;
        let h = tau1 - pc.tau0;
        if h > 0.0 {
            let span = report::Span {
                tau0: pc.tau0,
                tau1,
                h,
                y0: pc.y0,
                v0: pc.v0,
                // Lag w.r.t. the driver: lag(s) = lag0 + (y(s) - y0 - V s).
                lag0: core.frame.lag(pc.y0, pc.tau0),
                y1,
                v1,
                n_att: core.bags.n_attached(),
                terms,
            };
            if O::STRETCHES && O::SEGMENTS && self.window.sums(pc.tau0, tau1) {
                self.sums.add(&span, &core.frame, core.plate.v);
            } else if !O::STRETCHES || self.window.integrals(tau1) {
                obs.piece(&report::piece(&span, &core.frame, core.bags.anchor_sum(), &core.plate, self.kappa));
            }
        }
        core.tau = tau1;
        self.y = y1;
        self.yd = v1;
    }

    /// Kinematic plate: reports `[piece.tau0, tau1]` (friction = `F_b`, linear in time) and
    /// moves to `y = V tau1`.
    fn close_kinematic<O: Observer>(&mut self, core: &mut Core<Q>, tau1: f64, obs: &mut O) {
        let pc = &self.piece;
        let v = core.plate.v;
        let y1 = v * tau1;
        let h = tau1 - pc.tau0;
        if h > 0.0 {
            let n_att = core.bags.n_attached() as f64;
            // F_b(s) = kappa (N y(s) - C): its mean is its midpoint value, and
            // int (F_b - mean)^2 ds = (kappa N V)^2 h^3 / 12.
            let bond = self.kappa * (n_att * (0.5 * (pc.y0 + y1)) - core.bags.anchor_sum());
            let slope = self.kappa * n_att * v;
            obs.segment(&Segment {
                t0: core.frame.time(pc.tau0),
                t1: core.frame.time(tau1),
                friction: bond,
                friction_m2: slope * slope * h * h * h / 12.0,
                bond_force: bond,
                viscous: 0.0,
                attached: n_att as u64,
            });
        }
        core.tau = tau1;
        self.y = y1;
        self.yd = v;
    }

    /// Whether a piece ending at local time `tau1` is reported with its integrals
    /// ([`Observer::integrals_after`]: none in the warm-up for a run's observers).
    #[inline(always)]
    fn integrals<O: Observer>(&self, tau1: f64) -> bool {
        O::SEGMENTS && self.window.integrals(tau1)
    }

    /// The plate along the current piece, as a kinematic drive.
    #[inline(always)]
    fn drive(&self) -> Drive {
        Drive { y0: self.piece.y0, v: self.v }
    }

    /// Non-finite plate state is an error, never an output.
    #[inline]
    fn check(&self, core: &Core<Q>) -> Result<(), EngineError> {
        core.finite("X", self.y)?;
        core.finite("Xd", self.yd)
    }
}

impl<Q: ChannelQueue, M: PlateMotion> Stepper for LinearStepper<Q, M> {
    type Queue = Q;
    type Rate = LinearRate;
    const KINEMATIC: bool = M::KINEMATIC;
    const WEAK_RUPTURES: WeakRuptures = WeakRuptures::Horizon;

    fn start(&mut self, core: &mut Core<Q>) {
        self.open_piece(core);
        // At rest at t = 0; for M = 0 the velocity follows from the forces. A kinematic
        // plate moves at V from the start.
        self.yd = if M::KINEMATIC { core.plate.v } else { self.piece.traj.current().at(0.0).1 };
    }

    #[inline(always)]
    fn rate(&self) -> LinearRate {
        LinearRate
    }

    /// Along the piece, from the closed form (or the drive).
    #[inline(always)]
    fn position(&mut self, tau: f64) -> Result<f64, EngineError> {
        let s = tau - self.piece.tau0;
        Ok(if M::KINEMATIC { self.drive().position(s) } else { self.piece.traj.current().at(s).0 })
    }

    /// The piece's proven bounds (it was just opened, at the current time).
    #[inline(always)]
    fn bounds(&self, _core: &Core<Q>, h: f64) -> (f64, f64) {
        if M::KINEMATIC { self.drive().bounds(h) } else { self.piece.traj.current().bounds(h) }
    }

    /// The event changed the bond force `kappa (N_att y - C)` by `g = +-kappa (y_old - c)`
    /// along the old path, `|g| <= kappa max(|hi - c|, |lo - c|)`, from a common state:
    /// [`Trajectory::response`] of that bound. A kinematic plate does not respond.
    #[inline(always)]
    fn reach(&self, c: f64, rest: f64, lo: f64, hi: f64) -> f64 {
        if M::KINEMATIC {
            return 0.0;
        }
        let g = self.kappa * (hi - c).abs().max((lo - c).abs());
        self.piece.traj.current().response(rest) * g
    }

    #[inline]
    fn y(&self, _core: &Core<Q>) -> f64 {
        self.y
    }

    #[inline]
    fn velocity(&self, _core: &Core<Q>) -> f64 {
        self.yd
    }

    fn bond_force(&self, core: &Core<Q>) -> f64 {
        self.kappa * (core.bags.n_attached() as f64 * self.y - core.bags.anchor_sum())
    }

    /// The candidate's state (and, if accepted, the piece's integrals) at `t`, from the closed
    /// form; a kinematic plate's formations are thinned in the rate ([`Stepper::formation_acceptance`]).
    /// Always inlined, as [`Stepper::close`].
    #[inline(always)]
    fn formation<O: Observer>(&mut self, core: &mut Core<Q>, t: f64, obs: &mut O) -> Result<bool, EngineError> {
        if M::KINEMATIC {
            self.close_kinematic(core, t, obs);
            self.check(core)?;
            return Ok(true);
        }
        let h = t - self.piece.tau0;
        let (y, v, terms) = self.piece.traj.current().at_maybe_terms(h, core.plate.v, self.integrals::<O>(t));
        if core.accepts_formation(v) {
            self.report_piece(core, t, y, v, terms, obs);
            self.check(core)?;
            return Ok(true);
        }
        Ok(false)
    }

    /// Moves along the piece to `t` and reports `[piece.tau0, t]` as a segment. Always
    /// inlined: a rupture closes its piece here, and the call cost a tenth of the closing.
    #[inline(always)]
    fn close<O: Observer>(&mut self, core: &mut Core<Q>, t: f64, obs: &mut O) -> Result<(), EngineError> {
        if M::KINEMATIC {
            self.close_kinematic(core, t, obs);
        } else {
            let h = (t - self.piece.tau0).max(0.0);
            let (y1, v1, terms) = self.piece.traj.current().at_maybe_terms(h, core.plate.v, self.integrals::<O>(t));
            self.report_piece(core, t, y1, v1, terms, obs);
        }
        self.check(core)
    }

    /// Reads the observers' window in local time.
    #[inline]
    fn begin<O: Observer>(&mut self, core: &Core<Q>, obs: &O) {
        self.window = report::Window::new(obs.integrals_after(), obs.stretch_until(), &core.frame);
        self.sums.set_junctions(core.n);
    }

    /// Reports the pieces summed in this advance as one stretch.
    #[inline]
    fn stopped<O: Observer>(&mut self, core: &Core<Q>, obs: &mut O) {
        if O::STRETCHES && O::SEGMENTS {
            obs.stretch(&self.sums.take(&core.plate, core.frame.time(core.tau)));
        }
    }

    /// Starts a new closed-form piece at the current time and state.
    #[inline]
    fn open_piece(&mut self, core: &mut Core<Q>) {
        if !M::KINEMATIC {
            let p = &core.plate;
            // M y'' + eta y' + k y = K (V (tau + s) - lag_ref) + kappa C.
            let a = p.k * (p.v * core.tau - core.frame.lag_ref) + self.kappa * core.bags.anchor_sum();
            let b = p.k * p.v;
            self.piece.traj.select(p, self.kappa, core.bags.n_attached()).restart_on_plate(self.y, self.yd, a, b);
        }
        self.piece.tau0 = core.tau;
        self.piece.y0 = self.y;
        self.piece.v0 = self.yd;
    }

    #[inline]
    fn shifted(&mut self, core: &Core<Q>, _dtau: f64, dy: f64) {
        self.sums.shifted(dy);
        self.window.relocate(&core.frame);
        self.y = 0.0;
        self.piece.tau0 = 0.0;
        self.piece.y0 = 0.0;
    }

    #[inline]
    fn tension(&self, x: f64) -> f64 {
        self.kappa * x.abs()
    }

    /// Constant `g(V)` for a kinematic plate: folded into the formation rate, every
    /// candidate is an event.
    #[inline]
    fn formation_acceptance(&self, core: &Core<Q>) -> f64 {
        if M::KINEMATIC { core.formation.g(core.plate.v) } else { 1.0 }
    }

    #[inline]
    fn formation_slot(&mut self, rng: &mut Pcg64, n: usize) -> usize {
        self.next_formation.take(n, rng)
    }

    #[inline(always)]
    fn prefetch(&self, core: &Core<Q>) {
        self.next_formation.prefetch(&core.bags.detached);
    }
}
