//! `stickslip fit SCENE DATA.csv --free FIELD[,FIELD..] [--out DIR]`: calibration
//! ([`crate::fit`], docs/calibration.md). Every evaluation is appended to the journal in
//! `DIR`; a killed fit is continued by `stickslip resume DIR` (or the same command again),
//! which replays the journal's evaluations and gives the result of an uninterrupted fit.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use indicatif::{ProgressBar, ProgressStyle};

use super::args::load_scene;
use super::args::{EXIT_BAD_INPUT, EXIT_RUN_FAILED, SceneArgs, fail};
use super::out_dir::prepare_out_dir;
use super::{signals, study};
use crate::fit::model::{Evaluation, FitError, Objective, PoolSimulator};
use crate::fit::prepare;
use crate::scene::error::printable;
use crate::studies::journal::{self, StudyKind};

#[derive(clap::Args, Debug)]
pub struct FitArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The measured curve: CSV with a `friction` column (mean friction per junction), an optional `sigma` column (its standard error) and condition columns named by scene fields (e.g. plate.v).
    pub data: PathBuf,
    /// Free scene fields, comma-separated or repeated: FIELD, FIELD=LOW:HIGH, FIELD=LOW:HIGH:lin (default scale log when LOW > 0; default bounds the scene's value / 10 and x 10).
    #[arg(long, required = true, value_name = "FIELD[=LOW:HIGH[:lin|:log]],...")]
    pub free: Vec<String>,
    /// Runs per data point and evaluation, with the same seeds at every evaluation (common random numbers).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub replicas: u32,
    /// Multiplies the friction and sigma columns, to convert measured units (e.g. a friction coefficient) into the model's mean friction per junction.
    #[arg(long, default_value_t = 1.0, value_parser = parse_scale, allow_hyphen_values = true)]
    pub friction_scale: f64,
    /// Most evaluations of the misfit (each runs every data point's replicas).
    #[arg(long, default_value_t = 5000, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub max_evaluations: u32,
    /// Output directory (default: out/<scene file stem>-fit/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores). The results do not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
}

fn parse_scale(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if crate::fit::data::in_window(v) => Ok(v),
        _ => Err("must be a number from 1e-100 to 1e100".into()),
    }
}

pub(crate) fn fit(args: &FitArgs) -> ExitCode {
    let base = match load_scene(&args.scene, &[]) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let origin = args.data.display().to_string();
    let problem = match prepare::problem(base, &args.data, &args.free, args.replicas as usize, args.friction_scale) {
        Ok(p) => p,
        Err(m) => return fail(EXIT_BAD_INPUT, m),
    };
    let starts: Vec<f64> = problem.free.iter().map(|f| f.start).collect();
    let scenes = match problem.scenes(&starts) {
        Ok(s) => s,
        Err(e) => return fail(EXIT_BAD_INPUT, e),
    };
    let threads = match crate::estimate::check::study_threads(&scenes, args.threads.map(|t| t as usize), "the fit") {
        Ok(t) => t,
        Err(e) => return fail(EXIT_BAD_INPUT, e),
    };
    let out = args.out.clone().unwrap_or_else(|| Path::new("out").join(format!("{}-fit", problem.base.name)));
    let held = match prepare_out_dir(&out) {
        Ok(c) => c,
        Err(m) => return fail(EXIT_BAD_INPUT, m),
    };
    let max = args.max_evaluations as usize;
    let header = prepare::header(&problem, max, study::invocation());
    let seeds = vec![problem.base.run.seed; max];
    let mut journal = match study::open::<Evaluation>(StudyKind::Fit, &out, &header, &seeds) {
        Ok(j) => j,
        Err(code) => {
            held.abandon();
            return code;
        }
    };
    let done: Vec<Evaluation> = std::mem::take(&mut journal.opened.done).into_iter().map_while(|d| d).collect();
    let pool = match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
        Ok(p) => p,
        Err(e) => return fail(EXIT_RUN_FAILED, format!("cannot start the thread pool: {e}")),
    };
    let stop = signals::stop_on_signals();
    let sim = PoolSimulator { pool: &pool, stop: Some(stop.clone()) };
    let mut objective = Objective::new(&problem, &sim, done, Some(&journal.opened.journal), Some(stop), max);
    let progress = std::io::stderr().is_terminal().then(|| {
        let p = ProgressBar::new_spinner();
        if let Ok(style) = ProgressStyle::with_template("{spinner} {msg}, {elapsed} elapsed") {
            p.set_style(style);
        }
        p
    });
    if let Some(p) = progress.clone() {
        objective.on_new = Some(Box::new(move |n, best, stage| {
            p.set_message(format!("{}: {n} evaluations, best misfit {best:.6e}", stage.as_str()))
        }));
    }
    let started = std::time::Instant::now();
    let result = crate::fit::solve::fit(&objective);
    let made_now = objective.new_evaluations();
    drop(objective);
    if let Some(p) = &progress {
        p.finish_and_clear();
    }
    let kept = || {
        format!(
            "the evaluations are kept in {}; continue with `stickslip resume {}`",
            journal::path_in(&out).display(),
            out.display()
        )
    };
    let r = match result {
        Ok(r) => r,
        Err(FitError::Stopped { done }) => {
            let (name, code) = signals::received().unwrap_or(("a stop", EXIT_RUN_FAILED));
            return fail(code, format!("stopped by {name} after {done} evaluations; {}", kept()));
        }
        Err(e @ (FitError::TooMany { .. } | FitError::Journal(_))) => {
            return fail(EXIT_RUN_FAILED, format!("{e}; {}", kept()));
        }
        Err(e) => {
            journal.discard_if_new();
            held.abandon();
            return fail(EXIT_RUN_FAILED, e);
        }
    };
    if let Err(e) = crate::plot::files::write_fit(&problem, &r, &out, &prepare::data_name(&args.data)) {
        return study::write_failed(e, &out);
    }
    println!(
        "fit of {} to {} points of {} ({} replicas each, {} evaluations, {} made now, on {} threads in {:.2} s)",
        problem.free.iter().map(|f| f.field.as_str()).collect::<Vec<_>>().join(", "),
        problem.data.len(),
        printable(&origin),
        problem.replicas,
        r.evaluations,
        made_now,
        threads,
        started.elapsed().as_secs_f64()
    );
    for (j, f) in problem.free.iter().enumerate() {
        let iv = &r.intervals[j];
        let flags = crate::fit::report::flags(&r, j);
        println!(
            "  {} = {:.6e}  95% interval [{:.6e}, {:.6e}]{}",
            f.field,
            r.best.values[j],
            f.value(iv.low.y),
            f.value(iv.high.y),
            if flags.is_empty() { String::new() } else { format!("  ({})", flags.join("; ")) }
        );
    }
    let p = match (r.p_value, r.sigma_estimate) {
        (Some(p), _) => format!("p-value {p:.4}"),
        (None, Some(_)) => "no p-value (sigma estimated from the residuals)".to_string(),
        (None, None) => "no p-value (no degrees of freedom)".to_string(),
    };
    println!("  misfit chi2 = {:.4} with {} degrees of freedom; {p}", r.chi2, r.dof);
    if let Some(w) = crate::fit::report::noise_warning(&r) {
        eprintln!("warning: {w}");
    }
    println!(
        "output in {} (fit.json, fit.csv, fit.toml, fit.svg)",
        crate::scene::error::printable(&out.display().to_string())
    );
    ExitCode::SUCCESS
}
