//! The sweep's files as text: `sweep.csv`, `runs.csv`, `sweep.json`.

use std::fmt::Write as _;

use serde::Serialize;

use super::Sweep;
use super::outcome::SweepOutcome;
use super::values::value_text;
use crate::output::csv::push_f64;
use crate::scene::Scene;

/// Columns of `sweep.csv` after the first (which is named by the swept field).
pub const SWEEP_COLUMNS: &str = "replicas,friction_mean,friction_mean_ci95,friction_per_junction,friction_per_junction_ci95,friction_std,friction_std_ci95,attached_fraction_mean,attached_fraction_mean_ci95,regime,stick_slip_fraction,events,steps";
/// Columns of `runs.csv` after the first.
pub const RUNS_COLUMNS: &str = "replica,seed,friction_mean,friction_per_junction,friction_std,attached_fraction_mean,regime,stick_slip_cycles,events,steps";

impl SweepOutcome {
    /// `sweep.csv`: one row per value.
    pub fn sweep_csv(&self, sweep: &Sweep) -> String {
        let mut s = format!("{},{SWEEP_COLUMNS}\n", sweep.param);
        for r in &self.rows {
            s.push_str(&value_text(r.value.x));
            let _ = write!(s, ",{}", r.replicas);
            for (m, c) in [r.friction_mean, r.friction_per_junction, r.friction_std, r.attached_fraction_mean] {
                s.push(',');
                push_f64(&mut s, m);
                s.push(',');
                // A single replica has no confidence interval: the field is left empty.
                if c.is_finite() {
                    push_f64(&mut s, c);
                }
            }
            let _ = write!(s, ",{},", r.regime.as_str());
            push_f64(&mut s, r.stick_slip_fraction);
            let _ = writeln!(s, ",{},{}", r.events, r.steps);
        }
        s
    }

    /// `runs.csv`: one row per run.
    pub fn runs_csv(&self, sweep: &Sweep) -> String {
        let mut s = format!("{},{RUNS_COLUMNS}\n", sweep.param);
        for (v, row) in sweep.values.iter().zip(&self.summaries) {
            for (r, run) in row.iter().enumerate() {
                s.push_str(&value_text(v.x));
                let _ = write!(s, ",{r},{}", run.seed);
                for x in [run.friction_mean, run.friction_per_junction, run.friction_std, run.attached_fraction_mean] {
                    s.push(',');
                    push_f64(&mut s, x);
                }
                let _ = writeln!(
                    s,
                    ",{},{},{},{}",
                    run.regime.as_str(),
                    run.stick_slip_cycles,
                    run.counters.events.unwrap_or(0),
                    run.counters.steps.unwrap_or(0)
                );
            }
        }
        s
    }

    /// `sweep.json`: what was run (scene, field, values, seeds, overrides) and how long it took.
    pub fn sweep_json(&self, sweep: &Sweep) -> String {
        #[derive(Serialize)]
        struct Record<'a> {
            scene: &'a str,
            param: &'a str,
            values: Vec<&'a str>,
            replicas: usize,
            set: &'a [String],
            seed: u64,
            seed_rule: &'static str,
            seeds: Vec<Vec<u64>>,
            threads: usize,
            wall_seconds: f64,
            run_wall_seconds: Vec<f64>,
            base_scene: &'a Scene,
        }
        let r = Record {
            scene: &sweep.base.name,
            param: &sweep.param,
            values: sweep.values.iter().map(|v| v.text.as_str()).collect(),
            replicas: sweep.replicas,
            set: &sweep.set,
            seed: sweep.base.run.seed,
            seed_rule: "seed(i, r) = mix(mix(mix(run.seed) ^ i) ^ r), mix = SplitMix64 output of x + 0x9E3779B97F4A7C15; \
                        h >> 1, or 1 + h mod (2^31 - 2) for Park-Miller; i = value index, r = replica (0-based); see src/studies/seeds.rs",
            seeds: sweep.runs.iter().map(|row| row.iter().map(|s| s.run.seed).collect()).collect(),
            threads: self.threads,
            wall_seconds: self.wall_seconds,
            run_wall_seconds: self.rows.iter().map(|r| r.wall_seconds).collect(),
            base_scene: &sweep.base,
        };
        serde_json::to_string_pretty(&r).expect("the record serializes") + "\n"
    }
}
