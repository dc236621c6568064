//! `stickslip sweep`: one scene field, or two for a regime map, over lists of values, with
//! replicas, in parallel.
//!
//! Each `--param SECTION.KEY` takes one value list, `--values A,B,..`, `--range LO:HI:COUNT`
//! or `--log-range LO:HI:COUNT`: the first `--param` the first list given, the second the
//! second. `--log-x` / `--log-y` draw the first / second field on a log axis (implied by
//! `--log-range`).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Arg, ArgAction, ArgMatches};
use indicatif::{ProgressBar, ProgressStyle};

use super::args::load_scene;
use super::args::{EXIT_BAD_INPUT, EXIT_RUN_FAILED, SceneArgs, fail};
use super::out_dir::{OutDir, prepare_out_dir};
use super::study;
use crate::output::Summary;
use crate::scene::error::printable;
use crate::studies::format::fixed;
use crate::studies::journal::{Header, StudyKind};
use crate::studies::sweep::{MAX_AXES, Sweep, SweepAxis, SweepError, SweepOutcome, SweepSpec, ValueSpec, parse_values};

#[derive(clap::Args, Debug)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub axes: AxisArgs,
    /// Runs per grid point, each with its own seed.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub replicas: u32,
    /// Draw the first field on a log axis of sweep.svg (implied by its --log-range).
    #[arg(long)]
    pub log_x: bool,
    /// Draw the second field on a log axis of sweep.svg (implied by its --log-range).
    #[arg(long)]
    pub log_y: bool,
    /// Output directory (default: out/<scene file stem>-sweep-<SECTION.KEY>[-<SECTION.KEY>]/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores). The results do not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
}

/// Which flag a value list came with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ListFlag {
    Values,
    Range,
    LogRange,
}

/// The swept fields and value lists as given, each list with its position on the command
/// line (clap keeps the positions; pairing needs the order).
#[derive(Clone, Debug, Default)]
pub struct AxisArgs {
    pub params: Vec<String>,
    /// `(position, flag, text)`, in command-line order.
    pub lists: Vec<(usize, ListFlag, String)>,
}

const PARAM_HELP: &str = "A scene field to sweep, as SECTION.KEY (e.g. plate.v); give it twice for a 2-D map. Each --param takes one value list (--values, --range or --log-range), in the order given";

impl clap::Args for AxisArgs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        let list = |id: &'static str, long: &'static str, name: &'static str, help: &'static str| {
            Arg::new(id)
                .long(long)
                .value_name(name)
                .help(help)
                .action(ArgAction::Append)
                .allow_hyphen_values(true)
                .value_parser(clap::value_parser!(String))
        };
        cmd.arg(
            Arg::new("param")
                .long("param")
                .value_name("SECTION.KEY")
                .help(PARAM_HELP)
                .action(ArgAction::Append)
                .value_parser(clap::value_parser!(String)),
        )
        .arg(list("values", "values", "A,B,...", "Values separated by commas (e.g. 0.1,0.5,2)"))
        .arg(list("range", "range", "LO:HI:COUNT", "COUNT values evenly spaced from LO to HI (LO < HI)"))
        .arg(list(
            "log_range",
            "log-range",
            "LO:HI:COUNT",
            "COUNT values evenly spaced in log from LO to HI (0 < LO < HI); draws a log axis",
        ))
    }
    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl clap::FromArgMatches for AxisArgs {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let params = m.get_many::<String>("param").map(|v| v.cloned().collect()).unwrap_or_default();
        let mut lists = Vec::new();
        for (id, flag) in [("values", ListFlag::Values), ("range", ListFlag::Range), ("log_range", ListFlag::LogRange)]
        {
            if let (Some(texts), Some(positions)) = (m.get_many::<String>(id), m.indices_of(id)) {
                lists.extend(positions.zip(texts).map(|(p, t)| (p, flag, t.clone())));
            }
        }
        lists.sort_by_key(|l| l.0);
        Ok(AxisArgs { params, lists })
    }
    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl ListFlag {
    fn name(self) -> &'static str {
        match self {
            ListFlag::Values => "--values",
            ListFlag::Range => "--range",
            ListFlag::LogRange => "--log-range",
        }
    }
}

/// The sweep's axes from the command line: the k-th `--param` with the k-th value list.
/// The error is one line.
pub(crate) fn axes(args: &AxisArgs, log_x: bool, log_y: bool) -> Result<Vec<SweepAxis>, String> {
    let (np, nl) = (args.params.len(), args.lists.len());
    if np == 0 {
        return Err(crate::studies::sweep::SpecError::NoAxes.to_string());
    }
    if np > MAX_AXES {
        return Err(format!("--param: {np} fields given, at most {MAX_AXES} (a 2-D sweep)"));
    }
    let named = || args.params.iter().map(|p| printable(p)).collect::<Vec<_>>().join(" and ");
    if nl == 0 {
        return Err(format!("--values, --range or --log-range: no values given for {}", named()));
    }
    if np != nl {
        let flags = args.lists.iter().map(|l| l.1.name()).collect::<Vec<_>>().join(", ");
        return Err(format!(
            "--param {}: {np} field{} but {nl} value lists ({flags}); each --param takes one of --values, --range or --log-range, in the order given",
            named(),
            if np == 1 { "" } else { "s" }
        ));
    }
    if log_y && np < 2 {
        return Err("--log-y: there is no second field (give a second --param with its values)".to_string());
    }
    args.params
        .iter()
        .zip(&args.lists)
        .enumerate()
        .map(|(k, (param, (_, flag, text)))| {
            let spec = match flag {
                ListFlag::Values => ValueSpec::List(text),
                ListFlag::Range => ValueSpec::Range(text),
                ListFlag::LogRange => ValueSpec::LogRange(text),
            };
            let values = parse_values(spec).map_err(|e| e.to_string())?;
            let log = *flag == ListFlag::LogRange || if k == 0 { log_x } else { log_y };
            Ok(SweepAxis { param: param.clone(), values, log })
        })
        .collect()
}

/// A sweep run to its end, its files written.
pub(crate) struct Finished {
    pub sweep: Sweep,
    pub outcome: SweepOutcome,
    pub out: PathBuf,
    /// The output directory, held until the caller has written its own files.
    pub held: OutDir,
}

/// Runs the sweep `args` describe into `args.out` (else `default_out(&sweep)`), keeping its
/// journal, and writes its files. `check` sees the prepared sweep before anything is
/// created or run; its error is bad input. Every failure has been reported (one line) when
/// this returns its exit code.
pub(crate) fn run_study(
    args: &SweepArgs,
    default_out: impl FnOnce(&Sweep) -> PathBuf,
    check: impl FnOnce(&Sweep) -> Result<(), String>,
) -> Result<Finished, ExitCode> {
    let axes = axes(&args.axes, args.log_x, args.log_y).map_err(|m| fail(EXIT_BAD_INPUT, m))?;
    let scene = load_scene(&args.scene, &[])?;
    let spec = SweepSpec { axes, replicas: args.replicas as usize, set: args.scene.set.clone() };
    let sweep = Sweep::prepare(scene, spec).map_err(|e| fail(EXIT_BAD_INPUT, e))?;
    check(&sweep).map_err(|m| fail(EXIT_BAD_INPUT, m))?;
    let scenes = sweep.points.iter().flat_map(|p| &p.scenes);
    let threads = crate::estimate::check::study_threads(scenes, args.threads.map(|t| t as usize), "the sweep")
        .map_err(|e| fail(EXIT_BAD_INPUT, e))?;
    let out = args.out.clone().unwrap_or_else(|| default_out(&sweep));
    let held = prepare_out_dir(&out).map_err(|m| fail(EXIT_BAD_INPUT, m))?;
    let header = Header::new(StudyKind::Sweep, sweep.arguments(), &sweep.base, sweep.len(), study::invocation());
    let mut journal = study::open::<Summary>(StudyKind::Sweep, &out, &header, &sweep.seeds())?;
    let progress = std::io::stderr().is_terminal().then(|| {
        let p = ProgressBar::new(sweep.len() as u64);
        if let Ok(style) =
            ProgressStyle::with_template("{bar:40} {pos}/{len} runs, {elapsed} elapsed, about {eta} left")
        {
            p.set_style(style);
        }
        p
    });
    let result = sweep.run_from(threads, progress.as_ref(), journal.continuation());
    if let Some(p) = &progress {
        p.finish_and_clear();
    }
    let outcome = match result {
        Ok(o) => o,
        Err(SweepError::Interrupted(e)) => return Err(study::interrupted(&e, &out)),
        Err(e) => {
            journal.discard_if_new();
            held.abandon();
            return Err(fail(EXIT_RUN_FAILED, e));
        }
    };
    if let Err(e) = outcome.write(&sweep, &out) {
        return Err(study::write_failed(e, &out));
    }
    Ok(Finished { sweep, outcome, out, held })
}

pub(crate) fn sweep(args: &SweepArgs) -> ExitCode {
    let default_out = |s: &Sweep| Path::new("out").join(format!("{}-sweep-{}", s.base.name, s.name()));
    let Finished { sweep, outcome, out, .. } = match run_study(args, default_out, |_| Ok(())) {
        Ok(f) => f,
        Err(code) => return code,
    };
    let timing = outcome.timing.expect("Sweep::run records its timing");
    let fields = sweep.axes.iter().map(|a| a.param.as_str()).collect::<Vec<_>>().join(" x ");
    let sizes = sweep.axes.iter().map(|a| a.values.len().to_string()).collect::<Vec<_>>().join(" x ");
    println!(
        "sweep of {fields} over {sizes} values x {} replicas of scene {} ({} runs on {} threads in {:.2} s)",
        sweep.replicas,
        printable(&sweep.base.name),
        sweep.len(),
        timing.threads,
        timing.wall_seconds
    );
    for r in &outcome.rows {
        let (m, c) = r.friction_per_junction;
        let ci = if c.is_finite() { format!(" +- {}", fixed(c, 6)) } else { String::new() };
        let at: Vec<String> =
            sweep.axes.iter().zip(&r.values).map(|(a, v)| format!("{} = {:<12}", a.param, v.text)).collect();
        let amplitude = r.oscillation_amplitude.0 / r.n as f64;
        println!(
            "  {} F/N = {}{ci}  attached {:.4}  amplitude/N {}  {} ({}/{} stick-slip)",
            at.join(" "),
            fixed(m, 6),
            r.attached_fraction_mean.0,
            fixed(amplitude, 4),
            r.regime.as_str(),
            (r.stick_slip_fraction * r.replicas as f64).round(),
            r.replicas
        );
    }
    println!("output in {} (sweep.csv, runs.csv, sweep.svg, sweep.json)", printable(&out.display().to_string()));
    ExitCode::SUCCESS
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(params: &[&str], lists: &[(ListFlag, &str)]) -> AxisArgs {
        AxisArgs {
            params: params.iter().map(|s| s.to_string()).collect(),
            lists: lists.iter().enumerate().map(|(i, (f, t))| (i, *f, t.to_string())).collect(),
        }
    }

    #[test]
    fn the_kth_param_takes_the_kth_list() {
        let a = axes(
            &args(&["plate.v", "plate.k"], &[(ListFlag::LogRange, "0.1:10:3"), (ListFlag::Values, "5,50")]),
            false,
            false,
        )
        .unwrap();
        assert_eq!((a[0].param.as_str(), a[0].values.len(), a[0].log), ("plate.v", 3, true));
        assert_eq!((a[1].param.as_str(), a[1].values.len(), a[1].log), ("plate.k", 2, false));
        let a =
            axes(&args(&["plate.v", "plate.k"], &[(ListFlag::Values, "1"), (ListFlag::Values, "5,50")]), false, true)
                .unwrap();
        assert!(!a[0].log && a[1].log);
    }

    #[test]
    fn mismatched_lists_are_refused_in_one_line() {
        for (p, l, mention) in [
            (vec!["plate.v"], vec![], "--values"),
            (vec!["plate.v"], vec![(ListFlag::Values, "1"), (ListFlag::Range, "0:1:3")], "--range"),
            (vec!["plate.v", "plate.k"], vec![(ListFlag::Values, "1")], "plate.k"),
            (vec!["a.b", "c.d", "e.f"], vec![], "at most 2"),
        ] {
            let e = axes(&args(&p, &l), false, false).unwrap_err();
            assert!(e.contains(mention) && !e.contains('\n'), "{e}");
        }
        assert!(axes(&args(&["plate.v"], &[(ListFlag::Values, "1")]), false, true).unwrap_err().starts_with("--log-y"));
    }
}
