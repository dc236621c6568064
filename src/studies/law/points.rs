//! The points of a velocity-temperature map: every run's friction and regime, grouped by
//! grid point, and their aggregate across replicas.
//!
//! A point is **steady** when every replica slid smoothly; its regime is the sweep's
//! majority rule ([`Majority`]: `unstable` if any replica is, else the majority,
//! `mixed` at a tie). Means and 95 % intervals are Student-t across replicas
//! ([`crate::studies::stats`]): `t_{0.975, R-1} s / sqrt(R)`, none with one replica.

use serde::Serialize;

use super::scales::Scales;
use crate::observe::regime::Regime;
use crate::studies::stats::{ReplicaStats, t_quantile};
use crate::studies::sweep::Majority;

/// What the law needs of one run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunRecord {
    /// Time average of the total friction over the window (`friction_mean`).
    pub friction_mean: f64,
    /// `friction_mean / N`.
    pub friction_per_junction: f64,
    pub regime: Regime,
}

/// The runs of one grid point.
#[derive(Clone, Debug, PartialEq)]
pub struct PointRuns {
    /// `plate.v`.
    pub v: f64,
    /// `junctions.temperature`.
    pub t: f64,
    /// The replicas, in order.
    pub runs: Vec<RunRecord>,
}

/// A mean across replicas with its 95 % half-width and standard error (both `NaN` with
/// one replica).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Estimate {
    pub mean: f64,
    pub ci95: f64,
    pub se: f64,
}

impl Estimate {
    fn of(x: impl Iterator<Item = f64>) -> Estimate {
        let s = ReplicaStats::of(x.map(Some));
        Estimate { mean: s.mean, ci95: t_quantile(s.n as f64 - 1.0) * s.se, se: s.se }
    }
    /// The estimate scaled by `k > 0`.
    pub fn scaled(&self, k: f64) -> Estimate {
        Estimate { mean: self.mean * k, ci95: self.ci95 * k, se: self.se * k }
    }
}

/// One point of the law: model and physical values, regime.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LawPoint {
    pub v: f64,
    pub t: f64,
    /// `V l0 / t0`, m/s.
    pub slip_rate: f64,
    /// `T T_ref`, K.
    pub kelvin: f64,
    pub replicas: usize,
    /// Friction per junction (model units).
    pub friction_per_junction: Estimate,
    /// Total friction in newtons.
    pub friction_newtons: Estimate,
    /// `friction / normal load`: only for a steady point.
    pub mu: Option<Estimate>,
    pub regime: Majority,
    pub stick_slip_fraction: f64,
    pub steady: bool,
}

impl LawPoint {
    /// The aggregate of `p`'s replicas in the units of `scales`.
    pub fn new(p: &PointRuns, scales: &Scales) -> LawPoint {
        let regime = Majority::of(p.runs.iter().map(|r| r.regime));
        let steady = p.runs.iter().all(|r| r.regime == Regime::Smooth);
        let ss = p.runs.iter().filter(|r| r.regime == Regime::StickSlip).count();
        let total = Estimate::of(p.runs.iter().map(|r| r.friction_mean));
        LawPoint {
            v: p.v,
            t: p.t,
            slip_rate: scales.slip_rate(p.v),
            kelvin: scales.kelvin(p.t),
            replicas: p.runs.len(),
            friction_per_junction: Estimate::of(p.runs.iter().map(|r| r.friction_per_junction)),
            friction_newtons: total.scaled(scales.force_unit),
            mu: steady.then(|| total.scaled(scales.force_unit / scales.normal_load)),
            regime,
            stick_slip_fraction: ss as f64 / p.runs.len() as f64,
            steady,
        }
    }
}
