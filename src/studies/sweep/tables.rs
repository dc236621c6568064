//! The sweep's files as text: `sweep.csv`, `runs.csv`, `sweep.json`.
//!
//! `sweep.csv` and `runs.csv` depend only on the sweep and its runs' summaries: the same
//! bytes whatever ran the runs, in whatever order, on however many threads. Their leading
//! columns are the swept fields (one, or two for a map).

use std::fmt::Write as _;

use serde::Serialize;

use super::outcome::SweepOutcome;
use super::plan::Sweep;
use super::values::value_text;
use crate::output::csv::push_f64;
use crate::scene::Scene;

/// Columns of `sweep.csv` after the swept fields.
pub const SWEEP_COLUMNS: &str = "replicas,friction_mean,friction_mean_ci95,friction_per_junction,friction_per_junction_ci95,friction_std,friction_std_ci95,attached_fraction_mean,attached_fraction_mean_ci95,regime,stick_slip_fraction,events,steps,oscillation_amplitude,oscillation_amplitude_ci95,oscillation_period,oscillation_period_ci95";
/// Columns of `runs.csv` after the swept fields.
pub const RUNS_COLUMNS: &str = "replica,seed,friction_mean,friction_per_junction,friction_std,attached_fraction_mean,regime,stick_slip_cycles,events,steps,oscillation_amplitude,oscillation_period,oscillation_coherence,stuck_fraction";

/// Appends `,x`, or `,` alone when `x` is not finite (a single replica's interval, a
/// period no replica has).
fn cell(s: &mut String, x: f64) {
    s.push(',');
    if x.is_finite() {
        push_f64(s, x);
    }
}

impl Sweep {
    /// The header's leading fields: the swept fields.
    fn header(&self) -> String {
        self.axes.iter().map(|a| a.param.as_str()).collect::<Vec<_>>().join(",")
    }
    /// The leading fields of grid point `g`: its values.
    fn point_values(&self, g: usize) -> String {
        self.points[g].values.iter().map(|v| value_text(v.x)).collect::<Vec<_>>().join(",")
    }
}

impl SweepOutcome {
    /// `sweep.csv`: one row per grid point.
    pub fn sweep_csv(&self, sweep: &Sweep) -> String {
        let mut s = format!("{},{SWEEP_COLUMNS}\n", sweep.header());
        for r in &self.rows {
            s.push_str(&sweep.point_values(r.point));
            let _ = write!(s, ",{}", r.replicas);
            for (m, c) in [r.friction_mean, r.friction_per_junction, r.friction_std, r.attached_fraction_mean] {
                cell(&mut s, m);
                cell(&mut s, c);
            }
            let _ = write!(s, ",{}", r.regime.as_str());
            cell(&mut s, r.stick_slip_fraction);
            let _ = write!(s, ",{},{}", r.events, r.steps);
            for (m, c) in [r.oscillation_amplitude, r.oscillation_period] {
                cell(&mut s, m);
                cell(&mut s, c);
            }
            s.push('\n');
        }
        s
    }

    /// `runs.csv`: one row per run.
    pub fn runs_csv(&self, sweep: &Sweep) -> String {
        let mut s = format!("{},{RUNS_COLUMNS}\n", sweep.header());
        for (g, row) in self.summaries.iter().enumerate() {
            for (r, run) in row.iter().enumerate() {
                s.push_str(&sweep.point_values(g));
                let _ = write!(s, ",{r},{}", run.seed);
                for x in [run.friction_mean, run.friction_per_junction, run.friction_std, run.attached_fraction_mean] {
                    cell(&mut s, x);
                }
                let _ = write!(
                    s,
                    ",{},{},{},{}",
                    run.regime.as_str(),
                    run.stick_slip_cycles,
                    run.counters.events.unwrap_or(0),
                    run.counters.steps.unwrap_or(0)
                );
                let o = &run.oscillation;
                for x in [
                    o.oscillation_amplitude,
                    o.oscillation_period.unwrap_or(f64::NAN),
                    o.oscillation_coherence,
                    o.stuck_fraction,
                ] {
                    cell(&mut s, x);
                }
                s.push('\n');
            }
        }
        s
    }

    /// `sweep.json`: what was run (scene, fields, values, seeds, overrides) and, when known,
    /// how long it took.
    pub fn sweep_json(&self, sweep: &Sweep) -> String {
        #[derive(Serialize)]
        struct Record<'a> {
            scene: &'a str,
            param: &'a str,
            values: Vec<&'a str>,
            #[serde(skip_serializing_if = "Option::is_none")]
            param2: Option<&'a str>,
            #[serde(skip_serializing_if = "Option::is_none")]
            values2: Option<Vec<&'a str>>,
            replicas: usize,
            set: &'a [String],
            seed: u64,
            seed_rule: &'static str,
            /// `seeds[g][r]`, grid point `g` (row-major), replica `r`.
            seeds: Vec<Vec<u64>>,
            #[serde(skip_serializing_if = "Option::is_none")]
            threads: Option<usize>,
            #[serde(skip_serializing_if = "Option::is_none")]
            wall_seconds: Option<f64>,
            run_wall_seconds: Vec<f64>,
            base_scene: &'a Scene,
        }
        let texts = |k: usize| sweep.axes[k].values.iter().map(|v| v.text.as_str()).collect::<Vec<_>>();
        let r = Record {
            scene: &sweep.base.name,
            param: &sweep.axes[0].param,
            values: texts(0),
            param2: sweep.axes.get(1).map(|a| a.param.as_str()),
            values2: (sweep.axes.len() > 1).then(|| texts(1)),
            replicas: sweep.replicas,
            set: &sweep.set,
            seed: sweep.base.run.seed,
            seed_rule: "h(i, r) = mix(mix(mix(run.seed) ^ i) ^ r), mix = SplitMix64 output of x + 0x9E3779B97F4A7C15; \
                        seed = h(i, r) >> 1; for Park-Miller, replica r of point i starts r L draws after the state \
                        1 + h(i, 2^64 - 1) mod (2^31 - 2), L = N (steps + 1) the draws of one replica (disjoint \
                        blocks of the cycle); i = grid point index (the value index of a 1-D sweep; i1 * len(values2) \
                        + i2 in a 2-D one), r = replica (0-based); see src/studies/seeds.rs",
            seeds: sweep.points.iter().map(|p| p.scenes.iter().map(|s| s.run.seed).collect()).collect(),
            threads: self.timing.map(|t| t.threads),
            wall_seconds: self.timing.map(|t| t.wall_seconds),
            run_wall_seconds: self.rows.iter().map(|r| r.wall_seconds).collect(),
            base_scene: &sweep.base,
        };
        serde_json::to_string_pretty(&r).expect("the record serializes") + "\n"
    }
}
