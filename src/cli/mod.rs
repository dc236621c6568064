//! The command line: `stickslip run`, `stickslip resume`, `stickslip validate`, `stickslip compare`,
//! `stickslip sweep`, `stickslip stability`, `stickslip bench`, `stickslip friction-law`, `stickslip fit`.
//!
//! Exit codes: 0 success; 1 the run failed (numerical trouble, a write that failed
//! mid-run, a report that could not be written to standard output); 2 bad input (command
//! line, scene file, `--set`, output directory). A closed pipe on standard output ends the
//! process by `SIGPIPE`, quietly ([`stdout`]).

mod args;
mod bench;
mod command;
mod compare;
mod cpu;
mod fit;
mod friction_law;
mod out_dir;
mod resume;
mod run;
mod signals;
pub mod stability;
pub mod stdout;
mod study;
mod study_resume;
mod sweep;
mod validate;

use std::process::ExitCode;

use clap::Parser;

pub use args::{EXIT_BAD_INPUT, EXIT_RUN_FAILED, EngineArg, SceneArgs};
use args::{clap_one_line, fail};
pub use command::{Cli, Command};

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
        Command::Run { scene, engine, seed, out, checkpoint_every, threads } => {
            run::run(&scene, engine, seed, out, checkpoint_every, threads)
        }
        Command::Resume(args) => {
            study_resume::resume(&args.dir, args.checkpoint_every).unwrap_or_else(|| resume::resume(&args))
        }
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
