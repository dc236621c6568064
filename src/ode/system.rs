//! What every stepper shares: the system it integrates, its counters and its errors.

use serde::{Deserialize, Serialize};

/// A system of first-order ODEs `y' = f(t, y)` with a runtime dimension.
pub trait OdeSystem {
    /// Writes `f(t, y)` into `dydt` (same length as `y`). Non-finite output is detected by
    /// the integrator and reported as an error (or, inside a trial step, causes a retry with a
    /// smaller step); it never propagates into the solution.
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]);
}

/// Any `FnMut(t, y, dydt)` closure is a system.
impl<F: FnMut(f64, &[f64], &mut [f64])> OdeSystem for F {
    #[inline]
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self(t, y, dydt)
    }
}

/// Work counters of an integrator since its construction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct OdeStats {
    /// Accepted steps (including fixed steps taken with [`Dop853::step_fixed`](crate::ode::Dop853::step_fixed)).
    pub accepted: u64,
    /// Rejected step attempts: error test failed or non-finite values met.
    pub rejected: u64,
    /// Of `rejected`, the attempts rejected because a stage or the new state was non-finite.
    pub rejected_non_finite: u64,
    /// Evaluations of the right-hand side.
    pub rhs_evals: u64,
    /// Evaluations of `f(t, y)` at the start of a step because the FSAL derivative was not
    /// available: the first step, after [`Dop853::reset`](crate::ode::Dop853::reset), or when `t`/`y` were changed
    /// between steps. Each costs one RHS evaluation (included in `rhs_evals`).
    pub restarts: u64,
}

/// Why the integrator could not do what it was asked. It never panics and never returns a
/// non-finite state: on error, `t` and `y` passed to [`Dop853::step`](crate::ode::Dop853::step) are left unchanged.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OdeError {
    /// A configuration value is out of its domain.
    #[error("invalid ODE integrator setting {name} = {value}")]
    InvalidConfig { name: &'static str, value: f64 },
    /// A slice has the wrong length, or a component index is out of range.
    #[error("ODE dimension mismatch: expected {expected}, got {got}")]
    DimensionMismatch { expected: usize, got: usize },
    /// `step` was asked to go from `t` to a limit `t_max` that is not after `t`, or a time is
    /// not finite.
    #[error("invalid ODE step interval: t = {t}, t_max = {t_max}")]
    InvalidInterval { t: f64, t_max: f64 },
    /// The state handed to `step` contains a NaN or an infinity.
    #[error("non-finite ODE state at t = {t}")]
    NonFiniteState { t: f64 },
    /// The right-hand side is non-finite at the current (accepted) point: no step can help.
    #[error("non-finite ODE right-hand side at t = {t}")]
    NonFiniteRhs { t: f64 },
    /// Trial steps kept producing non-finite values; the step size was reduced to `h` (or
    /// `rejections` consecutive attempts failed) without success.
    #[error("non-finite values in ODE trial steps at t = {t}: step size reduced to {h} after {rejections} rejections")]
    NonFiniteStep { t: f64, h: f64, rejections: u32 },
    /// The step size needed to meet the tolerance fell below `10 eps |t|`: the tolerance is
    /// too tight for double precision, or the problem is singular or extremely stiff here.
    #[error("ODE step size underflow at t = {t}: h = {h}")]
    StepSizeUnderflow { t: f64, h: f64 },
    /// Too many consecutive rejected attempts within one step (see
    /// [`Dop853Config::max_consecutive_rejections`](crate::ode::Dop853Config::max_consecutive_rejections)).
    #[error("ODE step rejected {rejections} times in a row at t = {t} (last h = {h})")]
    TooManyRejections { t: f64, h: f64, rejections: u32 },
    /// Dense output was asked for before any step was accepted.
    #[error("no dense output: no step has been accepted yet")]
    NoDenseOutput,
    /// Dense output was asked for outside the last accepted step.
    #[error("dense output asked at t = {t}, outside the last step [{t_old}, {t_new}]")]
    OutsideDenseInterval { t: f64, t_old: f64, t_new: f64 },
    /// A deserialised integrator state is inconsistent (corrupt checkpoint).
    #[error("invalid ODE integrator state: {what}")]
    InvalidState { what: &'static str },
    /// An event function returned NaN or an infinity.
    #[error("non-finite event function value {value} at t = {t}")]
    NonFiniteEvent { t: f64, value: f64 },
}
