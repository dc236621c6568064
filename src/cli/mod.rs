//! The command line: `stickslip run`, `stickslip resume`, `stickslip validate`, `stickslip compare`,
//! `stickslip sweep`, `stickslip stability`, `stickslip bench`, `stickslip friction-law`, `stickslip fit`.
//!
//! Exit codes: 0 success; 1 the run failed (numerical trouble, a write that failed
//! mid-run, a report that could not be written to standard output); 2 bad input (command
//! line, scene file, `--set`, output directory). A closed pipe on standard output ends the
//! process by `SIGPIPE`, quietly ([`stdout`]).

mod bench;
mod compare;
mod cpu;
mod fit;
mod friction_law;
mod resume;
mod run;
mod signals;
pub mod stability;
pub mod stdout;
mod study;
mod study_resume;
mod sweep;
mod validate;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

/// Exit code for bad input.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code for a run that failed.
pub const EXIT_RUN_FAILED: u8 = 1;

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

/// Scene selection shared by the commands that read a scene.
#[derive(clap::Args, Debug, Clone)]
pub struct SceneArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Override a scene field, e.g. `--set plate.v=0.1` (repeatable; checked like the file).
    #[arg(long = "set", value_name = "SECTION.KEY=VALUE")]
    pub set: Vec<String>,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum EngineArg {
    Exact,
    Fixed,
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
        /// Random seed (overrides run.seed).
        #[arg(long)]
        seed: Option<u64>,
        /// Output directory (default: `out/<scene file stem>/`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write checkpoint.bin into the output directory at most every SECONDS of wall time, so that a killed run can be resumed.
        #[arg(long, value_name = "SECONDS", value_parser = resume::parse_seconds, allow_hyphen_values = true)]
        checkpoint_every: Option<f64>,
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

/// Prints a one-line error and returns the exit code.
pub(crate) fn fail(code: u8, message: impl std::fmt::Display) -> ExitCode {
    // One line whatever the message holds (a path or a `--set` with a newline in it).
    eprintln!("error: {}", crate::scene::error::printable(&message.to_string()));
    ExitCode::from(code)
}

/// clap's message as one line: its first paragraph (which names the argument and, on the
/// lines after the first, the missing argument or the allowed values), joined by spaces.
fn clap_one_line(e: &clap::Error) -> String {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand | ErrorKind::MissingSubcommand) {
        return "a command is required: `run`, `resume`, `validate`, `stability`, `sweep`, `compare`, `bench`, `friction-law` or `fit` (try --help)"
            .to_string();
    }
    let text = e.to_string();
    let first: Vec<&str> = text.lines().map(str::trim).take_while(|l| !l.is_empty()).collect();
    let line = first.join(" ");
    let line = line.trim_start_matches("error: ");
    if line.is_empty() { "invalid arguments (try --help)".to_string() } else { line.to_string() }
}

/// Entry point of the binary. Restores the default action of `SIGPIPE` ([`stdout`]).
pub fn main() -> ExitCode {
    if let Err(m) = cpu::check() {
        return fail(EXIT_RUN_FAILED, m);
    }
    stdout::restore_sigpipe();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) if e.use_stderr() => return fail(EXIT_BAD_INPUT, clap_one_line(&e)),
        // --help, --version: clap's text on stdout.
        Err(e) => {
            return match e.print() {
                Ok(()) => ExitCode::SUCCESS,
                Err(err) => stdout::write_failed(&err),
            };
        }
    };
    let code = match cli.command {
        Command::Run { scene, engine, seed, out, checkpoint_every } => {
            run::run(&scene, engine, seed, out, checkpoint_every)
        }
        Command::Resume(args) => resume::resume(&args),
        Command::Validate { scene } => validate::validate(&scene),
        Command::Stability { scene } => stability::stability(&scene),
        Command::Compare(args) => compare::compare(&args),
        Command::Bench(args) => bench::bench(&args),
        Command::Sweep(args) => sweep::sweep(&args),
        Command::FrictionLaw(args) => friction_law::friction_law(&args),
        Command::Fit(args) => fit::fit(&args),
    };
    report_peak_memory();
    code
}

/// With [`crate::estimate::system::REPORT_PEAK_ENV`] set, prints the process's peak resident
/// memory on stderr (one line), to compare with the estimate.
fn report_peak_memory() {
    use crate::estimate::system::{REPORT_PEAK_ENV, peak_resident};
    if std::env::var_os(REPORT_PEAK_ENV).is_some() {
        if let Some(b) = peak_resident() {
            eprintln!("peak memory {b} bytes ({})", crate::estimate::bytes(b));
        }
    }
}
