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

use rand_distr::{Distribution, Exp1};
use serde::{Deserialize, Serialize};

use super::contract::{Moved, Stepper, Target, WeakRuptures};
use crate::engine::EngineError;
use crate::engine::exact::core::clocks::ArrayQueue;
use crate::engine::exact::core::engine::Exact;
use crate::engine::exact::core::frame::Frame;
use crate::engine::exact::core::state::Core;
use crate::engine::exact::rupture::{Hazard, LinearRate};
use crate::observe::{Observer, Segment};
use crate::ode::{Dop853, Dop853Config, OdeError, OdeSystem};
use crate::physics::{Bond, ForceLaw, Plate};
use crate::rng::UniformSource;
use crate::scene::Scene;

/// Index of the plate's local position `y` in the integrated state (the linear engine's `y`).
const Y: usize = 0;

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
    attached: &'a [crate::engine::exact::core::bags::Attached],
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
pub type ExactDirect<L, B> = Exact<DirectStepper<L, B>, Hazard<L, B>>;

/// The direct stepper: the law and bond kind, the integrated state and DOP853.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct DirectStepper<L: ForceLaw, B: Bond> {
    law: L,
    bond: B,
    layout: Layout,
    /// Integrated state at the core's local time.
    state: Vec<f64>,
    /// Start of the current piece.
    tau0: f64,
    y0: f64,
    lag0: f64,
    /// Weak bonds: the hazard level of the next rupture.
    hazard_target: f64,
    ode: Dop853,
}

impl<L: ForceLaw, B: Bond> ExactDirect<L, B> {
    /// The engine for `scene` with the law and bond kind given (built by `scene::laws` for
    /// a scene's own; any [`ForceLaw`] works).
    pub fn new(scene: &Scene, law: L, bond: B) -> Result<Self, EngineError> {
        let mut core = Core::new(scene, 2)?;
        core.counters.ode_steps = Some(0);
        core.counters.ode_rejected = Some(0);
        let layout = Layout::new(core.plate.mass == 0.0, B::IS_WEAK);
        let cfg = Dop853Config {
            rtol: scene.exact.rtol,
            atol: scene.exact.atol,
            h_max: step_cap(&core.plate, law, core.n),
            ..Dop853Config::default()
        };
        let ode = Dop853::with_config(layout.dim, cfg).map_err(|e| ode_error(e, 0.0, scene.exact.rtol))?;
        let kernel = DirectStepper {
            law,
            bond,
            layout,
            state: vec![0.0; layout.dim],
            tau0: 0.0,
            y0: 0.0,
            lag0: 0.0,
            hazard_target: 0.0,
            ode,
        };
        Ok(Exact::start(core, kernel, Hazard { law, bond }))
    }
}

impl<L: ForceLaw, B: Bond> DirectStepper<L, B> {
    fn system<'a>(&self, core: &'a Core<ArrayQueue>) -> System<'a, L, B> {
        System { attached: &core.bags.attached, p: self.params(core) }
    }

    fn params(&self, core: &Core<ArrayQueue>) -> Params<L, B> {
        Params {
            law: self.law,
            bond: self.bond,
            plate: core.plate,
            frame: core.frame,
            lag0: self.lag0,
            layout: self.layout,
            rate_cap: self.rate_cap(),
        }
    }

    fn rate_cap(&self) -> f64 {
        Hazard { law: self.law, bond: self.bond }.rate_cap()
    }

    /// Weak bonds: the junction that ruptures now, chosen with probability `r_i / sum r`.
    fn pick_weak(&self, core: &mut Core<ArrayQueue>) -> usize {
        let y = self.state[Y];
        let cap = self.rate_cap();
        let rate = |c: f64| self.bond.k_off(self.law.tension(y - c)).min(cap);
        let total: f64 = core.bags.attached.iter().map(|a| rate(a.c)).sum();
        let mut u = core.rng.uniform() * total;
        let last = core.bags.n_attached() - 1;
        for (slot, a) in core.bags.attached.iter().enumerate() {
            let r = rate(a.c);
            if u < r {
                return slot;
            }
            u -= r;
        }
        last
    }

    /// A rupture now, chosen by [`DirectStepper::pick_weak`] (a candidate, always accepted).
    fn weak_rupture(&self, core: &mut Core<ArrayQueue>) -> Moved {
        core.count_candidate();
        Moved::Ruptured(self.pick_weak(core))
    }

    fn sync_ode_counters(&self, core: &mut Core<ArrayQueue>) {
        let st = self.ode.stats();
        core.counters.ode_steps = Some(st.accepted);
        core.counters.ode_rejected = Some(st.rejected);
    }

    /// Moves the current state to `tau` inside the last accepted step (dense output).
    fn seek(&mut self, core: &mut Core<ArrayQueue>, tau: f64) -> Result<(), EngineError> {
        self.ode.dense(tau, &mut self.state).map_err(|e| ode_error(e, core.frame.time(tau), 0.0))?;
        core.tau = tau;
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

impl<L: ForceLaw, B: Bond> Stepper for DirectStepper<L, B> {
    type Queue = ArrayQueue;
    type Rate = LinearRate;
    const KINEMATIC: bool = false;
    const WEAK_RUPTURES: WeakRuptures = WeakRuptures::Own;

    #[inline]
    fn rate(&self) -> LinearRate {
        LinearRate
    }

    fn start(&mut self, core: &mut Core<ArrayQueue>) {
        self.open_piece(core);
    }

    #[inline]
    fn y(&self, _core: &Core<ArrayQueue>) -> f64 {
        self.state[Y]
    }

    /// Plate velocity now (the overdamped plate's from the forces).
    fn velocity(&self, core: &Core<ArrayQueue>) -> f64 {
        let s = &self.state;
        match self.layout.vel {
            Some(iv) => s[iv],
            None => {
                let sys = self.system(core);
                let fb = sys.forces(s[Y]).0;
                sys.overdamped_velocity(fb, core.frame.lag(s[Y], core.tau))
            }
        }
    }

    fn bond_force(&self, core: &Core<ArrayQueue>) -> f64 {
        self.system(core).forces(self.state[Y]).0
    }

    /// DOP853 steps towards `target`. Weak bonds: a rupture where the hazard reaches its
    /// level (located on the dense output); a rate that grows too fast for the local time's
    /// resolution moves the time origin, or at `tau = 0` is an immediate rupture.
    fn step<O: Observer>(
        &mut self,
        core: &mut Core<ArrayQueue>,
        to: Target,
        _obs: &mut O,
    ) -> Result<Moved, EngineError> {
        let target = to.tau;
        if core.tau < target {
            let rtol = self.ode.config().rtol;
            let t_before = core.tau;
            let mut tau = core.tau;
            let mut sys = System { attached: &core.bags.attached, p: self.params(core) };
            let result = self.ode.step(&mut sys, &mut tau, &mut self.state, target);
            if let Err(e) = result {
                // Weak bonds: a rupture rate that grows on a time scale below the
                // resolution of the local time (the step floor is 10 eps |tau|, and the
                // step is rejected ever smaller near tau = 0) is
                // resolved by moving the time origin here (a new piece; the hazard
                // level is redrawn, which memorylessness allows). At tau = 0 it is
                // beyond any resolution: as for an overflowing rate, the rupture is
                // immediate (docs/model.md, "Equations", item 6), the junction chosen by its rate now.
                let unresolved = matches!(e, OdeError::StepSizeUnderflow { .. } | OdeError::TooManyRejections { .. });
                if B::IS_WEAK && unresolved && core.bags.n_attached() > 0 {
                    core.finite("X", self.state[Y])?;
                    if core.tau == 0.0 {
                        return Ok(self.weak_rupture(core));
                    }
                    return Ok(Moved::Rebase);
                }
                return Err(ode_error(e, core.frame.time(t_before), rtol));
            }
            core.tau = tau;
            self.sync_ode_counters(core);
            // Weak bonds: did the hazard reach its level inside this step?
            if let Some(ih) = self.layout.h {
                if self.state[ih] >= self.hazard_target {
                    let hit = self
                        .ode
                        .locate_component(ih, self.hazard_target)
                        .map_err(|e| ode_error(e, core.frame.time(t_before), rtol))?
                        .unwrap_or(core.tau);
                    self.seek(core, hit)?;
                    core.finite("X", self.state[Y])?;
                    return Ok(self.weak_rupture(core));
                }
            }
            if core.tau < target {
                return Ok(Moved::Short);
            }
        }
        core.finite("X", self.state[Y])?;
        Ok(Moved::There)
    }

    /// Reports the piece up to the current time as a segment.
    fn close<O: Observer>(&mut self, core: &mut Core<ArrayQueue>, _t: f64, obs: &mut O) -> Result<(), EngineError> {
        let h = core.tau - self.tau0;
        if h <= 0.0 {
            return Ok(());
        }
        let l = self.layout;
        let s = &self.state;
        let (li, l2) = (s[l.l], s[l.l2]);
        let (k, frame) = (core.plate.k, &core.frame);
        obs.segment(&Segment {
            t0: frame.time(self.tau0),
            t1: frame.time(core.tau),
            friction: -k * (self.lag0 + li / h),
            friction_m2: k * k * (l2 - li * li / h).max(0.0),
            bond_force: s[l.b] / h,
            viscous: core.plate.eta * (s[Y] - self.y0) / h,
            attached: core.bags.n_attached() as u64,
        });
        Ok(())
    }

    /// Starts a new piece at the current state: quadratures to zero, a fresh hazard level
    /// (weak bonds), and the integrator told the right-hand side has changed.
    fn open_piece(&mut self, core: &mut Core<ArrayQueue>) {
        let l = self.layout;
        self.state[l.l] = 0.0;
        self.state[l.l2] = 0.0;
        self.state[l.b] = 0.0;
        self.tau0 = core.tau;
        self.y0 = self.state[Y];
        self.lag0 = core.frame.lag(self.y0, core.tau);
        if let Some(ih) = l.h {
            self.state[ih] = 0.0;
            self.hazard_target = Exp1.sample(&mut core.rng);
        }
        self.ode.reset();
    }

    #[inline]
    fn shifted(&mut self, _core: &Core<ArrayQueue>, _dtau: f64, _dy: f64) {
        self.state[Y] = 0.0;
    }

    #[inline]
    fn tension(&self, x: f64) -> f64 {
        self.law.tension(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::exact::rupture::EXPONENT_CAP;
    use crate::engine::exact::rupture::hazard::CAP_RATE_FACTOR;

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
