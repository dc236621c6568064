//! What a sweep produced: one aggregate [`Row`] per value (means with 95 % Student-t
//! half-widths across replicas, the majority regime, totals) and every run's summary.

use serde::Serialize;

use super::values::SweepValue;
use crate::observe::regime::Regime;
use crate::output::Summary;
use crate::studies::stats::mean_ci95;

/// The regime of a value across its replicas.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Majority {
    /// Fewer than half of the replicas are stick-slip.
    Smooth,
    /// More than half are.
    StickSlip,
    /// Exactly half are.
    Mixed,
}

impl Majority {
    pub fn as_str(self) -> &'static str {
        match self {
            Majority::Smooth => "smooth",
            Majority::StickSlip => "stick-slip",
            Majority::Mixed => "mixed",
        }
    }
}

/// The aggregate of one value's replicas.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub value: SweepValue,
    pub replicas: usize,
    /// `(mean, 95% CI half-width)` across replicas.
    pub friction_mean: (f64, f64),
    pub friction_per_junction: (f64, f64),
    pub friction_std: (f64, f64),
    pub attached_fraction_mean: (f64, f64),
    pub regime: Majority,
    pub stick_slip_fraction: f64,
    /// Exact-engine events summed over the replicas.
    pub events: u64,
    /// Fixed-engine steps summed over the replicas.
    pub steps: u64,
    /// Wall-clock seconds summed over the replicas' runs.
    pub wall_seconds: f64,
}

impl Row {
    pub fn from_runs(value: &SweepValue, runs: &[Summary]) -> Row {
        let col = |f: fn(&Summary) -> f64| mean_ci95(&runs.iter().map(f).collect::<Vec<_>>());
        let ss = runs.iter().filter(|s| s.regime == Regime::StickSlip).count();
        let regime = match (2 * ss).cmp(&runs.len()) {
            std::cmp::Ordering::Less => Majority::Smooth,
            std::cmp::Ordering::Greater => Majority::StickSlip,
            std::cmp::Ordering::Equal => Majority::Mixed,
        };
        Row {
            value: value.clone(),
            replicas: runs.len(),
            friction_mean: col(|s| s.friction_mean),
            friction_per_junction: col(|s| s.friction_per_junction),
            friction_std: col(|s| s.friction_std),
            attached_fraction_mean: col(|s| s.attached_fraction_mean),
            regime,
            stick_slip_fraction: ss as f64 / runs.len() as f64,
            events: runs.iter().filter_map(|s| s.counters.events).sum(),
            steps: runs.iter().filter_map(|s| s.counters.steps).sum(),
            wall_seconds: runs.iter().map(|s| s.wall_seconds).sum(),
        }
    }
}

/// What a sweep produced.
#[derive(Clone, Debug)]
pub struct SweepOutcome {
    pub rows: Vec<Row>,
    /// `summaries[i][r]`.
    pub summaries: Vec<Vec<Summary>>,
    pub wall_seconds: f64,
    pub threads: usize,
}
