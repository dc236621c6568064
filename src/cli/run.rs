//! `stickslip run`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::args::{EXIT_BAD_INPUT, EXIT_RUN_FAILED, EngineArg, SceneArgs, fail, load_scene};
use super::out_dir::prepare_out_dir;
use super::stdout::emit;
use crate::output::Summary;
use crate::runner::{RunOptions, run_scene_with};
use crate::scene::Scene;
use crate::scene::error::compact;
use crate::studies::format::fixed;

pub(crate) fn run(
    args: &SceneArgs,
    engine: Option<EngineArg>,
    seed: Option<u64>,
    out: Option<PathBuf>,
    checkpoint_every: Option<f64>,
    threads: Option<usize>,
) -> ExitCode {
    if threads == Some(0) {
        return fail(EXIT_BAD_INPUT, "--threads = 0: must be at least 1");
    }
    let mut extra = Vec::new();
    if let Some(e) = engine {
        extra.push(format!("run.engine={}", if matches!(e, EngineArg::Exact) { "exact" } else { "fixed" }));
    }
    if let Some(s) = seed {
        extra.push(format!("run.seed={s}"));
    }
    let scene = match load_scene(args, &extra) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let out = out.unwrap_or_else(|| Path::new("out").join(&scene.name));
    // Before the output directory exists: a refused run leaves nothing behind.
    if let Err(e) = crate::estimate::check_run(&scene, &out, checkpoint_every.is_some()) {
        return fail(EXIT_BAD_INPUT, e);
    }
    let held = match prepare_out_dir(&out) {
        Ok(h) => h,
        Err(m) => return fail(EXIT_BAD_INPUT, m),
    };
    // After every bad-input check: bad input prints its one error line and nothing else.
    if let Some(w) = super::stability::warning(&scene) {
        eprintln!("{w}");
    }
    if let Some(w) = crate::engine::fixed::period_warning(&scene) {
        eprintln!("{w}");
    }
    let threads = threads.unwrap_or_else(rayon::current_num_threads);
    let opts = RunOptions { checkpoint_every, progress: true, stop: None, threads };
    match run_scene_with(&scene, Some(&out), &opts).and_then(|s| draw_plot(&scene, &out).map(|()| s)) {
        Ok(s) => emit(&summary_lines(&s, &out)),
        Err(e) => {
            // A failed run leaves no empty output directory behind.
            held.abandon();
            fail(EXIT_RUN_FAILED, e)
        }
    }
}

/// Draws `trace.svg` from the finished `trace.csv` when the scene asks for it
/// (`output.plot`, which needs `output.trace`).
pub(crate) fn draw_plot(scene: &Scene, out: &Path) -> Result<(), crate::runner::RunError> {
    if !scene.output.plot {
        return Ok(());
    }
    crate::plot::trace::write_trace_svg(out, scene)
        .map_err(|e| crate::runner::RunError::Output { path: out.join("trace.svg"), source: std::io::Error::other(e) })
}

/// The regime as the summary line gives it: an unstable run with its growth factor and
/// the largest stable step.
fn regime_text(s: &Summary) -> String {
    match (&s.stability, s.regime) {
        (Some(n), crate::observe::regime::Regime::Unstable) => format!(
            "regime unstable ({}: the plate step grows x{} per step with every junction attached; \
             largest stable dt {}, see `stickslip stability`)",
            n.unstable.map_or("seen", |c| c.as_str()),
            n.growth_factor.map_or_else(|| "undefined".to_string(), super::stability::num),
            n.largest_stable_dt.map_or_else(|| "undefined".to_string(), super::stability::num)
        ),
        _ => format!("regime {} ({} stick-slip cycles)", s.regime.as_str(), s.stick_slip_cycles),
    }
}

/// The four summary lines `run` and `resume` print, and a fifth, a warning, when the run
/// drew more numbers than the Park–Miller generator's period.
pub(crate) fn summary_lines(s: &Summary, out: &Path) -> String {
    let work = match (s.counters.steps, s.counters.events) {
        (Some(n), _) => format!("{n} steps"),
        (_, Some(n)) => format!("{n} events"),
        _ => String::new(),
    };
    let period = s.rng_period_exceeded.map_or(String::new(), |p| format!("warning: {p}\n"));
    format!(
        "scene {} ({} engine, seed {}, N = {}, t_end = {})\n\
         friction per junction {} (std of total {}) over [{}, {}]\n\
         attached fraction {:.4}; {}\n\
         {work}, {} ruptures, {} formations in {:.3} s; output in {}\n{period}",
        crate::scene::error::printable(&s.scene),
        s.engine_name(),
        s.seed,
        s.n,
        compact(s.t_end),
        fixed(s.friction_per_junction, 6),
        fixed(s.friction_std, 6),
        compact(s.t_warmup),
        compact(s.t_end),
        s.attached_fraction_mean,
        regime_text(s),
        s.counters.ruptures,
        s.counters.formations,
        s.wall_seconds,
        crate::scene::error::printable(&out.display().to_string())
    )
}
