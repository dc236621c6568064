//! `stickslip resume DIR`: continues a killed run from the checkpoint in its output
//! directory, (a killed study resumes from its journal: [`super::study_resume`]) (docs/runs.md).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::args::{EXIT_BAD_INPUT, EXIT_RUN_FAILED, fail};
use super::out_dir::prepare_out_dir;
use super::run::{draw_plot, summary_lines};
use super::stdout::emit;
use crate::output::Summary;
use crate::runner::{self, Resumed, RunOptions};
use crate::scene::Scene;

#[derive(clap::Args, Debug)]
pub struct ResumeArgs {
    /// Output directory of the run (the one holding checkpoint.bin) or of the sweep or compare (the one holding journal.jsonl).
    pub dir: PathBuf,
    /// Checkpoint interval from now on (default: the run's own --checkpoint-every).
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds, allow_hyphen_values = true)]
    pub checkpoint_every: Option<f64>,
}

/// Longest checkpoint interval accepted (about 30 000 years).
const MAX_SECONDS: f64 = 1e12;

/// Parses `--checkpoint-every`: a finite number of seconds, > 0.
pub(crate) fn parse_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| "not a number (expected seconds, a number > 0)".to_string())?;
    if !(v > 0.0 && v <= MAX_SECONDS) {
        return Err(format!("must be a number of seconds > 0 and <= {MAX_SECONDS:e}"));
    }
    Ok(v)
}

/// Resumes a run (the dispatch tries [`super::study_resume::resume`] first).
pub(crate) fn resume(args: &ResumeArgs) -> ExitCode {
    // All cores, as `run` by default: the results do not depend on it.
    let opts = RunOptions {
        checkpoint_every: args.checkpoint_every,
        progress: true,
        stop: None,
        threads: rayon::current_num_threads(),
    };
    // A directory that cannot be written, or that another run holds, is reported before
    // anything else is done; it is held until the run is done.
    let _held = match args.dir.is_dir().then(|| prepare_out_dir(&args.dir)).transpose() {
        Ok(h) => h,
        Err(m) => return fail(EXIT_BAD_INPUT, m),
    };
    match runner::resume(&args.dir, &opts) {
        Ok(Resumed::Finished) => match plot_left_undrawn(&args.dir) {
            // Killed after its results were in place but before its plot was drawn.
            Some(scene) => {
                if let Err(e) = draw_plot(&scene, &args.dir) {
                    return fail(EXIT_RUN_FAILED, e);
                }
                emit(&format!(
                    "the run in {} is finished (summary.json is there, no checkpoint is left); its trace.svg was \
                     missing and is drawn now\n",
                    args.dir.display()
                ))
            }
            None => emit(&format!(
                "the run in {} is finished (summary.json is there, no checkpoint is left): nothing to resume\n",
                args.dir.display()
            )),
        },
        Ok(Resumed::Completed { from_t, summary }) => {
            if let Err(e) = draw_plot(&summary.parameters, &args.dir) {
                return fail(EXIT_RUN_FAILED, e);
            }
            emit(&format!("resumed from the checkpoint at t = {from_t}\n{}", summary_lines(&summary, &args.dir)))
        }
        Err(e) if e.is_bad_input() => fail(EXIT_BAD_INPUT, e),
        Err(e) => fail(EXIT_RUN_FAILED, e),
    }
}

/// The scene of a finished run in `dir` whose plot is asked for (`output.plot`) and not
/// there, with its `trace.csv` in place: a run killed between its last result and its
/// plot. `None` otherwise, and when `summary.json` cannot be read.
fn plot_left_undrawn(dir: &Path) -> Option<Scene> {
    if dir.join("trace.svg").exists() || !dir.join("trace.csv").is_file() {
        return None;
    }
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let summary: Summary = serde_json::from_str(&text).ok()?;
    summary.parameters.output.plot.then_some(summary.parameters)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds() {
        assert_eq!(parse_seconds("2.5"), Ok(2.5));
        assert_eq!(parse_seconds("1e-3"), Ok(1e-3));
        for bad in ["0", "-1", "-0.5", "NaN", "nan", "inf", "-inf", "abc", "", "1e13", "0x10"] {
            assert!(parse_seconds(bad).is_err(), "{bad}");
        }
    }
}
