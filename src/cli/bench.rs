//! `stickslip bench SCENE`: a scaling study ([`crate::studies::scaling`]) from `--n-min` to
//! `--n-max` junctions in both engines; writes `bench.csv` and `bench.svg` into `--out`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::args::load_scene;
use super::args::{EXIT_BAD_INPUT, EXIT_RUN_FAILED, SceneArgs, fail};
use super::out_dir::prepare_out_dir;
use crate::estimate::{self, BASELINE_BYTES, bytes};
use crate::output::atomic::write_whole;
use crate::studies::scaling::{self, Row, Spec};

/// Largest `N` the study goes to by default (memory allowing): a default study takes a
/// minute or two on two cores.
pub const DEFAULT_N_MAX: usize = 10_000_000;

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Smallest junction count.
    #[arg(long, default_value_t = 1000)]
    pub n_min: usize,
    /// Largest junction count (default: 1e7 or the largest that fits in memory, whichever is smaller).
    #[arg(long)]
    pub n_max: Option<usize>,
    /// Junction counts per factor of ten between --n-min and --n-max.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=20))]
    pub per_decade: u32,
    /// Events (exact) or junction-steps (fixed) per run: sets each run's t_end.
    #[arg(long, default_value_t = 1e7, allow_hyphen_values = true)]
    pub work: f64,
    /// One t_end for every run instead of --work.
    #[arg(long, allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Output directory (default: `out/<scene>-bench/`).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Checks the options that clap does not; one line naming the option.
fn check(args: &BenchArgs) -> Result<(), String> {
    use crate::scene::validate::{EVENTS_MAX, N_MAX};
    if args.n_min == 0 || args.n_min > N_MAX {
        return Err(format!("--n-min = {}: must be from 1 to {N_MAX} junctions", args.n_min));
    }
    if let Some(n) = args.n_max.filter(|&n| n < args.n_min || n > N_MAX) {
        return Err(format!("--n-max = {n}: must be from --n-min ({}) to {N_MAX} junctions", args.n_min));
    }
    if !(args.work >= 1.0 && args.work <= EVENTS_MAX) {
        let work = crate::scene::error::compact(args.work);
        return Err(format!("--work = {work}: must be a number of events or junction-steps from 1 to {EVENTS_MAX:e}"));
    }
    if let Some(t) = args.t_end.filter(|t| !(t.is_finite() && *t > 0.0)) {
        return Err(format!("--t-end = {t}: must be a finite time > 0"));
    }
    Ok(())
}

pub(crate) fn bench(args: &BenchArgs) -> ExitCode {
    if let Err(m) = check(args) {
        return fail(EXIT_BAD_INPUT, m);
    }
    let base = match load_scene(&args.scene, &[]) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let available = estimate::available_memory();
    let too_big = |runs: &[(crate::scene::Scene, estimate::Estimate)]| {
        runs.iter().map(|r| r.1.peak_bytes()).max().filter(|&p| available.as_ref().is_some_and(|a| p > a.bytes))
    };
    // The largest N asked for, or the default's: the largest of the ladder up to 1e7 that fits.
    let n_max = args.n_max.unwrap_or(DEFAULT_N_MAX.max(args.n_min));
    let mut sizes = scaling::sizes(args.n_min, n_max, args.per_decade);
    let runs = loop {
        let spec = Spec { sizes: sizes.clone(), work: args.work, t_end: args.t_end };
        let runs = match scaling::plan(&base, &spec) {
            Ok(r) => r,
            Err(e) => return fail(EXIT_BAD_INPUT, e),
        };
        let Some(needed) = too_big(&runs) else { break runs };
        let a = available.as_ref().expect("only an available amount is exceeded");
        if args.n_max.is_some() || sizes.len() == 1 {
            let n = sizes.last().copied().unwrap_or(args.n_min);
            let flag = if args.n_max.is_some() { "--n-max" } else { "--n-min" };
            return fail(
                EXIT_BAD_INPUT,
                format!(
                    "{flag} = {n}: a run at N = {n} needs an estimated {} of memory (with {} for the program), but {} is available ({}); lower {flag}",
                    bytes(needed),
                    bytes(BASELINE_BYTES),
                    bytes(a.bytes),
                    a.source
                ),
            );
        }
        sizes.pop();
    };
    let out = args.out.clone().unwrap_or_else(|| Path::new("out").join(format!("{}-bench", base.name)));
    let held = match prepare_out_dir(&out) {
        Ok(h) => h,
        Err(m) => return fail(EXIT_BAD_INPUT, m),
    };
    println!(
        "bench {}: N = {} to {} ({} sizes), exact and fixed engines, {}",
        crate::scene::error::printable(&base.name),
        sizes[0],
        sizes[sizes.len() - 1],
        sizes.len(),
        match args.t_end {
            Some(t) => format!("t_end = {t}"),
            None => format!("about {:e} events or junction-steps per run", args.work),
        }
    );
    let mut rows: Vec<Row> = Vec::new();
    for (scene, est) in &runs {
        match scaling::measure(scene, est) {
            Ok(r) => {
                println!("{}", line(&r));
                rows.push(r);
            }
            Err(e) => {
                held.abandon();
                return fail(EXIT_RUN_FAILED, e);
            }
        }
    }
    let svg = match crate::plot::scaling::scaling_svg(&base.name, &rows) {
        Ok(s) => s,
        Err(e) => return fail(EXIT_RUN_FAILED, e),
    };
    for (name, text) in [("bench.csv", scaling::csv(&rows)), ("bench.svg", svg)] {
        if let Err(e) = write_whole(&out, name, text.as_bytes()) {
            return fail(EXIT_RUN_FAILED, format!("cannot write {}: {e}", out.join(name).display()));
        }
    }
    println!("output in {}", crate::scene::error::printable(&out.display().to_string()));
    ExitCode::SUCCESS
}

/// One run's figures as printed.
fn line(r: &Row) -> String {
    let engine = scaling::engine_name(r.engine);
    let measured = r.measured_bytes_per_junction.map_or(String::new(), |m| format!(", {m:.1} measured"));
    // No event (rates of zero) or no time measured: no figure per unit.
    let per = r.ns_per_unit();
    let per =
        if per.is_finite() { format!("{per:.2} ns per {}", r.unit()) } else { format!("no {} to time", r.unit()) };
    format!(
        "{engine} N = {}: {per} ({} in {:.3} s, t_end = {}), set-up {:.3} s, {:.1} bytes per junction estimated{measured}",
        r.n,
        r.work,
        r.run_seconds,
        crate::studies::format::sig(r.t_end, 4),
        r.setup_seconds,
        r.estimated_bytes_per_junction,
    )
}
