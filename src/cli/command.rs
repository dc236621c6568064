//! The command line's grammar: the commands and their arguments (clap).

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use super::args::{EngineArg, SceneArgs};
use super::{bench, compare, fit, friction_law, resume, sweep};

#[derive(Parser, Debug)]
#[command(
    name = "stickslip",
    version,
    about = "Junction friction (FKU bond model): exact event-driven and fixed-step simulation"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run one scene and write summary.json (and trace.csv, events.csv as the scene asks).
    Run {
        #[command(flatten)]
        scene: SceneArgs,
        /// Engine (overrides run.engine).
        #[arg(long)]
        engine: Option<EngineArg>,
        /// Random seed (overrides run.seed; a TOML integer, so at most 9223372036854775807).
        #[arg(long, value_parser = clap::value_parser!(u64).range(..=i64::MAX as u64))]
        seed: Option<u64>,
        /// Output directory (default: `out/<scene file stem>/`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write checkpoint.bin into the output directory at most every SECONDS of wall time, so that a killed run can be resumed.
        #[arg(long, value_name = "SECONDS", value_parser = resume::parse_seconds, allow_hyphen_values = true)]
        checkpoint_every: Option<f64>,
        /// Threads the fixed-step engine shares each step's junctions among (default: all cores; large N only). The results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Continue a killed run from the checkpoint in its output directory, or a killed sweep or compare from its journal.
    Resume(resume::ResumeArgs),
    /// Sweep one scene field, or two for a regime map, over values, with replicas, in parallel; writes sweep.csv and sweep.svg.
    Sweep(sweep::SweepArgs),
    /// Check a scene and print its resolved parameters.
    Validate {
        #[command(flatten)]
        scene: SceneArgs,
    },
    /// Stability limits of the fixed-step scheme at a scene's parameters (docs/stability.md).
    Stability {
        #[command(flatten)]
        scene: SceneArgs,
    },
    /// Work-precision study: error against run time of the fixed-step and exact engines.
    Compare(compare::CompareArgs),
    /// Scaling study: a scene at growing N in both engines; writes bench.csv and bench.svg (time per event and per junction-step, set-up time, memory per junction).
    Bench(bench::BenchArgs),
    /// A friction law for continuum codes from a map over plate.v and junctions.temperature (run here, or --from a finished sweep): law.csv, abaqus.inp, ansys.mac, law.json.
    FrictionLaw(friction_law::FrictionLawArgs),
    /// Fit free scene fields to a measured friction curve (DATA.csv), with 95 % intervals; writes fit.json, fit.csv, fit.toml and fit.svg.
    Fit(fit::FitArgs),
}
