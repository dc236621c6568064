//! What engines report: [`Sample`]s on the output grid, [`JunctionEvent`]s and the
//! [`Segment`]s' time integrals of the observables.

use serde::{Deserialize, Serialize};

/// The state at one instant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Time `t`.
    pub t: f64,
    /// Plate position `X`.
    pub x: f64,
    /// Plate velocity `Xd`.
    pub v: f64,
    /// Driving-spring force `F = K (V t - X)` (the friction force; with a kinematic plate, `F_b`).
    pub friction: f64,
    /// Bond force `F_b = sum_i q_i f_i^x`.
    pub bond_force: f64,
    /// Number of attached junctions.
    pub attached: u64,
    /// Number of junctions `N`.
    pub n: u64,
}

impl Sample {
    /// `n(t) = attached / N`.
    pub fn attached_fraction(&self) -> f64 {
        self.attached as f64 / self.n as f64
    }
}

/// Kind of a junction event.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EventKind {
    Rupture,
    Formation,
}

impl EventKind {
    pub fn as_str(self) -> &'static str {
        match self {
            EventKind::Rupture => "rupture",
            EventKind::Formation => "formation",
        }
    }
}

/// One junction switching state.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JunctionEvent {
    /// Time of the event (for the fixed engine, the start of the step in which it flipped).
    pub t: f64,
    /// Junction index in `0..N`.
    pub junction: u32,
    pub kind: EventKind,
    /// Extension `x_i` at the event (after re-attachment rules are applied, for formations).
    pub extension: f64,
    /// Tension `f_i` at the event.
    pub tension: f64,
}

/// Time integrals of the observables over one piece `[t0, t1]` of the trajectory.
///
/// Means are `(1/h) int_{t0}^{t1} (.) dt` with `h = t1 - t0`; `friction_m2` is
/// `int (F - friction)^2 dt`, so variances combine without cancellation (Chan et al.).
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct Segment {
    pub t0: f64,
    pub t1: f64,
    /// Mean driving-spring force `F = K (V t - X)` over the segment (kinematic plate: mean `F_b`).
    pub friction: f64,
    /// `int (F - mean)^2 dt` over the segment (>= 0).
    pub friction_m2: f64,
    /// Mean bond force `F_b`.
    pub bond_force: f64,
    /// Mean viscous force `eta Xd`.
    pub viscous: f64,
    /// Attached count (constant on a segment).
    pub attached: u64,
}
