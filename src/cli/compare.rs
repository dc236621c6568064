//! `stickslip compare`: the work-precision study of [`crate::studies::compare`].

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::args::load_scene;
use super::args::{EXIT_BAD_INPUT, EXIT_RUN_FAILED, SceneArgs, fail};
use super::out_dir::prepare_out_dir;
use super::study;
use crate::studies::compare::{JobRecord, Plan, StudyError, default_dts, report};
use crate::studies::journal::{Header, StudyKind};

#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Steps of the fixed engine, comma-separated (default: the scene's fixed.dt and its
    /// halvings down to fixed.dt/256).
    #[arg(long, value_name = "DT,DT,..", allow_hyphen_values = true)]
    pub dts: Option<String>,
    /// Replicas per fixed-step point; the exact points use 1, 2, 4, .. up to this many.
    #[arg(long, default_value_t = 64)]
    pub replicas: usize,
    /// Replicas of the exact reference (default: 4 x --replicas).
    #[arg(long)]
    pub ref_replicas: Option<usize>,
    /// `exact.rtol` of the exact points (default: the scene's). The reference keeps the
    /// scene's, so the points' errors include what the looser tolerance costs.
    #[arg(long, value_name = "RTOL", allow_hyphen_values = true)]
    pub exact_rtol: Option<f64>,
    /// Output directory (default: out/<scene file stem>-compare/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replicas run at a time (default: 1). Estimates do not depend on it; costs may:
    /// replicas side by side share the machine (caches, memory, and the core itself on a
    /// host that runs two virtual processors on one), so by default each is timed alone.
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Parses `--dts`: a comma-separated list of finite numbers > 0.
pub(crate) fn parse_dts(text: &str) -> Result<Vec<f64>, String> {
    let bad = |why: String| format!("--dts = {text:?}: {why} (a comma-separated list of steps > 0, e.g. 1,0.5,0.25)");
    if text.trim().is_empty() {
        return Err(bad("the list is empty".into()));
    }
    text.split(',')
        .map(|item| {
            let item = item.trim();
            if item.is_empty() {
                return Err(bad("an entry is empty".into()));
            }
            match item.parse::<f64>() {
                Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
                Ok(_) => Err(bad(format!("{item} is not allowed: each step must be a finite number > 0"))),
                Err(_) => Err(bad(format!("{item:?} is not a number"))),
            }
        })
        .collect()
}

/// The command line as typed, for the report.
fn command_line() -> String {
    quoted(&std::env::args().collect::<Vec<_>>())
}

/// A command line (program name first) as a shell reads it, `stickslip` first.
pub(crate) fn quoted(argv: &[String]) -> String {
    let quote = |a: String| {
        if !a.is_empty() && a.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=,:+".contains(c)) {
            a
        } else {
            format!("'{}'", a.replace('\'', r"'\''"))
        }
    };
    std::iter::once("stickslip".to_string())
        .chain(argv.iter().skip(1).cloned().map(quote))
        .collect::<Vec<_>>()
        .join(" ")
}

pub(crate) fn compare(args: &CompareArgs) -> ExitCode {
    compare_as(args, &command_line())
}

/// `compare`, with `command` the command line quoted in compare.md.
pub(crate) fn compare_as(args: &CompareArgs, command: &str) -> ExitCode {
    let scene = match load_scene(&args.scene, &[]) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let dts = match &args.dts {
        Some(text) => match parse_dts(text) {
            Ok(d) => d,
            Err(m) => return fail(EXIT_BAD_INPUT, m),
        },
        None => default_dts(&scene),
    };
    if args.threads == Some(0) {
        return fail(EXIT_BAD_INPUT, "--threads = 0: must be at least 1");
    }
    let ref_replicas = args.ref_replicas.unwrap_or(args.replicas.saturating_mul(4));
    let plan = match Plan::new(&scene, dts, args.replicas, ref_replicas, args.exact_rtol) {
        Ok(p) => p,
        Err(e) => return fail(EXIT_BAD_INPUT, e),
    };
    let engines = [crate::scene::EngineKind::Fixed, crate::scene::EngineKind::Exact].map(|engine| {
        let mut s = scene.clone();
        s.run.engine = engine;
        s
    });
    let threads =
        match crate::estimate::check::study_threads(engines.iter(), Some(args.threads.unwrap_or(1)), "compare") {
            Ok(t) => t,
            Err(e) => return fail(EXIT_BAD_INPUT, e),
        };
    let out = args.out.clone().unwrap_or_else(|| Path::new("out").join(format!("{}-compare", scene.name)));
    let held = match prepare_out_dir(&out) {
        Ok(h) => h,
        Err(m) => return fail(EXIT_BAD_INPUT, m),
    };
    let header = Header::new(StudyKind::Compare, plan.arguments(), &scene, plan.seeds().len(), study::invocation());
    let mut journal = match study::open::<JobRecord>(StudyKind::Compare, &out, &header, &plan.seeds()) {
        Ok(j) => j,
        Err(code) => return code,
    };
    let result = match plan.run_from(Some(threads), journal.continuation()) {
        Ok(s) => s,
        Err(StudyError::Interrupted(e)) => return study::interrupted(&e, &out),
        Err(e) => {
            journal.discard_if_new();
            held.abandon();
            return fail(EXIT_RUN_FAILED, e);
        }
    };
    if let Err(e) = result.write(&out, command) {
        return study::write_failed(e, &out);
    }
    let study = result;
    let name = crate::scene::error::printable(&scene.name);
    println!("compare {name}: {} points, reference of {} exact replicas", study.points.len(), ref_replicas);
    for line in report::reading(&study) {
        println!("{line}");
    }
    println!("output in {}", crate::scene::error::printable(&out.display().to_string()));
    ExitCode::SUCCESS
}

#[cfg(test)]
mod tests {
    use super::parse_dts;

    #[test]
    fn dts_lists() {
        assert_eq!(parse_dts("1, 0.5,0.25").unwrap(), vec![1.0, 0.5, 0.25]);
        for bad in ["", " ", "1,,2", "-1", "0", "NaN", "nan", "inf", "abc", "1;2"] {
            let e = parse_dts(bad).unwrap_err();
            assert!(e.starts_with("--dts = "), "{bad}: {e}");
            assert!(!e.contains('\n'));
        }
    }
}
