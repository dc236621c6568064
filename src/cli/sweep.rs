//! `stickslip sweep`: one scene field over a list of values, with replicas, in parallel.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::ArgGroup;
use indicatif::{ProgressBar, ProgressStyle};

use super::run::{load_scene, prepare_out_dir, remove_if_empty};
use super::{EXIT_BAD_INPUT, EXIT_RUN_FAILED, SceneArgs, fail};
use crate::studies::sweep::{Sweep, ValueSpec, parse_values};

#[derive(clap::Args, Debug)]
#[command(group(ArgGroup::new("swept_values").required(true).args(["values", "log_range", "range"])))]
pub struct SweepArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The scene field to sweep, as SECTION.KEY (e.g. plate.v, junctions.temperature).
    #[arg(long, value_name = "SECTION.KEY")]
    pub param: String,
    /// The values, separated by commas (e.g. 0.1,0.5,2).
    #[arg(long, value_name = "A,B,...", allow_hyphen_values = true)]
    pub values: Option<String>,
    /// COUNT values evenly spaced in log from LO to HI (0 < LO < HI); draws a log x axis.
    #[arg(long = "log-range", value_name = "LO:HI:COUNT", allow_hyphen_values = true)]
    pub log_range: Option<String>,
    /// COUNT values evenly spaced from LO to HI (LO < HI).
    #[arg(long, value_name = "LO:HI:COUNT", allow_hyphen_values = true)]
    pub range: Option<String>,
    /// Runs per value, each with its own seed.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub replicas: u32,
    /// Draw sweep.svg with a log x axis (implied by --log-range).
    #[arg(long)]
    pub log_x: bool,
    /// Output directory (default: out/<scene file stem>-sweep-<SECTION.KEY>/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores). The results do not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
}

pub(crate) fn sweep(args: &SweepArgs) -> ExitCode {
    let spec = match (&args.values, &args.log_range, &args.range) {
        (Some(v), _, _) => ValueSpec::List(v),
        (_, Some(l), _) => ValueSpec::LogRange(l),
        (_, _, Some(r)) => ValueSpec::Range(r),
        _ => unreachable!("clap requires one of --values, --log-range, --range"),
    };
    let values = match parse_values(spec) {
        Ok(v) => v,
        Err(m) => return fail(EXIT_BAD_INPUT, m),
    };
    let scene = match load_scene(&args.scene, &[]) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let log_x = args.log_x || args.log_range.is_some();
    let sweep = match Sweep::prepare(scene, &args.param, values, args.replicas as usize, log_x, args.scene.set.clone())
    {
        Ok(s) => s,
        Err(m) => return fail(EXIT_BAD_INPUT, m),
    };
    let out =
        args.out.clone().unwrap_or_else(|| Path::new("out").join(format!("{}-sweep-{}", sweep.base.name, sweep.param)));
    let created = match prepare_out_dir(&out) {
        Ok(c) => c,
        Err(m) => return fail(EXIT_BAD_INPUT, m),
    };
    let progress = std::io::stderr().is_terminal().then(|| {
        let p = ProgressBar::new(sweep.len() as u64);
        if let Ok(style) =
            ProgressStyle::with_template("{bar:40} {pos}/{len} runs, {elapsed} elapsed, about {eta} left")
        {
            p.set_style(style);
        }
        p
    });
    let result = sweep.run(args.threads.unwrap_or(0) as usize, progress.as_ref());
    if let Some(p) = &progress {
        p.finish_and_clear();
    }
    let outcome = match result
        .map_err(|e| e.to_string())
        .and_then(|o| o.write(&sweep, &out).map(|()| o).map_err(|e| e.to_string()))
    {
        Ok(o) => o,
        Err(e) => {
            remove_if_empty(&created);
            return fail(EXIT_RUN_FAILED, e);
        }
    };
    println!(
        "sweep of {} over {} values x {} replicas of scene {} ({} runs on {} threads in {:.2} s)",
        sweep.param,
        sweep.values.len(),
        sweep.replicas,
        sweep.base.name,
        sweep.len(),
        outcome.threads,
        outcome.wall_seconds
    );
    for r in &outcome.rows {
        let (m, c) = r.friction_per_junction;
        let ci = if c.is_finite() { format!(" +- {c:.6}") } else { String::new() };
        println!(
            "  {} = {:<12} F/N = {m:.6}{ci}  attached {:.4}  {} ({}/{} stick-slip)",
            sweep.param,
            r.value.text,
            r.attached_fraction_mean.0,
            r.regime.as_str(),
            (r.stick_slip_fraction * r.replicas as f64).round(),
            r.replicas
        );
    }
    println!("output in {} (sweep.csv, runs.csv, sweep.svg, sweep.json)", out.display());
    ExitCode::SUCCESS
}
