//! Plate integrators of the fixed-step scheme (step 3): one step of
//! `M Xdd + eta Xd + F_b + K (X - V t) = 0` from `t_n` to `t_{n+1} = t_n + dt`, with the
//! junction states `q` frozen over the step.
//!
//! The integrator is a plain enum matched once per step, not a type parameter: the match
//! costs one predictable branch per step against `O(N)` junction work, so making it
//! generic would only multiply the monomorphised engines (and compile time) by four.

use serde::{Deserialize, Serialize};

use crate::physics::Plate;
use crate::scene::IntegratorKind;

/// The plate update of one step. `Overdamped` is forced when `M = 0`, whatever the scene's
/// `fixed.integrator` says.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Integrator {
    /// `Xd_{n+1} = Xd_n + dt a_n`, then `X_{n+1} = X_n + dt Xd_{n+1}`.
    SemiImplicitEuler,
    /// `X_{n+1} = X_n + dt Xd_n`, `Xd_{n+1} = Xd_n + dt a_n`.
    ExplicitEuler,
    /// Velocity Verlet, damping trapezoidal (implicit); see [`Integrator::step`].
    VelocityVerlet,
    /// `M = 0`: `v_n = -(F_b + K u_n) / eta`, `X_{n+1} = X_n + dt v_n`, `Xd_{n+1} = v_n`.
    Overdamped,
    /// `plate.kinematic`: no plate equation, `X_{n+1} = V t_{n+1}` (from the step count),
    /// `Xd = V`.
    Kinematic,
}

impl Integrator {
    /// The plate update of `scene`: [`Integrator::Kinematic`] for `plate.kinematic`, else
    /// [`Integrator::new`] of its option and mass.
    pub fn of_scene(scene: &crate::scene::Scene) -> Integrator {
        if scene.plate.kinematic {
            Integrator::Kinematic
        } else {
            Integrator::new(scene.fixed.integrator, scene.plate.mass)
        }
    }

    /// The integrator for a scene's option and plate mass.
    pub fn new(kind: IntegratorKind, mass: f64) -> Integrator {
        if mass == 0.0 {
            return Integrator::Overdamped;
        }
        match kind {
            IntegratorKind::SemiImplicitEuler => Integrator::SemiImplicitEuler,
            IntegratorKind::ExplicitEuler => Integrator::ExplicitEuler,
            IntegratorKind::VelocityVerlet => Integrator::VelocityVerlet,
        }
    }
}

/// The plate after one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlateStep {
    /// `X_{n+1}`.
    pub x: f64,
    /// `Xd_{n+1}`.
    pub v: f64,
    /// The velocity whose viscous force `eta v` balances the step's forces: `Xd_n` for the
    /// inertial integrators, the step's overdamped velocity `v_n` for `M = 0`.
    pub viscous_v: f64,
}

/// Where the plate is at `t_n` and what acts on it during the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlateState {
    /// `t_n = n dt`.
    pub t: f64,
    /// `t_{n+1} = (n + 1) dt`.
    pub t_next: f64,
    /// `X_n`.
    pub x: f64,
    /// `Xd_n`.
    pub v: f64,
    /// `F_b` from the step's `q` and `x_i(t_n)`.
    pub bond_force: f64,
}

impl Integrator {
    /// One plate step. `bond_force_moved(dX)` is `F_b` with the same `q` and the attached
    /// junctions moved by `dX` (`x_i + dX`); only velocity Verlet calls it.
    ///
    /// With the lag `u = X - V t` and `a_n = -(eta Xd_n + F_b + K u_n) / M`:
    /// - semi-implicit Euler: `Xd_{n+1} = Xd_n + dt a_n`, `X_{n+1} = X_n + dt Xd_{n+1}`;
    /// - explicit Euler: `X_{n+1} = X_n + dt Xd_n`, `Xd_{n+1} = Xd_n + dt a_n`;
    /// - velocity Verlet: `X_{n+1} = X_n + dt Xd_n + dt^2/2 a_n`; `F_b'` = `F_b` at the new
    ///   junction positions; the velocity is the trapezoidal rule with the linear damping
    ///   term taken implicitly (so `eta` adds no stability limit):
    ///   `Xd_{n+1} (1 + dt eta/(2M)) = Xd_n + dt/2 (a_n + (-F_b' - K u_{n+1}) / M)`;
    /// - overdamped (`M = 0`): `v_n = -(F_b + K u_n) / eta`, `X_{n+1} = X_n + dt v_n`,
    ///   `Xd_{n+1} = v_n`;
    /// - kinematic: `X_{n+1} = V t_{n+1}`, `Xd_{n+1} = V`, no viscous force.
    #[inline]
    pub fn step(self, p: &Plate, dt: f64, s: PlateState, bond_force_moved: impl FnOnce(f64) -> f64) -> PlateStep {
        let lag = s.x - p.v * s.t;
        match self {
            Integrator::SemiImplicitEuler => {
                let v = s.v + dt * p.acceleration(lag, s.v, s.bond_force);
                PlateStep { x: s.x + dt * v, v, viscous_v: s.v }
            }
            Integrator::ExplicitEuler => {
                let v = s.v + dt * p.acceleration(lag, s.v, s.bond_force);
                PlateStep { x: s.x + dt * s.v, v, viscous_v: s.v }
            }
            Integrator::VelocityVerlet => {
                let a = p.acceleration(lag, s.v, s.bond_force);
                let x = s.x + dt * s.v + 0.5 * dt * dt * a;
                let fb_new = bond_force_moved(x - s.x);
                let lag_new = x - p.v * s.t_next;
                let rhs = s.v + 0.5 * dt * (a + (-fb_new - p.k * lag_new) / p.mass);
                let v = rhs / (1.0 + 0.5 * dt * p.eta / p.mass);
                PlateStep { x, v, viscous_v: s.v }
            }
            Integrator::Overdamped => {
                let v = p.overdamped_velocity(lag, s.bond_force);
                PlateStep { x: s.x + dt * v, v, viscous_v: v }
            }
            Integrator::Kinematic => PlateStep { x: p.v * s.t_next, v: p.v, viscous_v: 0.0 },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: Plate = Plate { mass: 2.0, eta: 0.5, k: 3.0, v: 0.25 };

    fn state() -> PlateState {
        PlateState { t: 1.0, t_next: 1.1, x: 0.4, v: -0.2, bond_force: 0.7 }
    }

    #[test]
    fn euler_steps_by_hand() {
        let s = state();
        let a = -(0.5 * -0.2 + 0.7 + 3.0 * (0.4 - 0.25)) / 2.0;
        let si = Integrator::SemiImplicitEuler.step(&P, 0.1, s, |_| unreachable!());
        assert_eq!(si.v, -0.2 + 0.1 * a);
        assert_eq!(si.x, 0.4 + 0.1 * si.v);
        assert_eq!(si.viscous_v, -0.2);
        let ex = Integrator::ExplicitEuler.step(&P, 0.1, s, |_| unreachable!());
        assert_eq!(ex.v, si.v);
        assert_eq!(ex.x, 0.4 + 0.1 * -0.2);
    }

    #[test]
    fn verlet_by_hand() {
        let s = state();
        let dt = 0.1;
        let a = -(0.5 * -0.2 + 0.7 + 3.0 * (0.4 - 0.25)) / 2.0;
        let x = 0.4 + dt * -0.2 + 0.5 * dt * dt * a;
        // A linear bond force with stiffness 2: F_b' = F_b + 2 dX.
        let vv = Integrator::VelocityVerlet.step(&P, dt, s, |dx| 0.7 + 2.0 * dx);
        assert!((vv.x - x).abs() < 1e-16);
        let fb1 = 0.7 + 2.0 * (x - 0.4);
        let a1_without_damping = (-fb1 - 3.0 * (x - 0.25 * 1.1)) / 2.0;
        // The implicit damping: v1 = v0 + dt/2 (a0 + a1_without_damping - eta v1 / M).
        let v1 = vv.v;
        let residual = v1 - (-0.2 + 0.5 * dt * (a + a1_without_damping - 0.5 * v1 / 2.0));
        assert!(residual.abs() < 1e-16, "{residual}");
    }

    #[test]
    fn kinematic_follows_the_drive() {
        let k = Integrator::Kinematic.step(&P, 0.1, state(), |_| unreachable!());
        assert_eq!(k, PlateStep { x: 0.25 * 1.1, v: 0.25, viscous_v: 0.0 });
    }

    #[test]
    fn overdamped_uses_the_step_velocity() {
        let p = Plate { mass: 0.0, ..P };
        let s = state();
        let od = Integrator::new(IntegratorKind::VelocityVerlet, 0.0).step(&p, 0.1, s, |_| unreachable!());
        let v = -(0.7 + 3.0 * (0.4 - 0.25)) / 0.5;
        assert_eq!(od.v, v);
        assert_eq!(od.viscous_v, v);
        assert_eq!(od.x, 0.4 + 0.1 * v);
    }
}
