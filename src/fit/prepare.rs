//! A fit from its inputs as `stickslip fit` and Python's `stickslip.fit` take them: the
//! data file read and checked against the scene, the free parameters parsed, the problem
//! seeded and its runs validated at the starting values; and the journal's header. Both
//! front ends use these, so they refuse the same input with the same line and keep
//! journals each can continue.

use std::path::Path;

use super::data::DataSet;
use super::free::parse_free;
use super::model::Problem;
use crate::scene::Scene;
use crate::scene::error::printable;
use crate::studies::journal::{Header, Invocation, StudyKind};

/// The problem of fitting `free` (`--free` arguments) to the data file `data` on `base`
/// (overrides applied), with `replicas` runs per point and the data's friction and sigma
/// multiplied by `friction_scale`. Errors are one line naming the file, line or field.
pub fn problem(
    base: Scene,
    data: &Path,
    free: &[String],
    replicas: usize,
    friction_scale: f64,
) -> Result<Problem, String> {
    let origin = data.display().to_string();
    let text =
        std::fs::read_to_string(data).map_err(|e| format!("cannot read data file {}: {e}", printable(&origin)))?;
    let data = DataSet::parse(&text, &origin, &base, friction_scale).map_err(|e| e.to_string())?;
    let free = parse_free(free, &base, &data)?;
    let problem = Problem::new(base, data, free, replicas).map_err(|m| format!("{}: {m}", printable(&origin)))?;
    let starts: Vec<f64> = problem.free.iter().map(|f| f.start).collect();
    problem.scenes(&starts).map_err(|e| e.to_string())?;
    Ok(problem)
}

/// The journal's header of a fit of `problem` with at most `max` evaluations.
pub fn header(problem: &Problem, max: usize, command: Option<Invocation>) -> Header {
    Header::new(StudyKind::Fit, problem.arguments(max), &problem.base, max, command)
}

/// The data file's name as `fit.json` records it.
pub fn data_name(data: &Path) -> String {
    data.file_name().map_or_else(|| data.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// The folder of a fit's output directory where a fit started without a command line
/// (from Python) keeps its scene, for `stickslip resume`.
pub const INPUT_DIR: &str = "input";

/// What `stickslip resume DIR` needs of a fit started from Python: its scene (overrides
/// applied) written whole to `DIR/input/<scene name>.toml` (the name is the file's stem,
/// and the scene read back is the same scene: the journal's fingerprint holds), and the
/// `stickslip fit` command line of the same fit on that file, with absolute paths.
pub fn python_invocation(
    problem: &Problem,
    data: &Path,
    free: &[String],
    friction_scale: f64,
    max: usize,
    out: &Path,
) -> std::io::Result<Invocation> {
    let cwd = std::env::current_dir()?;
    let absolute = |p: &Path| cwd.join(p).to_string_lossy().into_owned();
    let dir = out.join(INPUT_DIR);
    std::fs::create_dir_all(&dir)?;
    let text = toml::to_string(&problem.base.to_file()).expect("a scene always serializes");
    let scene = crate::output::atomic::write_whole(&dir, &format!("{}.toml", problem.base.name), text.as_bytes())?;
    let mut argv: Vec<String> = vec!["stickslip".into(), "fit".into(), absolute(&scene), absolute(data)];
    for f in free {
        argv.extend(["--free".into(), f.clone()]);
    }
    argv.extend([
        "--replicas".into(),
        problem.replicas.to_string(),
        "--friction-scale".into(),
        friction_scale.to_string(),
        "--max-evaluations".into(),
        max.to_string(),
        "--out".into(),
        absolute(out),
    ]);
    Ok(Invocation { argv, cwd })
}
