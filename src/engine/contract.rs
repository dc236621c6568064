//! The engine contract: [`Engine`] (what the runner drives), its [`Counters`], why it fails
//! ([`EngineError`]), and [`EngineVisitor`], code handed the engine a scene builds.

use serde::{Serialize, de::DeserializeOwned};

use crate::observe::{Observer, Sample};
use crate::scene::EngineKind;
use crate::scene::error::compact;

/// Counters an engine keeps; reported in `summary.json`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct Counters {
    pub ruptures: u64,
    pub formations: u64,
    /// Fixed engine: steps taken.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps: Option<u64>,
    /// Exact engine: events executed (ruptures + formations).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub events: Option<u64>,
    /// Exact engine: thinning candidates drawn (accepted or not).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub candidates: Option<u64>,
    /// Exact engine, tilted law: accepted steps of the adaptive plate integrator.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ode_steps: Option<u64>,
    /// Exact engine, tilted law: rejected steps of the adaptive plate integrator.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ode_rejected: Option<u64>,
    /// Exact engine: coordinate re-basings (long runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rebases: Option<u64>,
    /// Exact engine, tilted law, series method: re-basings of the bond-force series.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub series_rebases: Option<u64>,
    /// Exact engine, tilted law, series method: the largest bound of the series' error on
    /// the bond force over the run, relative to `kappa l0 max(N_att, 1)`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub series_error: Option<f64>,
}

/// Why an engine could not go on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EngineError {
    /// The fixed-step plate update blew up (typically `dt` beyond the stability limit).
    #[error(
        "the plate diverged at step {step} (t = {t}): {quantity} = {value:.6e}; the time step fixed.dt is probably beyond the integrator's stability limit (see `stickslip stability`)"
    )]
    Diverged { step: u64, t: f64, quantity: &'static str, value: f64 },
    /// A quantity became NaN or infinite.
    #[error("numerical trouble at t = {t}: {quantity} = {value}")]
    NonFinite { t: f64, quantity: &'static str, value: f64 },
    /// The adaptive integrator could not meet its tolerance.
    #[error(
        "the adaptive plate integrator failed at t = {}: step size {} too small for exact.rtol = {}",
        compact(t),
        compact(h),
        compact(rtol)
    )]
    StepSizeUnderflow { t: f64, h: f64, rtol: f64 },
    /// The adaptive integrator failed for another reason.
    #[error("the adaptive plate integrator failed at t = {t}: {source}")]
    Integrator {
        t: f64,
        #[source]
        source: crate::ode::OdeError,
    },
    /// The scene's force law or bond kind refused its parameters (validation refuses them first).
    #[error("{0}")]
    Parameter(#[from] crate::physics::ParamError),
    /// A large buffer could not be allocated.
    #[error(transparent)]
    OutOfMemory(#[from] crate::engine::alloc::AllocError),
    /// The plate left the bounds its step proved (weak-bond thinning's envelope would no
    /// longer dominate the rates: an acceptance above 1). An internal error, never expected.
    #[error(
        "internal error at t = {t}: the plate at y = {y} left its step's proven bounds [{lo}, {hi}], so the weak-bond thinning would not be exact"
    )]
    EnvelopeViolated { t: f64, y: f64, lo: f64, hi: f64 },
    /// The engine cannot run this scene.
    #[error("the {engine} engine cannot run this scene: {reason}")]
    Unsupported { engine: &'static str, reason: &'static str },
    /// Weak-bond thinning rejects nearly every candidate: its envelope bounds the rates far
    /// too loosely for the run to finish ([`crate::engine::exact::rupture::stalled`]).
    #[error(
        "the weak-bond rupture thinning drew {candidates} candidates for {events} events by t = {t}: its envelope exp(beta dx kappa |x|) exceeds the tilted law's rates by up to exp(beta dx kappa l0), too loose to finish at this temperature; run it with run.engine = \"fixed\", or at a higher junctions.temperature"
    )]
    ThinningStalled { t: f64, candidates: u64, events: u64 },
}

/// A method that advances a scene in time. (`Send + 'static`: an engine can be kept behind a
/// `runner::Simulation` handle.)
pub trait Engine: Serialize + DeserializeOwned + Send + 'static {
    /// Which engine this is.
    const KIND: EngineKind;
    /// Whether its bonds are weak (ruptures drawn from a force-dependent rate). The run loop
    /// keeps rupture-force statistics only then, chosen by this constant at compile time.
    const WEAK_BONDS: bool;
    /// Current time.
    fn time(&self) -> f64;
    /// The engine's fixed step, if it has one: it can only stop on multiples of it.
    fn time_step(&self) -> Option<f64>;
    /// Advances to `t_stop` and reports segments (and events, if `O::EVENTS`) to `obs`.
    ///
    /// The exact engine stops at `t_stop` exactly. The fixed engine takes whole steps and
    /// stops at the first step boundary `n dt >= t_stop` (to within `1e-9 dt`).
    fn advance<O: Observer>(&mut self, t_stop: f64, obs: &mut O) -> Result<(), EngineError>;
    /// The state now.
    fn sample(&self) -> Sample;
    /// Counters so far.
    fn counters(&self) -> Counters;
    /// Lets the engine share its work among `threads` threads (the caller's included) from
    /// now on; `1` keeps it on the caller's. The results are the same for every count. Not
    /// part of the engine's state (a deserialized engine runs on one thread until told).
    /// The default ignores it: the fixed-step engine uses it ([`super::fixed::FixedEngine`]).
    fn set_threads(&mut self, _threads: usize) {}
}

/// Something to do with an engine once its concrete type is known (a run, a resume, a bench).
pub trait EngineVisitor {
    type Output;
    fn visit<E: Engine>(self, engine: E) -> Self::Output;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step size far below 1 is shown in exponent form, not as 80 characters of zeros
    /// and digits.
    #[test]
    fn a_step_size_underflow_shows_short_numbers() {
        let e = EngineError::StepSizeUnderflow { t: 0.0, h: 4.4336561899658515e-62, rtol: 1e-10 };
        assert_eq!(
            e.to_string(),
            "the adaptive plate integrator failed at t = 0: step size 4.4336561899658515e-62 too small for exact.rtol = 0.0000000001"
        );
    }
}
