//! Plate motions of the series engine, chosen once per run.
//!
//! - [`Dynamic`]: the plate equation `M y'' + eta y' + S(y) + K lag = 0` (or `eta y' = ...`
//!   when `M = 0`) with `S` the junction force from the [`SeriesSum`], integrated by the
//!   L-stable [`Rosenbrock`] method with the analytic Jacobian, together with the
//!   quadratures of the segment statistics: `L = int (lag - lag0)`, `L2 = int (lag - lag0)^2`,
//!   `B = int S`. Stable at any stiffness: the step follows the accuracy, not `M/eta` or
//!   `sqrt(M/K)`.
//! - [`Kinematic`]: `y = V tau` exactly, no ODE and no integrator; the statistics come from
//!   [`SeriesSum::integral`] (`int S dy`) and an 8-point Gauss–Legendre rule for
//!   `int (S - S0)^2`.
//!
//! Every step keeps `|y - base| <= radius` of the series (re-basing, and retaking the step
//! if the bounds of the accepted step leave the disc) and, for weak bonds, `y_hi - y_lo <=
//! max_spread`, so the thinning envelope of the step is tight.

use serde::{Deserialize, Serialize, de::DeserializeOwned};

use super::{Rosenbrock, RosenbrockConfig, SeriesSum, StiffSystem};
use crate::engine::exact::frame::Frame;
use crate::engine::exact::tilted::ode_error;
use crate::engine::{Counters, EngineError};
use crate::observe::Segment;
use crate::physics::Plate;

/// One plate step `[s0, s1]` and proven bounds of `y` over it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    pub s0: f64,
    pub s1: f64,
    pub y_lo: f64,
    pub y_hi: f64,
}

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

/// Where each quantity sits in the integrated state.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct Layout {
    /// Velocity index (`None` for the overdamped plate).
    vel: Option<usize>,
    /// `L`; `L2 = l + 1`, `B = l + 2`.
    l: usize,
    dim: usize,
}

impl Layout {
    fn new(overdamped: bool) -> Layout {
        let (vel, l) = if overdamped { (None, 1) } else { (Some(1), 2) };
        Layout { vel, l, dim: l + 3 }
    }
}

/// The plate equation with the series force, and its quadratures.
struct System<'a> {
    series: &'a SeriesSum,
    plate: Plate,
    frame: Frame,
    lag0: f64,
    layout: Layout,
}

impl StiffSystem for System<'_> {
    fn rhs(&mut self, t: f64, s: &[f64], d: &mut [f64]) {
        let y = s[0];
        let fb = self.series.force(y);
        let lag = self.frame.lag(y, t);
        let p = &self.plate;
        match self.layout.vel {
            Some(iv) => {
                d[0] = s[iv];
                d[iv] = p.acceleration(lag, s[iv], fb);
            }
            None => d[0] = p.overdamped_velocity(lag, fb),
        }
        let dl = lag - self.lag0;
        let l = self.layout.l;
        d[l] = dl;
        d[l + 1] = dl * dl;
        d[l + 2] = fb;
    }

    /// `d/dy` of the plate rows is `-(S'(y) + K) / M` (or `/ eta`), `d/dv = -eta/M`; the
    /// explicit time dependence is through `lag = y - V t + lag_ref` only.
    fn jacobian(&mut self, t: f64, s: &[f64], j: &mut [f64], dt: &mut [f64]) {
        let (y, n) = (s[0], self.layout.dim);
        let (_, ds) = self.series.force_and_stiffness(y);
        let p = &self.plate;
        let dl = self.frame.lag(y, t) - self.lag0;
        j.iter_mut().for_each(|v| *v = 0.0);
        match self.layout.vel {
            Some(iv) => {
                j[iv] = 1.0;
                j[iv * n] = -(ds + p.k) / p.mass;
                j[iv * n + iv] = -p.eta / p.mass;
                dt[0] = 0.0;
                dt[iv] = p.k * p.v / p.mass;
            }
            None => {
                j[0] = -(ds + p.k) / p.eta;
                dt[0] = p.k * p.v / p.eta;
            }
        }
        let l = self.layout.l;
        j[l * n] = 1.0;
        j[(l + 1) * n] = 2.0 * dl;
        j[(l + 2) * n] = ds;
        dt[l] = -p.v;
        dt[l + 1] = -2.0 * dl * p.v;
        dt[l + 2] = 0.0;
    }
}

/// Retakes of one step (validity or spread) before giving up.
const MAX_RETAKES: u32 = 200;

/// The dynamic plate: Rosenbrock on `[y, v, L, L2, B]` (`[y, L, L2, B]` when `M = 0`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Dynamic {
    plate: Plate,
    layout: Layout,
    ode: Rosenbrock,
    state: Vec<f64>,
    /// State before the last step (restored when a step is retaken).
    saved: Vec<f64>,
    tau0: f64,
    y0: f64,
    lag0: f64,
}

impl Dynamic {
    pub fn new(plate: Plate, rtol: f64, atol: f64) -> Result<Dynamic, EngineError> {
        let layout = Layout::new(plate.mass == 0.0);
        let cfg = RosenbrockConfig { rtol, atol, ..RosenbrockConfig::default() };
        let ode = Rosenbrock::with_config(layout.dim, cfg).map_err(|e| ode_error(e, 0.0, rtol))?;
        Ok(Dynamic {
            plate,
            layout,
            ode,
            state: vec![0.0; layout.dim],
            saved: vec![0.0; layout.dim],
            tau0: 0.0,
            y0: 0.0,
            lag0: 0.0,
        })
    }
}

impl Motion for Dynamic {
    const KINEMATIC: bool = false;
    #[inline]
    fn y(&self, _tau: f64) -> f64 {
        self.state[0]
    }
    fn velocity(&self, series: &SeriesSum, frame: &Frame, tau: f64) -> f64 {
        match self.layout.vel {
            Some(iv) => self.state[iv],
            None => {
                let y = self.state[0];
                self.plate.overdamped_velocity(frame.lag(y, tau), series.force(y))
            }
        }
    }
    fn open_piece(&mut self, tau: f64, _series: &SeriesSum, frame: &Frame) {
        let l = self.layout.l;
        self.state[l..l + 3].iter_mut().for_each(|v| *v = 0.0);
        self.tau0 = tau;
        self.y0 = self.state[0];
        self.lag0 = frame.lag(self.y0, tau);
        self.ode.reset();
    }
    fn step(&mut self, ctx: &mut StepCtx<'_>, tau: f64, target: f64) -> Result<Step, EngineError> {
        if ctx.recentre(self.state[0]) {
            self.ode.reset();
        }
        let rtol = self.ode.config().rtol;
        self.saved.copy_from_slice(&self.state);
        let mut retakes = 0;
        loop {
            let mut t = tau;
            let mut sys = System {
                series: ctx.series,
                plate: self.plate,
                frame: *ctx.frame,
                lag0: self.lag0,
                layout: self.layout,
            };
            self.ode
                .step(&mut sys, &mut t, &mut self.state, target)
                .map_err(|e| ode_error(e, ctx.frame.time(tau), rtol))?;
            let (lo, hi) = self.ode.component_bounds(0).map_err(|e| ode_error(e, ctx.frame.time(tau), rtol))?;
            let (base, r) = (ctx.series.base(), ctx.series.radius());
            let valid = lo >= base - r && hi <= base + r;
            let tight = hi - lo <= ctx.max_spread;
            if valid && tight {
                return Ok(Step { s0: tau, s1: t, y_lo: lo, y_hi: hi });
            }
            retakes += 1;
            if retakes > MAX_RETAKES {
                return Err(EngineError::StepSizeUnderflow { t: ctx.frame.time(tau), h: t - tau, rtol });
            }
            // Restore the state before the step and retake it, shorter.
            self.state.copy_from_slice(&self.saved);
            let mut factor: f64 = 0.5;
            if !valid && self.saved[0] != base {
                ctx.rebase_series(self.saved[0]);
            }
            if !tight {
                factor = factor.min(0.5 * ctx.max_spread / (hi - lo));
            }
            self.ode.reset();
            self.ode.set_h_proposal((t - tau) * factor);
        }
    }
    #[inline]
    fn y_at(&mut self, s: f64) -> Result<f64, EngineError> {
        self.ode.dense_component(0, s).map_err(|e| ode_error(e, s, 0.0))
    }
    fn finish(&mut self, step: &Step, s: f64, _series: &SeriesSum) -> Result<(), EngineError> {
        if s < step.s1 {
            self.ode.dense(s, &mut self.state).map_err(|e| ode_error(e, s, 0.0))?;
        }
        Ok(())
    }
    fn segment(&self, tau: f64, frame: &Frame, plate: &Plate, _series: &SeriesSum) -> Option<Segment> {
        let h = tau - self.tau0;
        if h <= 0.0 {
            return None;
        }
        let l = self.layout.l;
        let s = &self.state;
        let (li, l2) = (s[l], s[l + 1]);
        let k = plate.k;
        Some(Segment {
            t0: frame.time(self.tau0),
            t1: frame.time(tau),
            friction: -k * (self.lag0 + li / h),
            friction_m2: k * k * (l2 - li * li / h).max(0.0),
            bond_force: s[l + 2] / h,
            viscous: plate.eta * (s[0] - self.y0) / h,
            attached: 0,
        })
    }
    fn rebase(&mut self, dtau: f64, dy: f64) {
        self.state[0] -= dy;
        self.y0 -= dy;
        self.tau0 -= dtau;
        self.ode.reset();
    }
    fn sync_counters(&self, c: &mut Counters) {
        let st = self.ode.stats();
        c.ode_steps = Some(st.accepted);
        c.ode_rejected = Some(st.rejected);
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
pub struct Kinematic {
    v: f64,
    tau0: f64,
    /// `S` at the start of the piece, and `int (S - S0) ds`, `int (S - S0)^2 ds` since.
    f0: f64,
    i1: f64,
    i2: f64,
}

impl Kinematic {
    pub fn new(v: f64) -> Kinematic {
        Kinematic { v, tau0: 0.0, f0: 0.0, i1: 0.0, i2: 0.0 }
    }
}

impl Motion for Kinematic {
    const KINEMATIC: bool = true;
    #[inline]
    fn y(&self, tau: f64) -> f64 {
        self.v * tau
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
            return Ok(Step { s0: tau, s1: target, y_lo: y, y_hi: y });
        }
        ctx.recentre(y);
        let room = ctx.series.base() + ctx.series.radius() - y;
        let dy = room.min(ctx.max_spread);
        let s1 = target.min(tau + dy / self.v);
        Ok(Step { s0: tau, s1, y_lo: y, y_hi: self.y(s1) })
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
