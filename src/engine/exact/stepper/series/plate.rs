//! Plate motions of the series engine, chosen once per run.
//!
//! - [`RosenbrockPlate`]: the plate equation `M y'' + eta y' + S(y) + K lag = 0` (or `eta y' = ...`
//!   when `M = 0`) with `S` the junction force from the [`SeriesSum`], integrated by the
//!   L-stable Rosenbrock method ([`RosenbrockN`] on 2 variables, or 1 when `M = 0`) with the
//!   analytic Jacobian. Stable at any stiffness: the step follows the accuracy, not `M/eta`
//!   or `sqrt(M/K)`. The segment statistics are not integrated: `L = int (lag - lag0)` and
//!   `L2 = int (lag - lag0)^2` are exact integrals of each step's dense-output cubic
//!   ([`RosenbrockN::dense_integrals`]), and `B = int S` follows from the plate equation's
//!   force balance ([`RosenbrockPlate::segment`]).
//! - [`DrivenPlate`]: `y = V tau` exactly, no ODE and no integrator; the statistics come from
//!   [`SeriesSum::integral`] (`int S dy`) and an 8-point Gauss–Legendre rule for
//!   `int (S - S0)^2`.
//!
//! Every step keeps `|y - base| <= radius` of the series (re-basing, and retaking the step
//! if the bounds of the accepted step leave the disc) and, for weak bonds, `y_hi - y_lo <=
//! max_spread`, so the thinning envelope of the step is tight.

use serde::{Deserialize, Serialize, de::DeserializeOwned};

use super::sum::{LocalCubic, SeriesSum};
use super::taylor::{ORDER, Plant, TimeSeries, Tol};
use crate::engine::exact::core::frame::Frame;
use crate::engine::exact::stepper::contract::Step;
use crate::engine::exact::stepper::direct::ode_error;
use crate::engine::{Counters, EngineError};
use crate::observe::Segment;
use crate::ode::{RosenbrockConfig, RosenbrockN, StiffSystem};
use crate::physics::Plate;

/// What a step may change besides the motion: the series (re-basings) and the counters.
pub struct StepCtx<'a> {
    pub series: &'a mut SeriesSum,
    pub frame: &'a Frame,
    pub counters: &'a mut Counters,
    /// Largest `y_hi - y_lo` of a step.
    pub max_spread: f64,
}

impl StepCtx<'_> {
    /// Re-bases the series at `y` and counts it.
    #[inline]
    fn rebase_series(&mut self, y: f64) {
        self.series.rebase(y);
        *self.counters.series_rebases.get_or_insert(0) += 1;
    }
    /// Re-bases the series at `y` if `y` is more than half the radius away from its base
    /// (a step from there could leave the disc). Returns whether it did.
    #[inline]
    fn recentre(&mut self, y: f64) -> bool {
        if (y - self.series.base()).abs() > 0.5 * self.series.radius() {
            self.rebase_series(y);
            true
        } else {
            false
        }
    }
}

/// How the plate moves between events.
pub trait Motion: Clone + std::fmt::Debug + Serialize + DeserializeOwned + Send + 'static {
    /// `true` for the kinematic drive (friction reported as the bond force).
    const KINEMATIC: bool;
    /// Plate position at the current local time `tau`.
    fn y(&self, tau: f64) -> f64;
    /// The lag `X - V t` now (0 for the kinematic drive).
    fn lag(&self, tau: f64, frame: &Frame) -> f64;
    /// Plate velocity now.
    fn velocity(&self, series: &SeriesSum, frame: &Frame, tau: f64) -> f64;
    /// Starts a piece (segment) at `tau`.
    fn open_piece(&mut self, tau: f64, series: &SeriesSum, frame: &Frame);
    /// Takes one step from `tau` towards `target` (never past it); `tau` is not moved: the
    /// caller ends the step with [`Motion::finish`].
    fn step(&mut self, ctx: &mut StepCtx<'_>, tau: f64, target: f64) -> Result<Step, EngineError>;
    /// Position at `s` inside the last step.
    fn y_at(&mut self, s: f64) -> Result<f64, EngineError>;
    /// Ends the last step at `s` (its end, or an event inside it) and accumulates its
    /// statistics up to `s`.
    fn finish(&mut self, step: &Step, s: f64, series: &SeriesSum) -> Result<(), EngineError>;
    /// The statistics of the piece from its start to `tau`.
    fn segment(&self, tau: f64, frame: &Frame, plate: &Plate, series: &SeriesSum) -> Option<Segment>;
    /// The frame moved by `(dtau, dy)`; the current local time becomes 0.
    fn rebase(&mut self, dtau: f64, dy: f64);
    /// Work counters (integrator steps).
    fn sync_counters(&self, counters: &mut Counters);
}

/// The bond force as the plate's right-hand side sees it: the series, or its local cubic
/// (chosen once per step, [`RosenbrockPlate::step`]).
trait BondForce {
    fn force(&self, y: f64) -> f64;
    fn force_and_stiffness(&self, y: f64) -> (f64, f64);
}

impl BondForce for SeriesSum {
    #[inline]
    fn force(&self, y: f64) -> f64 {
        SeriesSum::force(self, y)
    }
    #[inline]
    fn force_and_stiffness(&self, y: f64) -> (f64, f64) {
        SeriesSum::force_and_stiffness(self, y)
    }
}

impl BondForce for LocalCubic {
    #[inline]
    fn force(&self, y: f64) -> f64 {
        LocalCubic::force(self, y)
    }
    #[inline]
    fn force_and_stiffness(&self, y: f64) -> (f64, f64) {
        LocalCubic::force_and_stiffness(self, y)
    }
}

/// Part of the series' error budget `rtol kappa l0 max(N, 1)` a step's local cubic may use:
/// its remainder `r4 d^4` over the step's excursion `d`.
const CUBIC_SHARE: f64 = 1.0 / 16.0;
/// The local cubic is used when the step's expected excursion (velocity times the proposed
/// step) is at most this fraction of the excursion the cubic allows.
const CUBIC_MARGIN: f64 = 0.25;

/// Largest dimension of the plate's ODE: `[u, W]`.
const DIM: usize = 2;

/// The plate equation in the lag `u = X - V t` and `w = Xd - V`, with the series force at
/// `y = u + V t - lag_ref`: state `[u, W]` (`W = tau_w w`), or `[u]` when `M = 0`
/// (`dynamic = false`). In these variables the drive's force `K u` has no cancellation (in
/// `y`, `K (y - V t)` loses `K eps |y|`, which at `K = 1e9` exceeds any velocity tolerance),
/// and the tolerance on `u` is one on the friction `-K u`.
struct System<'a, F: BondForce> {
    series: &'a F,
    plate: Plate,
    lag_ref: f64,
    dynamic: bool,
    /// `1 / tau_w` (the state holds `W = tau_w w`), and `tau_w / M` (`M > 0`) or `1 / eta`
    /// (`M = 0`): the right-hand side multiplies, no division.
    inv_tau_w: f64,
    scale: f64,
}

impl<F: BondForce> System<'_, F> {
    #[inline]
    fn y(&self, u: f64, t: f64) -> f64 {
        position(u, t, self.plate.v, self.lag_ref)
    }
}

/// The plate's position `y = u + V t - lag_ref` in the frame from the lag `u`, summed as
/// `u + (V t - lag_ref)`: inside a step, `u` is the only operand on the critical path of a
/// stage (`V t - lag_ref` is known before the stage argument).
#[inline]
fn position(u: f64, t: f64, v: f64, lag_ref: f64) -> f64 {
    u + (v * t - lag_ref)
}

impl<F: BondForce> StiffSystem for System<'_, F> {
    /// `u' = w`, `M w' = -(eta (w + V) + S + K u)` (in `W = tau_w w`); overdamped:
    /// `u' = -(S + K u)/eta - V`.
    #[inline]
    fn rhs(&mut self, t: f64, s: &[f64], d: &mut [f64]) {
        let fb = self.series.force(self.y(s[0], t));
        self.fill_rhs(fb, s, d);
    }

    /// `d/du` of the plate rows is `-(S' + K) / M` (or `/ eta`), `d/dw = -eta/M`; the time
    /// enters only through `S(u + V t - lag_ref)`: `d/dt = -S' V / M` (or `/ eta`).
    #[inline]
    fn jacobian(&mut self, t: f64, s: &[f64], j: &mut [f64], dt: &mut [f64]) {
        let (_, ds) = self.series.force_and_stiffness(self.y(s[0], t));
        self.fill_jacobian(ds, j, dt);
    }

    /// Both at once from one pass over the series (`S` and `S'` by one Horner loop).
    #[inline]
    fn rhs_and_jacobian(&mut self, t: f64, s: &[f64], d: &mut [f64], j: &mut [f64], dt: &mut [f64]) {
        let (fb, ds) = self.series.force_and_stiffness(self.y(s[0], t));
        self.fill_rhs(fb, s, d);
        self.fill_jacobian(ds, j, dt);
    }
}

impl<F: BondForce> System<'_, F> {
    /// The right-hand side at state `s` with bond force `fb`.
    #[inline]
    fn fill_rhs(&self, fb: f64, s: &[f64], d: &mut [f64]) {
        // The plate equation's net force (`Plate::net_force`), divided by `M` (or `eta`) as a
        // multiplication by the precomputed `scale`.
        let u = s[0];
        let p = &self.plate;
        if self.dynamic {
            let w = s[1] * self.inv_tau_w;
            d[0] = w;
            d[1] = p.net_force(u, w + p.v, fb) * self.scale;
        } else {
            d[0] = p.net_force(u, 0.0, fb) * self.scale - p.v;
        }
    }

    /// The Jacobian and `df/dt` with the series' stiffness `ds = S'`.
    #[inline]
    fn fill_jacobian(&self, ds: f64, j: &mut [f64], dt: &mut [f64]) {
        let (p, c) = (&self.plate, self.scale);
        if self.dynamic {
            j[0] = 0.0;
            j[1] = self.inv_tau_w;
            j[2] = -(ds + p.k) * c;
            j[3] = -p.eta * c * self.inv_tau_w;
            dt[0] = 0.0;
            dt[1] = -ds * p.v * c;
        } else {
            j[0] = -(ds + p.k) * c;
            dt[0] = -ds * p.v * c;
        }
    }
}

/// Retakes of one step (validity or spread) before giving up.
const MAX_RETAKES: u32 = 200;
/// Retakes for the spread (weak bonds) before a wider step is accepted.
const LOOSE_AFTER: u32 = 20;

/// The dynamic plate: Rosenbrock on `[u, W]` (`[u]` when `M = 0`), `u = X - V t` the lag,
/// `W = tau_w (Xd - V)`; the piece's statistics from the dense output and the force balance
/// ([`RosenbrockPlate::segment`]).
///
/// The velocity is held in length units, scaled by its own time scale
/// `tau_w = min(M / eta, sqrt(M / (K + kappa N)))`: an error `dw` in the velocity moves the
/// plate by at most about `tau_w dw` before the plate's damping (or, undamped, its
/// oscillation) takes it back, so the one tolerance `atol + rtol |.|` applied to `u` and `W`
/// is a tolerance on the position. Without the scaling a stiff plate (M/eta = 1e-11)
/// would resolve every event's velocity transient, invisible in the position, to `atol`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RosenbrockPlate {
    plate: Plate,
    /// `M > 0`: the state is `[u, W]`; else `[u]`.
    dynamic: bool,
    tau_w: f64,
    ode: RosenbrockN<DIM>,
    state: [f64; DIM],
    /// State before the last step (restored when a step is retaken).
    saved: [f64; DIM],
    /// `lag_ref` of the frame: `y = u + V tau - lag_ref`.
    lag_ref: f64,
    /// Local time of the state (the last step's end, or the event inside it).
    tau: f64,
    /// Start of the piece: time, lag `u0` and scaled velocity `W0`.
    tau0: f64,
    u0: f64,
    w0: f64,
    /// `int (u - u0)` and `int (u - u0)^2` over the piece so far.
    l1: f64,
    l2: f64,
    /// Whether steps may evaluate the series' local cubic (on; off only in tests comparing
    /// the two). Not serialised.
    #[serde(skip, default = "on")]
    cubic: bool,
    /// Steps are Taylor series in time ([`super::taylor`]) instead of RODAS4: chosen once
    /// per run when the plate is not stiff on the time scale of the events
    /// ([`RosenbrockPlate::new`]).
    taylor: bool,
    /// The last Taylor step: its series and start. Not serialised (a checkpoint is taken
    /// between steps).
    #[serde(skip)]
    series_in_time: TimeSeries,
    #[serde(skip)]
    step_start: f64,
    /// Degree of the force polynomial the next Taylor step asks for first: one more than the
    /// last step's series needed. A hint only (the series' coefficients do not depend on it,
    /// [`force_terms`]), so not serialised.
    #[serde(skip)]
    degree_hint: usize,
    /// Taylor steps taken and retaken.
    taylor_steps: u64,
    taylor_retakes: u64,
}

/// The plate takes Taylor steps when its fastest rate times the mean time between events
/// is at most this: then one step of order up to [`ORDER`] spans an event gap at the
/// tolerances the scenes use, where RODAS4 (order 4) needs several.
const TAYLOR_STIFFNESS: f64 = 4.0;
/// The force's Taylor coefficients at `y0` (`force[j] = S^(j)(y0)/j!`) up to a degree of at
/// least `degree`, rounded up to one of three (`derivatives_at` works in whole fixed-size
/// arrays): the degree written. Each coefficient is the same whatever the degree asked, so
/// a series in time built on them is too, up to the order the degree reaches.
#[inline]
fn force_terms(series: &SeriesSum, y0: f64, degree: usize, force: &mut [f64; ORDER + 1]) -> usize {
    match degree {
        0..=4 => {
            put(force, series.derivatives_at::<5>(y0));
            4
        }
        5..=7 => {
            put(force, series.derivatives_at::<8>(y0));
            7
        }
        _ => {
            put(force, series.derivatives_at::<{ ORDER - 1 }>(y0));
            ORDER - 2
        }
    }
}

/// `force[..M] = d`, element by element: register moves (in the README's `release` build
/// `copy_from_slice` compiles to a call to the C library's `memcpy`, once per plate step).
#[inline(always)]
#[allow(clippy::manual_memcpy)] // the suggested `copy_from_slice` is the call this avoids
fn put<const M: usize>(force: &mut [f64; ORDER + 1], d: [f64; M]) {
    const { assert!(M <= ORDER + 1) };
    for i in 0..M {
        force[i] = d[i];
    }
}
/// How far (in radii) the plate may stray from the series' base before a Taylor step
/// re-bases it, and how far ahead of the plate the new base goes: fewer re-bases as it
/// grows, more steps halved at the disc's far edge (on Fig. 1, 0.75 and 0.9 cost 1.3 % and
/// 0.6 % more instructions; docs/engines.md).
const LEAD: f64 = 0.85;

fn on() -> bool {
    true
}

impl RosenbrockPlate {
    /// `kappa_n = kappa N`, the junctions' largest stiffness (`d f^x / dx <= kappa`);
    /// `event_rate = N max(k0, kon0)`, the scene's largest event rate of strong bonds (a
    /// lower bound for weak ones). The plate takes Taylor steps when its fastest rate,
    /// `eta/M + sqrt((K + kappa N)/M)` (or `(K + kappa N)/eta` overdamped), is at most
    /// `TAYLOR_STIFFNESS` times `event_rate`: the events then come faster than the plate's
    /// own time scales, and a step spans an event gap. Otherwise (a stiff plate, or no
    /// events at all) RODAS4, which is L-stable.
    pub fn new(
        plate: Plate,
        kappa_n: f64,
        rtol: f64,
        atol: f64,
        event_rate: f64,
    ) -> Result<RosenbrockPlate, EngineError> {
        let dynamic = plate.mass != 0.0;
        let dim = if dynamic { 2 } else { 1 };
        let k = plate.k + kappa_n;
        let mut tau_w = if plate.eta > 0.0 { plate.mass / plate.eta } else { f64::INFINITY };
        if k > 0.0 {
            tau_w = tau_w.min((plate.mass / k).sqrt());
        }
        if !(tau_w.is_finite() && tau_w > 0.0) {
            tau_w = 1.0;
        }
        let cfg = RosenbrockConfig { rtol, atol, ..RosenbrockConfig::default() };
        let ode = RosenbrockN::with_config(dim, cfg).map_err(|e| ode_error(e, 0.0, rtol))?;
        let fastest = if dynamic { plate.eta / plate.mass + (k / plate.mass).sqrt() } else { k / plate.eta };
        let taylor = event_rate > 0.0 && fastest.is_finite() && fastest <= TAYLOR_STIFFNESS * event_rate;
        // At rest at X = 0: u = 0, W = tau_w (0 - V).
        let mut state = [0.0; DIM];
        if dynamic {
            state[1] = -tau_w * plate.v;
        }
        Ok(RosenbrockPlate {
            plate,
            dynamic,
            tau_w,
            ode,
            state,
            saved: state,
            lag_ref: 0.0,
            tau: 0.0,
            tau0: 0.0,
            u0: 0.0,
            w0: state[1],
            l1: 0.0,
            l2: 0.0,
            cubic: true,
            taylor,
            series_in_time: TimeSeries::default(),
            step_start: 0.0,
            degree_hint: 0,
            taylor_steps: 0,
            taylor_retakes: 0,
        })
    }
    /// The ODE's dimension: 2 (`[u, W]`), or 1 (`[u]`) for the overdamped plate. Derived,
    /// not stored: a checkpoint cannot make it disagree with the state's length.
    #[inline]
    fn dim(&self) -> usize {
        if self.dynamic { 2 } else { 1 }
    }
    #[inline]
    fn y_of(&self, u: f64, tau: f64) -> f64 {
        position(u, tau, self.plate.v, self.lag_ref)
    }

    /// The plate's ODE with the bond force `f`.
    #[inline]
    fn system<'a, F: BondForce>(&self, f: &'a F) -> System<'a, F> {
        let p = &self.plate;
        System {
            series: f,
            plate: *p,
            lag_ref: self.lag_ref,
            dynamic: self.dynamic,
            inv_tau_w: 1.0 / self.tau_w,
            scale: if self.dynamic { self.tau_w / p.mass } else { 1.0 / p.eta },
        }
    }

    /// The series' local cubic at the step's start `y0` ([`SeriesSum::taylor_at`] over the
    /// rest of the disc, `room = radius - |y0 - base|`) and the excursions it allows
    /// ([`Reach`]: `e <= room` with `r4 e^4 <= CUBIC_SHARE rtol kappa l0 max(N, 1)`; `r4`
    /// bounds `|S''''|/24` over `|z - y0| <= room`, so over `|z - y0| <= e` too). `None` (the
    /// series is evaluated) when the step's expected excursion, `|velocity| h` with `h` the
    /// proposed step, is more than `CUBIC_MARGIN` of what it allows: few junctions, or
    /// large steps.
    fn local_cubic(
        &self,
        series: &SeriesSum,
        y0: f64,
        tau: f64,
        target: f64,
        rtol: f64,
    ) -> Option<(LocalCubic, Reach)> {
        let room = series.radius() - (y0 - series.base()).abs();
        if room.is_nan() || room <= 0.0 {
            return None;
        }
        let (c, r4) = series.taylor_at(y0, room);
        if !(r4.is_finite() && c.iter().all(|x| x.is_finite())) {
            return None;
        }
        let reach = Reach { room, r4, tol: CUBIC_SHARE * rtol * series.scale() };
        let v = if self.dynamic {
            self.state[1] / self.tau_w + self.plate.v
        } else {
            self.plate.overdamped_velocity(self.state[0], c[0])
        };
        let h = self.ode.h_proposal().map_or(target - tau, |h| h.min(target - tau));
        if reach.allows((v * h).abs() / CUBIC_MARGIN) { Some((LocalCubic { at: y0, c }, reach)) } else { None }
    }
}

impl RosenbrockPlate {
    /// One Taylor step ([`super::taylor`]) from `tau` towards `target`: the series in time
    /// from the state and the bond force's derivatives at the start, the step as long as
    /// its last two terms allow (the whole way when they do), then bounds of `y` over it:
    /// `y0 + [min(0, b1 h), max(0, b1 h)] +- (sum_(k>=2) |u_k| h^k + tol_u)` (`b1 = u'(0) +
    /// V`), widened by round-off. The step is halved while those bounds leave the series'
    /// disc (after re-basing the series at `y0` once) or, for weak bonds, are wider than
    /// `max_spread`; halving needs no new series. The series is re-based ahead of the plate
    /// once the plate is more than `LEAD` radii from the base (at `y0 +- LEAD radius`, on
    /// the side the plate has moved to).
    fn taylor_step(&mut self, ctx: &mut StepCtx<'_>, tau: f64, target: f64) -> Result<Step, EngineError> {
        let (rtol, atol) = (self.ode.config().rtol, self.ode.config().atol);
        let p = self.plate;
        let u0 = self.state[0];
        let w0 = if self.dynamic { self.state[1] / self.tau_w } else { 0.0 };
        let tol = Tol { u: atol + rtol * u0.abs(), w: (atol + rtol * self.state[1].abs()) / self.tau_w };
        let y0 = self.y_of(u0, tau);
        // Past `LEAD` of the radius, the series moves `LEAD` of its radius ahead of the
        // plate, in the direction it came: a plate that keeps going crosses `2 LEAD` radii
        // before the next re-base, and a step from within `LEAD` of the base may span the
        // remaining `1 - LEAD` of the radius (a longer one is halved or re-based at `y0`).
        let off = y0 - ctx.series.base();
        if off.abs() > LEAD * ctx.series.radius() {
            ctx.rebase_series(y0 + LEAD * ctx.series.radius().copysign(off));
        }
        let mut retakes = 0u32;
        loop {
            // The degree the last step needed, plus one; all of it only when that falls short.
            let full = target - tau;
            let first = if self.dynamic { 2 } else { 1 };
            let mut force = [0.0; ORDER + 1];
            let degree = force_terms(ctx.series, y0, self.degree_hint, &mut force);
            let plant = Plant { mass: p.mass, eta: p.eta, k: p.k, v: p.v, force: &force, degree };
            let mut ts = TimeSeries::of(&plant, u0, w0, full, tol);
            if !ts.converged && degree < ORDER - 2 {
                let degree = force_terms(ctx.series, y0, ORDER, &mut force);
                let plant = Plant { mass: p.mass, eta: p.eta, k: p.k, v: p.v, force: &force, degree };
                ts = TimeSeries::of(&plant, u0, w0, full, tol);
            }
            self.degree_hint = ts.order + 1 - first;
            // Every coefficient enters the last one through a product or a sum (the
            // recurrence's `eta (K+1) u_(K+1)` and `K u_K` terms are there even when `eta`
            // or `K` is 0: `0 inf` is NaN), so a NaN or an infinity anywhere shows in it.
            let last = ts.u[ts.order];
            if !last.is_finite() {
                return Err(EngineError::NonFinite { t: ctx.frame.time(tau), quantity: "plate series", value: last });
            }
            let mut h = if ts.converged { full } else { ts.step_within(full, tol, self.dynamic) };
            let b1 = ts.u[1] + p.v;
            let (base, r) = (ctx.series.base(), ctx.series.radius());
            // Retakes of this series: halved while too wide, until a re-base needs a new one.
            loop {
                let r2 = ts.curvature_bound(h) + tol.u;
                let (lo, hi) = (y0 + (b1 * h).min(0.0) - r2, y0 + (b1 * h).max(0.0) + r2);
                let (lo, hi) = (lo - 4.0 * f64::EPSILON * lo.abs(), hi + 4.0 * f64::EPSILON * hi.abs());
                let valid = lo >= base - r && hi <= base + r;
                let tight = hi - lo <= ctx.max_spread || retakes >= LOOSE_AFTER;
                if valid && tight {
                    let t = if h >= full { target } else { tau + h };
                    self.series_in_time = ts;
                    self.step_start = tau;
                    self.tau = t;
                    self.taylor_steps += 1;
                    return Ok(Step { s0: tau, s1: t, y_lo: lo, y_hi: hi, cubic_error: 0.0 });
                }
                retakes += 1;
                self.taylor_retakes += 1;
                if retakes > MAX_RETAKES || h.is_nan() || h <= 0.0 {
                    return Err(EngineError::StepSizeUnderflow { t: ctx.frame.time(tau), h, rtol });
                }
                if !valid && y0 != base {
                    ctx.rebase_series(y0);
                    break;
                }
                let mut factor: f64 = 0.5;
                if !tight {
                    factor = factor.min(0.5 * ctx.max_spread / (hi - lo));
                }
                h *= factor;
            }
        }
    }
}

/// The excursions `e` from its centre over which a local cubic stands for the series:
/// `e <= room` (inside the series' disc) and `r4 e^4 <= tol` (its remainder within its
/// share of the tolerance). Tested as written, without taking the fourth root.
#[derive(Clone, Copy, Debug)]
struct Reach {
    room: f64,
    r4: f64,
    tol: f64,
}

impl Reach {
    #[inline]
    fn allows(&self, e: f64) -> bool {
        let e2 = e * e;
        e <= self.room && self.r4 * (e2 * e2) <= self.tol
    }
}

impl Motion for RosenbrockPlate {
    const KINEMATIC: bool = false;
    #[inline]
    fn y(&self, tau: f64) -> f64 {
        self.y_of(self.state[0], tau)
    }
    #[inline]
    fn lag(&self, _tau: f64, _frame: &Frame) -> f64 {
        self.state[0]
    }
    fn velocity(&self, series: &SeriesSum, _frame: &Frame, tau: f64) -> f64 {
        let p = &self.plate;
        if self.dynamic {
            self.state[1] / self.tau_w + p.v
        } else {
            let u = self.state[0];
            p.overdamped_velocity(u, series.force(self.y_of(u, tau)))
        }
    }
    fn open_piece(&mut self, tau: f64, _series: &SeriesSum, _frame: &Frame) {
        self.tau0 = tau;
        self.tau = tau;
        self.u0 = self.state[0];
        self.w0 = self.state[1];
        self.l1 = 0.0;
        self.l2 = 0.0;
        self.ode.reset();
    }
    fn step(&mut self, ctx: &mut StepCtx<'_>, tau: f64, target: f64) -> Result<Step, EngineError> {
        if self.taylor {
            return self.taylor_step(ctx, tau, target);
        }
        if ctx.recentre(self.y(tau)) {
            self.ode.reset();
        }
        let rtol = self.ode.config().rtol;
        self.saved = self.state;
        let n = self.dim();
        let mut retakes = 0;
        // The local cubic is tried until a step of it leaves the excursion it allows.
        let mut try_cubic = self.cubic;
        loop {
            let mut t = tau;
            let y0 = self.y_of(self.state[0], tau);
            let cubic = if try_cubic { self.local_cubic(ctx.series, y0, tau, target, rtol) } else { None };
            let stepped = match &cubic {
                Some((lc, _)) => {
                    let mut sys = self.system(lc);
                    self.ode.step(&mut sys, &mut t, &mut self.state[..n], target)
                }
                None => {
                    let mut sys = self.system(&*ctx.series);
                    self.ode.step(&mut sys, &mut t, &mut self.state[..n], target)
                }
            };
            stepped.map_err(|e| ode_error(e, ctx.frame.time(tau), rtol))?;
            let (ulo, uhi) = self.ode.component_bounds(0).map_err(|e| ode_error(e, ctx.frame.time(tau), rtol))?;
            // y = u + V s - lag_ref with V >= 0: bounded by the u bounds at the two ends.
            let (lo, hi) = (self.y_of(ulo, tau), self.y_of(uhi, t));
            let (lo, hi) = (lo - 4.0 * f64::EPSILON * lo.abs(), hi + 4.0 * f64::EPSILON * hi.abs());
            let (base, r) = (ctx.series.base(), ctx.series.radius());
            let valid = lo >= base - r && hi <= base + r;
            // After LOOSE_AFTER retakes a wider step is accepted: the envelope stays valid
            // (only less tight), and a spread below what the plate can resolve (an
            // overflowing rate exponent) becomes an immediate rupture in the thinning.
            let tight = hi - lo <= ctx.max_spread || retakes >= LOOSE_AFTER;
            // The cubic's remainder `r4 e^4` over the step's excursion `e`, if within its `d`.
            let (in_cubic, cubic_error) = match cubic {
                Some((_, reach)) => {
                    let e = (hi - y0).max(y0 - lo).max(0.0);
                    (reach.allows(e), reach.r4 * (e * e) * (e * e) / ctx.series.scale())
                }
                None => (true, 0.0),
            };
            if valid && tight && in_cubic {
                self.tau = t;
                return Ok(Step { s0: tau, s1: t, y_lo: lo, y_hi: hi, cubic_error });
            }
            retakes += 1;
            if retakes > MAX_RETAKES {
                return Err(EngineError::StepSizeUnderflow { t: ctx.frame.time(tau), h: t - tau, rtol });
            }
            // Restore the state before the step and retake it: shorter when it left the
            // disc or was too wide; with the series, at the same size, when it left the
            // cubic's excursion.
            self.state = self.saved;
            let mut factor: f64 = if valid && tight { 1.0 } else { 0.5 };
            if !valid && y0 != base {
                ctx.rebase_series(y0);
            }
            if !tight {
                factor = factor.min(0.5 * ctx.max_spread / (hi - lo));
            }
            if !in_cubic {
                try_cubic = false;
            }
            self.ode.reset();
            self.ode.set_h_proposal((t - tau) * factor);
        }
    }
    #[inline]
    fn y_at(&mut self, s: f64) -> Result<f64, EngineError> {
        if self.taylor {
            return Ok(self.y_of(self.series_in_time.at(s - self.step_start), s));
        }
        let u = self.ode.dense_component(0, s).map_err(|e| ode_error(e, s, 0.0))?;
        Ok(self.y_of(u, s))
    }
    fn finish(&mut self, step: &Step, s: f64, _series: &SeriesSum) -> Result<(), EngineError> {
        if self.taylor {
            let ts = &self.series_in_time;
            let ds = s - self.step_start;
            let (u, w) = ts.at_with_slope(ds);
            self.state[0] = u;
            if self.dynamic {
                self.state[1] = w * self.tau_w;
            }
            let (i1, i2) = ts.integrals(ds, self.u0);
            self.l1 += i1;
            self.l2 += i2;
            self.tau = s;
            return Ok(());
        }
        if s < step.s1 {
            let n = self.dim();
            self.ode.dense(s, &mut self.state[..n]).map_err(|e| ode_error(e, s, 0.0))?;
        }
        let (i1, i2) = self.ode.dense_integrals(0, s, self.u0).map_err(|e| ode_error(e, s, 0.0))?;
        self.l1 += i1;
        self.l2 += i2;
        self.tau = s;
        Ok(())
    }
    /// The piece's statistics: friction `-K u` from `L = int (u - u0)`, `L2 = int (u -
    /// u0)^2` (exact integrals of the dense output); the bond force from the plate
    /// equation integrated over the piece (an identity of the ODE, no quadrature of `S`):
    /// `int S = -(M (w1 - w0) + eta (u1 - u0) + eta V h + K (u0 h + L))`, or without the
    /// `M` term for the overdamped plate. Accuracy (docs/engines.md, "Statistics of a piece
    /// (tilted law, dynamic plate)"): each term carries the integrator's error of `u1`, `w1`, `L`, so the
    /// piece's mean has an error of about `(M / tau_w + eta) tol / h + K tol`, `tol` the
    /// tolerance on `u` and `W`; it is large only for pieces much shorter than the plate's
    /// time scales, and it telescopes: over consecutive pieces the `M w` and `eta u` terms
    /// sum to their values at the ends, so a window's mean is as accurate as the friction's.
    /// Round-off: `eps (M |w| / h + eta |Xd| + K |u|)` per piece, negligible beside that.
    fn segment(&self, tau: f64, frame: &Frame, plate: &Plate, _series: &SeriesSum) -> Option<Segment> {
        let h = tau - self.tau0;
        if h <= 0.0 {
            return None;
        }
        let (l1, l2) = (self.l1, self.l2);
        let k = plate.k;
        let du = self.state[0] - self.u0;
        let mut momentum = plate.eta * (du + plate.v * h);
        if self.dynamic {
            momentum += plate.mass * ((self.state[1] - self.w0) / self.tau_w);
        }
        let int_s = -(momentum + k * (self.u0 * h + l1));
        Some(Segment {
            t0: frame.time(self.tau0),
            t1: frame.time(tau),
            friction: -k * (self.u0 + l1 / h),
            friction_m2: k * k * (l2 - l1 * l1 / h).max(0.0),
            bond_force: int_s / h,
            // eta (X1 - X0) / h = eta (V + (u1 - u0) / h).
            viscous: plate.eta * (plate.v + du / h),
            attached: 0,
        })
    }
    fn rebase(&mut self, dtau: f64, dy: f64) {
        self.lag_ref += dy - self.plate.v * dtau;
        self.tau0 -= dtau;
        self.tau -= dtau;
        self.ode.reset();
    }
    fn sync_counters(&self, c: &mut Counters) {
        let st = self.ode.stats();
        c.ode_steps = Some(st.accepted + self.taylor_steps);
        c.ode_rejected = Some(st.rejected + self.taylor_retakes);
    }
}

/// Gauss–Legendre nodes and weights on `[-1, 1]`, 8 points (exact for degree 15).
const GL8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

/// The kinematic drive: `y = V tau` in the local frame, no ODE.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DrivenPlate {
    v: f64,
    tau0: f64,
    /// `S` at the start of the piece, and `int (S - S0) ds`, `int (S - S0)^2 ds` since.
    f0: f64,
    i1: f64,
    i2: f64,
}

impl DrivenPlate {
    pub fn new(v: f64) -> DrivenPlate {
        DrivenPlate { v, tau0: 0.0, f0: 0.0, i1: 0.0, i2: 0.0 }
    }
}

impl Motion for DrivenPlate {
    const KINEMATIC: bool = true;
    #[inline]
    fn y(&self, tau: f64) -> f64 {
        self.v * tau
    }
    #[inline]
    fn lag(&self, _tau: f64, _frame: &Frame) -> f64 {
        0.0
    }
    #[inline]
    fn velocity(&self, _series: &SeriesSum, _frame: &Frame, _tau: f64) -> f64 {
        self.v
    }
    fn open_piece(&mut self, tau: f64, series: &SeriesSum, _frame: &Frame) {
        self.tau0 = tau;
        self.f0 = series.force(self.y(tau));
        self.i1 = 0.0;
        self.i2 = 0.0;
    }
    fn step(&mut self, ctx: &mut StepCtx<'_>, tau: f64, target: f64) -> Result<Step, EngineError> {
        let y = self.y(tau);
        if self.v == 0.0 {
            return Ok(Step { s0: tau, s1: target, y_lo: y, y_hi: y, cubic_error: 0.0 });
        }
        ctx.recentre(y);
        let room = ctx.series.base() + ctx.series.radius() - y;
        let dy = room.min(ctx.max_spread);
        let mut s1 = target.min(tau + dy / self.v);
        if s1 <= tau {
            // A spread too small to resolve in time: a wider step (the thinning then sees an
            // overflowing envelope, an immediate rupture).
            s1 = target.min(tau + room / self.v);
        }
        Ok(Step { s0: tau, s1, y_lo: y, y_hi: self.y(s1), cubic_error: 0.0 })
    }
    #[inline]
    fn y_at(&mut self, s: f64) -> Result<f64, EngineError> {
        Ok(self.y(s))
    }
    fn finish(&mut self, step: &Step, s: f64, series: &SeriesSum) -> Result<(), EngineError> {
        let h = s - step.s0;
        if h <= 0.0 || self.v == 0.0 {
            // A plate at rest keeps S = S0 (the segment's mean), with no spread.
            return Ok(());
        }
        let (ya, yb) = (self.y(step.s0), self.y(s));
        // int (S - S0) ds = (int S dy) / V - S0 h, exact for the series.
        self.i1 += series.integral(ya, yb) / self.v - self.f0 * h;
        let (mid, half) = (0.5 * (ya + yb), 0.5 * (yb - ya));
        let q: f64 = GL8
            .iter()
            .map(|&(x, w)| {
                let d = series.force(mid + half * x) - self.f0;
                w * d * d
            })
            .sum();
        self.i2 += 0.5 * h * q;
        Ok(())
    }
    fn segment(&self, tau: f64, frame: &Frame, _plate: &Plate, _series: &SeriesSum) -> Option<Segment> {
        let h = tau - self.tau0;
        if h <= 0.0 {
            return None;
        }
        let mean = self.f0 + self.i1 / h;
        Some(Segment {
            t0: frame.time(self.tau0),
            t1: frame.time(tau),
            friction: mean,
            friction_m2: (self.i2 - self.i1 * self.i1 / h).max(0.0),
            bond_force: mean,
            viscous: 0.0,
            attached: 0,
        })
    }
    fn rebase(&mut self, dtau: f64, _dy: f64) {
        self.tau0 -= dtau;
    }
    fn sync_counters(&self, _c: &mut Counters) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::{ForceLaw, Tilted};

    fn ctx<'a>(series: &'a mut SeriesSum, frame: &'a Frame, counters: &'a mut Counters) -> StepCtx<'a> {
        StepCtx { series, frame, counters, max_spread: f64::INFINITY }
    }

    /// No junctions, overdamped: `u(t) = -(V eta / K) (1 - exp(-K t / eta))` (the plate
    /// starts at rest at the drive), and the piece's quadratures match its integrals.
    #[test]
    fn dynamic_plate_follows_the_closed_form() {
        let plate = Plate { mass: 0.0, eta: 2.0, k: 3.0, v: 0.5 };
        let law = Tilted { kappa: 0.1, l0: 1.0 };
        let mut series = SeriesSum::new(law, 1e-10);
        let frame = Frame::new(plate.v);
        let mut counters = Counters::default();
        let mut m = RosenbrockPlate::new(plate, 0.0, 1e-10, 1e-12, 0.0).unwrap();
        m.open_piece(0.0, &series, &frame);
        let (mut tau, target) = (0.0, 2.0);
        while tau < target {
            let step = m.step(&mut ctx(&mut series, &frame, &mut counters), tau, target).unwrap();
            m.finish(&step, step.s1, &series).unwrap();
            tau = step.s1;
        }
        let r = plate.k / plate.eta;
        let u = -(plate.v / r) * (1.0 - (-r * target).exp());
        assert!((m.lag(tau, &frame) - u).abs() < 1e-9, "{} vs {u}", m.lag(tau, &frame));
        // Mean friction -K mean(u): int u = -(V/r) (T - (1 - e^{-rT})/r).
        let int_u = -(plate.v / r) * (target - (1.0 - (-r * target).exp()) / r);
        let seg = m.segment(tau, &frame, &plate, &series).unwrap();
        assert!((seg.friction - (-plate.k * int_u / target)).abs() < 1e-8, "{}", seg.friction);
        // No junctions: the force balance's bond force is `-(eta du_T + K int du) / T` in
        // the errors `du` of the numerical plate, at most what the two checks above allow.
        let allowed = plate.eta * 1e-9 / target + 1e-8;
        assert!(seg.bond_force.abs() < allowed, "{} vs {allowed}", seg.bond_force);
    }

    /// The bond force of a piece from the force balance equals an independent quadrature
    /// of `S` along the same numerical plate (8-point Gauss–Legendre on the series over each
    /// step's dense output), where the balance's terms are large beside `int S`: an
    /// undamped heavy plate whose drive force `K u` is ~1e3 times the bond force, and an
    /// overdamped plate with the same junctions. The two differ only by the integrator's
    /// global errors `E_u`, `E_W` of `u` and `W`: `|dB| <= M |dW| / tau_w + eta |du| + (K +
    /// S'_max) T E_u`; the allowance takes `E <= steps (atol + rtol max|state|)` (local
    /// errors added up, no amplification over less than a period).
    #[test]
    fn force_balance_bond_force_matches_a_quadrature() {
        let law = Tilted { kappa: 0.1, l0: 1.0 };
        let anchors = [-0.3, -0.1, 0.0, 0.05, 0.2];
        for plate in
            [Plate { mass: 1e4, eta: 0.0, k: 100.0, v: 0.5 }, Plate { mass: 0.0, eta: 300.0, k: 100.0, v: 0.5 }]
        {
            let (rtol, atol) = (1e-10, 1e-12);
            let mut series = SeriesSum::new(law, rtol);
            for c in anchors {
                series.add(c);
            }
            let frame = Frame::new(plate.v);
            let mut counters = Counters::default();
            let kappa_n = law.kappa * anchors.len() as f64;
            let mut m = RosenbrockPlate::new(plate, kappa_n, rtol, atol, 0.0).unwrap();
            m.open_piece(0.0, &series, &frame);
            let (mut tau, target) = (0.0, 3.0);
            let (mut quad, mut big, mut state_max) = (0.0, 0.0f64, 0.0f64);
            while tau < target {
                let step = m.step(&mut ctx(&mut series, &frame, &mut counters), tau, target).unwrap();
                m.finish(&step, step.s1, &series).unwrap();
                let (mid, half) = (0.5 * (step.s0 + step.s1), 0.5 * (step.s1 - step.s0));
                for &(x, w) in &GL8 {
                    let y = m.y_at(mid + half * x).unwrap();
                    quad += half * w * series.force(y);
                }
                tau = step.s1;
                big = big.max((plate.k * m.lag(tau, &frame)).abs());
                state_max = state_max.max(m.state[0].abs()).max(m.state[1].abs());
            }
            let seg = m.segment(tau, &frame, &plate, &series).unwrap();
            let mean = quad / target;
            assert!(big > 500.0 * mean.abs(), "the test needs K u >> S: {big} vs {mean}");
            let steps = m.ode.stats().accepted as f64;
            let e = steps * (atol + rtol * state_max);
            let tau_w = if m.dynamic { m.tau_w } else { f64::INFINITY };
            let allowed = (plate.mass / tau_w + plate.eta) * e / target + (plate.k + kappa_n) * e;
            let diff = (seg.bond_force - mean).abs();
            assert!(diff <= allowed, "M = {}: {} vs {mean}, allowed {allowed}", plate.mass, seg.bond_force);
            assert!(allowed < 1e-5 * big, "the allowance is too loose to test anything: {allowed}");
        }
    }

    /// Kinematic drive past one junction: the segment's mean is `int S dt / h` (compared
    /// with a fine Simpson rule on the law itself), its spread `int (S - mean)^2 dt`. In
    /// both modes of the series (direct mode's radius is twice the bins', so its steps are
    /// up to twice as long and it re-bases half as often).
    #[test]
    fn kinematic_segment_integrates_the_bond_force() {
        for direct in [false, true] {
            kinematic_segment(direct);
        }
    }

    fn kinematic_segment(direct: bool) {
        let law = Tilted { kappa: 0.3, l0: 1.0 };
        let mut series = if direct { SeriesSum::direct(law, 1e-12) } else { SeriesSum::new(law, 1e-12) };
        let c = -0.4;
        series.add(c);
        let frame = Frame::new(0.7);
        let mut counters = Counters::default();
        let mut m = DrivenPlate::new(0.7);
        m.open_piece(0.0, &series, &frame);
        let (mut tau, target) = (0.0, 3.0);
        while tau < target {
            let step = m.step(&mut ctx(&mut series, &frame, &mut counters), tau, target).unwrap();
            assert!(step.y_hi - series.base() <= series.radius() * (1.0 + 1e-12));
            m.finish(&step, step.s1, &series).unwrap();
            tau = step.s1;
        }
        assert!(counters.series_rebases.unwrap() >= if direct { 5 } else { 10 });
        let n = 20_000;
        let f = |t: f64| law.force_x(0.7 * t - c);
        let simpson = |g: &dyn Fn(f64) -> f64| {
            let h = target / n as f64;
            (0..=n)
                .map(|i| {
                    g(i as f64 * h)
                        * if i == 0 || i == n {
                            1.0
                        } else if i % 2 == 1 {
                            4.0
                        } else {
                            2.0
                        }
                })
                .sum::<f64>()
                * h
                / 3.0
        };
        let mean = simpson(&f) / target;
        let m2 = simpson(&|t| (f(t) - mean).powi(2));
        let seg = m.segment(tau, &frame, &Plate { mass: 1.0, eta: 1.0, k: 1.0, v: 0.7 }, &series).unwrap();
        assert!((seg.friction - mean).abs() < 1e-9 * mean.abs(), "{} vs {mean}", seg.friction);
        assert!((seg.friction_m2 - m2).abs() < 1e-7 * m2, "{} vs {m2}", seg.friction_m2);
        assert_eq!(seg.viscous, 0.0);
    }

    /// Taylor steps against RODAS4 on the same plate and force: Fig. 1's plate (and an
    /// overdamped one) over 150 junctions spread as a sliding contact spreads them, stepped
    /// to event-like targets 1/30 apart to `t = 20`, across several re-bases. The lag and
    /// velocity agree within the two integrators' summed local tolerances (each step's
    /// `atol + rtol |state|`; the plate is damped, so local errors do not grow), the Taylor
    /// plate takes about one step per target, and RODAS4 several.
    #[test]
    fn taylor_plate_matches_rodas() {
        let law = Tilted { kappa: 0.1, l0: 1.0 };
        let (rtol, atol) = (1e-10, 1e-12);
        for plate in
            [Plate { mass: 75.0, eta: 75.0, k: 150.0, v: 0.5 }, Plate { mass: 0.0, eta: 75.0, k: 150.0, v: 0.5 }]
        {
            let mut base = SeriesSum::new(law, rtol);
            for i in 0..150 {
                base.add(-6.0 + 6.0 * (i as f64 / 150.0).powi(2));
            }
            base.rebase(0.0);
            let frame = Frame::new(plate.v);
            let run = |event_rate: f64| {
                let mut series = base.clone();
                let mut counters = Counters::default();
                let mut m = RosenbrockPlate::new(plate, law.kappa * 150.0, rtol, atol, event_rate).unwrap();
                assert_eq!(m.taylor, event_rate > 0.0);
                m.open_piece(0.0, &series, &frame);
                let (mut tau, mut steps, mut e) = (0.0, 0u64, 0.0);
                for target in (1..=600).map(|i| i as f64 / 30.0) {
                    while tau < target {
                        let step = m.step(&mut ctx(&mut series, &frame, &mut counters), tau, target).unwrap();
                        m.finish(&step, step.s1, &series).unwrap();
                        tau = step.s1;
                        steps += 1;
                        e += atol + rtol * m.state[0].abs().max(m.state[1].abs());
                    }
                }
                let v = m.velocity(&series, &frame, tau);
                (m.lag(tau, &frame), v, steps, e, counters.series_rebases.unwrap_or(0))
            };
            let (u_t, v_t, steps_t, e_t, rebases) = run(30.0);
            let (u_r, v_r, steps_r, e_r, _) = run(0.0);
            assert!(rebases >= 10, "{rebases} re-bases: the test should cross several");
            assert!(steps_t <= 700, "{steps_t} Taylor steps for 600 targets");
            assert!(steps_r > steps_t, "RODAS4 {steps_r} steps, Taylor {steps_t}");
            let allowed = e_t + e_r;
            assert!((u_t - u_r).abs() <= allowed, "M = {}: lag {u_t} vs {u_r}, allowed {allowed}", plate.mass);
            let tau_w = if plate.mass > 0.0 { (plate.mass / (plate.k + 15.0)).sqrt().min(1.0) } else { 1.0 };
            assert!((v_t - v_r).abs() <= allowed / tau_w, "M = {}: velocity {v_t} vs {v_r}", plate.mass);
            println!(
                "M = {}: u {u_t:e} {u_r:e} v {v_t:e} {v_r:e}, allowed {allowed:.2e}; steps {steps_t} vs {steps_r}",
                plate.mass
            );
        }
    }

    /// The local cubic against the series: an overdamped plate over 3000 junctions, stepped
    /// to event-like targets `1e-4` apart (so most steps take the cubic: its excursion
    /// `d ~ l0 (rtol/31)^(1/4) ~ 1e-3` here) and then in one long stretch (steps too long for
    /// it: the series). Every cubic step's remainder is within `CUBIC_SHARE rtol`, and the
    /// lag agrees with the same plate on the series alone within twice the integrators'
    /// summed local tolerances plus the remainder's effect, `|du| <= T max(r4 e^4) / eta`
    /// (`u' = -(S + K u)/eta - V`, the force perturbed by at most that, and `d/du` of the
    /// right-hand side negative). In both modes of the series (direct mode's wider disc
    /// gives a larger `r4`, so a slightly shorter reach).
    #[test]
    fn local_cubic_plate_matches_the_series_plate() {
        for direct in [false, true] {
            local_cubic_plate(direct);
        }
    }

    /// `local_cubic_plate_matches_the_series_plate` with the series in bins or direct mode.
    fn local_cubic_plate(direct: bool) {
        let law = Tilted { kappa: 0.1, l0: 1.0 };
        let plate = Plate { mass: 0.0, eta: 50.0, k: 10.0, v: 0.5 };
        let (rtol, atol) = (1e-10, 1e-12);
        let mut base = if direct { SeriesSum::direct(law, rtol) } else { SeriesSum::new(law, rtol) };
        for i in 0..3000 {
            base.add(-0.9 + 0.6 * (i as f64 / 3000.0));
        }
        base.rebase(0.0);
        let frame = Frame::new(plate.v);
        let run = |cubic: bool| {
            let mut series = base.clone();
            let mut counters = Counters::default();
            let mut m = RosenbrockPlate::new(plate, law.kappa * 3000.0, rtol, atol, 0.0).unwrap();
            m.cubic = cubic;
            m.open_piece(0.0, &series, &frame);
            let (mut tau, mut used, mut series_steps, mut worst, mut state_max) = (0.0, 0, 0, 0.0f64, 0.0f64);
            for target in (1..=2000).map(|i| i as f64 * 1e-4).chain([1.0]) {
                while tau < target {
                    let step = m.step(&mut ctx(&mut series, &frame, &mut counters), tau, target).unwrap();
                    m.finish(&step, step.s1, &series).unwrap();
                    tau = step.s1;
                    if step.cubic_error > 0.0 {
                        used += 1;
                    } else {
                        series_steps += 1;
                    }
                    worst = worst.max(step.cubic_error);
                    state_max = state_max.max(m.state[0].abs());
                }
            }
            let steps = m.ode.stats().accepted as f64;
            (m.lag(tau, &frame), used, series_steps, worst, steps * (atol + rtol * state_max), series.scale())
        };
        let (u_c, used, series_steps, worst, e_c, scale) = run(true);
        let (u_s, used_s, _, _, e_s, _) = run(false);
        assert_eq!(used_s, 0);
        assert!(used >= 1500, "cubic steps {used}");
        assert!(series_steps >= 1, "the long stretch should fall back to the series");
        assert!(worst > 0.0 && worst <= CUBIC_SHARE * rtol, "remainder {worst}");
        let allowed = e_c + e_s + 1.0 * worst * scale / plate.eta;
        assert!((u_c - u_s).abs() <= allowed, "{u_c} vs {u_s}, allowed {allowed}");
        println!(
            "direct mode {direct}: cubic steps {used}, series steps {series_steps}, |du| {:.3e}, allowed {allowed:.3e}",
            (u_c - u_s).abs()
        );
    }

    /// A step that leaves the cubic's excursion is retaken on the series: a heavy plate at
    /// rest (velocity 0, so the expected excursion is 0 and the cubic is tried) under a large
    /// junction force, with a loose `atol` and a proposed first step of 0.05, accelerates
    /// beyond the cubic's `d` (~1.3e-3 at `rtol = 1e-10`) in its first step. That step comes
    /// back with `cubic_error == 0` after two accepted integrator steps (the cubic's, then
    /// the series' at the same size) and no re-basing, and its excursion `e` has
    /// `r4 e^4` above the cubic's share of the budget (so the cubic's attempt, along nearly
    /// the same path, could not be accepted).
    #[test]
    fn step_leaving_the_cubic_is_retaken_on_the_series() {
        let law = Tilted { kappa: 1.0, l0: 1.0 };
        let plate = Plate { mass: 1.0, eta: 0.1, k: 1.0, v: 0.01 };
        let (rtol, atol) = (1e-10, 1e-4);
        let mut series = SeriesSum::new(law, rtol);
        for _ in 0..1000 {
            series.add(-0.5);
        }
        series.rebase(0.0);
        let frame = Frame::new(plate.v);
        let mut counters = Counters::default();
        let mut m = RosenbrockPlate::new(plate, law.kappa * 1000.0, rtol, atol, 0.0).unwrap();
        m.open_piece(0.0, &series, &frame);
        m.ode.set_h_proposal(0.05);
        let (mut tau, mut retaken) = (0.0, 0);
        for _ in 0..5 {
            let (before, rebases) = (m.ode.stats().accepted, counters.series_rebases);
            let y0 = m.y(tau);
            let step = m.step(&mut ctx(&mut series, &frame, &mut counters), tau, 1.0).unwrap();
            m.finish(&step, step.s1, &series).unwrap();
            tau = step.s1;
            if m.ode.stats().accepted == before + 2 && counters.series_rebases == rebases {
                assert_eq!(step.cubic_error, 0.0);
                let e = (step.y_hi - y0).max(y0 - step.y_lo);
                let (_, r4) = series.taylor_at(y0, series.radius() - (y0 - series.base()).abs());
                assert!(r4 * e.powi(4) > CUBIC_SHARE * rtol * series.scale(), "retaken within the cubic's range");
                retaken += 1;
            }
        }
        assert!(retaken >= 1, "no step left the cubic");
    }
}
