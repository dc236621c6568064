//! `summary.json`: the run's window statistics, counters and resolved parameters.

use serde::{Deserialize, Serialize};

use crate::engine::Counters;
use crate::observe::regime::numerics::Numerics;
use crate::observe::regime::{Oscillation, Regime};
use crate::rng::PeriodExceeded;
use crate::scene::{EngineKind, Scene};

/// Everything a run reports at its end.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    /// Scene name (file stem).
    pub scene: String,
    pub engine: EngineKind,
    pub seed: u64,
    /// Number of junctions `N`.
    pub n: u64,
    pub t_end: f64,
    pub t_warmup: f64,
    /// Time-weighted mean of `F = K (V t - X)` over `[t_warmup, t_end]` (kinematic plate: of `F_b`).
    pub friction_mean: f64,
    /// Time-weighted standard deviation of `F` over the window.
    pub friction_std: f64,
    /// `friction_mean / N`.
    pub friction_per_junction: f64,
    /// Time-weighted mean of `F_b`.
    pub bond_force_mean: f64,
    /// Time-weighted mean of `eta Xd`.
    pub viscous_force_mean: f64,
    /// Time-weighted mean of `n(t)`.
    pub attached_fraction_mean: f64,
    /// Mean tension at rupture over the window (weak bonds only).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub rupture_force_mean: Option<f64>,
    /// Standard error of `rupture_force_mean`.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub rupture_force_sem: Option<f64>,
    /// `smooth` or `stick-slip` (docs/model.md, "Regime criterion"), or `unstable` when a
    /// fixed-step run's plate step failed (docs/stability.md, "Unstable runs").
    pub regime: Regime,
    /// Whole periods of the oscillation in the window when stick-slip, else 0.
    pub stick_slip_cycles: u64,
    /// What the regime criterion measured: `oscillation_period`, `oscillation_amplitude`
    /// (half the mean peak-to-trough range of the friction per period, force),
    /// `oscillation_coherence`, `amplitude_cv` and `amplitude_cv_limit`, `junction_noise`,
    /// and the supporting signs `stuck_fraction` and `slips`.
    #[serde(flatten)]
    pub oscillation: Oscillation,
    /// Fixed-step runs with a plate equation: the plate step's growth factor per step,
    /// the largest stable `dt`, why the run is unstable (if it is) and the longest locked
    /// period-2 oscillation.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub stability: Option<Numerics>,
    /// Fixed-step runs on the Park–Miller generator that drew more numbers than its period
    /// `2^31 - 2` (its stream repeated): `draws` and `period`. Absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub rng_period_exceeded: Option<PeriodExceeded>,
    #[serde(flatten)]
    pub counters: Counters,
    /// Wall-clock time of the run in seconds.
    pub wall_seconds: f64,
    /// The resolved scene (every parameter, defaults filled in).
    pub parameters: Scene,
}

impl Summary {
    /// Engine name as a string.
    pub fn engine_name(&self) -> &'static str {
        match self.engine {
            EngineKind::Exact => "exact",
            EngineKind::Fixed => "fixed",
        }
    }
}
