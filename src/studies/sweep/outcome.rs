//! What a sweep produced: one aggregate [`Row`] per grid point (means with 95 % Student-t
//! half-widths across replicas, the majority regime, the oscillation, totals) and every
//! run's summary. [`Sweep::outcome`] builds it from the summaries of all runs, however they
//! were run.

use serde::Serialize;

use super::plan::Sweep;
use super::values::SweepValue;
use crate::observe::regime::Regime;
use crate::output::Summary;
use crate::studies::stats::mean_ci95;

/// The regime of a grid point across its replicas: `Unstable` when any replica is (its
/// numbers are the scheme's, not the model's), else the majority.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Majority {
    /// Fewer than half of the replicas are stick-slip.
    Smooth,
    /// More than half are.
    StickSlip,
    /// Exactly half are.
    Mixed,
    /// At least one replica is unstable (a fixed step beyond the plate step's stability).
    Unstable,
}

impl Majority {
    /// The regime of replicas whose regimes are `regimes`.
    pub fn of(regimes: impl Iterator<Item = Regime>) -> Majority {
        let (mut runs, mut ss, mut unstable) = (0usize, 0usize, false);
        for r in regimes {
            runs += 1;
            ss += usize::from(r == Regime::StickSlip);
            unstable |= r == Regime::Unstable;
        }
        match (2 * ss).cmp(&runs) {
            _ if unstable => Majority::Unstable,
            std::cmp::Ordering::Less => Majority::Smooth,
            std::cmp::Ordering::Greater => Majority::StickSlip,
            std::cmp::Ordering::Equal => Majority::Mixed,
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            Majority::Smooth => "smooth",
            Majority::StickSlip => "stick-slip",
            Majority::Mixed => "mixed",
            Majority::Unstable => "unstable",
        }
    }
}

/// The aggregate of one grid point's replicas.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Grid point index.
    pub point: usize,
    /// The value of each axis.
    pub values: Vec<SweepValue>,
    /// Junctions `N` at this point (for per-junction figures).
    pub n: u64,
    pub replicas: usize,
    /// `(mean, 95% CI half-width)` across replicas (half-width NaN for one replica).
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
    /// Oscillation amplitude (force) across all replicas (0 for a replica without a period).
    pub oscillation_amplitude: (f64, f64),
    /// Oscillation period across the replicas that have one (`(NaN, NaN)` if none has).
    pub oscillation_period: (f64, f64),
}

impl Row {
    /// The aggregate of grid point `point` (values `values`) from its replicas' summaries.
    pub fn from_runs(point: usize, values: &[SweepValue], runs: &[Summary]) -> Row {
        let col = |f: fn(&Summary) -> f64| mean_ci95(&runs.iter().map(f).collect::<Vec<_>>());
        let ss = runs.iter().filter(|s| s.regime == Regime::StickSlip).count();
        let regime = Majority::of(runs.iter().map(|s| s.regime));
        let periods: Vec<f64> = runs.iter().filter_map(|s| s.oscillation.oscillation_period).collect();
        Row {
            point,
            values: values.to_vec(),
            n: runs.first().map_or(0, |s| s.n),
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
            oscillation_amplitude: col(|s| s.oscillation.oscillation_amplitude),
            oscillation_period: if periods.is_empty() { (f64::NAN, f64::NAN) } else { mean_ci95(&periods) },
        }
    }
}

/// How a sweep was run (not reproducible: only in `sweep.json`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// Wall-clock seconds of the whole sweep.
    pub wall_seconds: f64,
    /// Worker threads (or processes) it ran on.
    pub threads: usize,
}

/// What a sweep produced.
#[derive(Clone, Debug)]
pub struct SweepOutcome {
    /// One per grid point, in grid order.
    pub rows: Vec<Row>,
    /// `summaries[g][r]`: grid point `g`, replica `r`.
    pub summaries: Vec<Vec<Summary>>,
    /// How long it took, when the caller knows ([`Sweep::run`] sets it).
    pub timing: Option<Timing>,
}

/// Why summaries do not make an outcome of a sweep.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OutcomeError {
    #[error("{got} summaries for a sweep of {expected} runs")]
    Count { expected: usize, got: usize },
    #[error(
        "summary {position} has seed {got}, but run {position} (grid point {point}, replica {replica}) has seed {expected}: summaries must come in the order of Sweep::runs"
    )]
    Order { position: usize, point: usize, replica: usize, expected: u64, got: u64 },
}

impl Sweep {
    /// The outcome from the summaries of all runs, in the order of [`Sweep::runs`] (grid
    /// point by grid point, replicas in order), wherever they ran. Each summary's seed must
    /// be its run's: a summary out of place is an error, never a wrong table.
    pub fn outcome(&self, summaries: Vec<Summary>) -> Result<SweepOutcome, OutcomeError> {
        if summaries.len() != self.len() {
            return Err(OutcomeError::Count { expected: self.len(), got: summaries.len() });
        }
        for (position, (run, s)) in self.runs().zip(&summaries).enumerate() {
            if run.scene.run.seed != s.seed {
                return Err(OutcomeError::Order {
                    position,
                    point: run.point,
                    replica: run.replica,
                    expected: run.scene.run.seed,
                    got: s.seed,
                });
            }
        }
        let mut it = summaries.into_iter();
        let per_point: Vec<Vec<Summary>> =
            self.points.iter().map(|_| it.by_ref().take(self.replicas).collect()).collect();
        let rows = self.points.iter().zip(&per_point).map(|(p, s)| Row::from_runs(p.index, &p.values, s)).collect();
        Ok(SweepOutcome { rows, summaries: per_point, timing: None })
    }
}
