//! Where a map comes from: a sweep just run ([`from_outcome`]) or a finished sweep's
//! directory ([`read_sweep_dir`]: its `sweep.json` and `runs.csv`). Either way the
//! sweep must be a 2-D map over `plate.v` and `junctions.temperature`.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::points::{PointRuns, RunRecord};
use super::scales::Scales;
use crate::observe::regime::Regime;
use crate::scene::error::{compact, printable};
use crate::studies::journal;
use crate::studies::sweep::{Sweep, SweepOutcome};

/// The velocity field.
pub const V_FIELD: &str = "plate.v";
/// The temperature field.
pub const T_FIELD: &str = "junctions.temperature";

/// A map's runs, grouped by grid point (in the sweep's order).
#[derive(Clone, Debug, PartialEq)]
pub struct LawInput {
    /// The scene's name.
    pub scene: String,
    pub replicas: usize,
    pub points: Vec<PointRuns>,
}

/// Why a map cannot make a law: one line.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SourceError {
    #[error(
        "{context}: the sweep's fields are {found}; a friction law needs a 2-D sweep over {V_FIELD} and {T_FIELD} (--param {V_FIELD} ... --param {T_FIELD} ...)"
    )]
    NotVT { context: String, found: String },
    #[error("--from {dir}: not a directory")]
    NoDir { dir: String },
    #[error(
        "--from {dir}: holds no sweep (no sweep.json, no journal.jsonl); give the output directory of `stickslip sweep`"
    )]
    NoSweep { dir: String },
    #[error(
        "--from {dir}: the sweep has not finished ({done} of {total} runs in journal.jsonl{files}); continue it with `stickslip resume {dir}`, then make the law"
    )]
    Unfinished { dir: String, done: usize, total: usize, files: &'static str },
    #[error("--from {path}: {why}")]
    Damaged { path: String, why: String },
    #[error("{field} = {value}: the friction law needs {field} > 0 (it is fitted in ln V and 1/T)")]
    NotPositive { field: &'static str, value: f64 },
    #[error(
        "{field} = {}: the law's {what} would be {} {unit}, not a normal positive number (from 2.2e-308 to 1.8e308)",
        compact(*value), compact(*physical)
    )]
    Unrepresentable { field: &'static str, value: f64, what: &'static str, physical: f64, unit: &'static str },
    #[error(
        "{T_FIELD} = {}: the friction law is fitted in 1/T and its square, which needs {T_FIELD} from {}",
        compact(*value), compact(T_MIN)
    )]
    TooCold { value: f64 },
    #[error("{field} = {value} and {other} = {other_value}: the grid point is there twice")]
    Duplicate { field: &'static str, value: f64, other: &'static str, other_value: f64 },
}

/// The positions of `plate.v` and `junctions.temperature` among `params`.
pub fn vt_axes(params: &[&str], context: &str) -> Result<(usize, usize), SourceError> {
    let v = params.iter().position(|p| *p == V_FIELD);
    let t = params.iter().position(|p| *p == T_FIELD);
    match (v, t) {
        (Some(v), Some(t)) if params.len() == 2 => Ok((v, t)),
        _ => Err(SourceError::NotVT { context: context.to_string(), found: printable(&params.join(" x ")) }),
    }
}

fn regime(text: &str) -> Option<Regime> {
    [Regime::Smooth, Regime::StickSlip, Regime::Unstable].into_iter().find(|r| r.as_str() == text)
}

/// The map of a sweep run in this process.
pub fn from_outcome(sweep: &Sweep, outcome: &SweepOutcome) -> Result<LawInput, SourceError> {
    let params: Vec<&str> = sweep.axes.iter().map(|a| a.param.as_str()).collect();
    let (iv, it) = vt_axes(&params, "--param")?;
    let points = sweep
        .points
        .iter()
        .zip(&outcome.summaries)
        .map(|(p, runs)| PointRuns {
            v: p.values[iv].x,
            t: p.values[it].x,
            runs: runs
                .iter()
                .map(|s| RunRecord {
                    friction_mean: s.friction_mean,
                    friction_per_junction: s.friction_per_junction,
                    regime: s.regime,
                })
                .collect(),
        })
        .collect();
    Ok(LawInput { scene: sweep.base.name.clone(), replicas: sweep.replicas, points })
}

/// What `sweep.json` holds that the law reads.
#[derive(Deserialize)]
struct SweepRecord {
    scene: String,
    param: String,
    values: Vec<String>,
    param2: Option<String>,
    values2: Option<Vec<String>>,
    replicas: usize,
    seeds: Vec<Vec<u64>>,
}

/// Runs in the journal of `dir` and the study's total, if it has a readable header.
fn journal_count(dir: &Path) -> Option<(usize, usize)> {
    let header = journal::read_header(dir).ok()??;
    let text = std::fs::read(journal::path_in(dir)).ok()?;
    let whole = text.iter().filter(|&&b| b == b'\n').count();
    Some((whole.saturating_sub(1), header.runs))
}

/// The map of a finished sweep's directory: `sweep.json` (fields, values, replicas, seeds)
/// and `runs.csv` (every run's friction and regime). A sweep whose journal holds fewer
/// runs than the study, or without `sweep.json`, has not finished.
pub fn read_sweep_dir(dir: &Path) -> Result<LawInput, SourceError> {
    let shown = printable(&dir.display().to_string());
    if !dir.is_dir() {
        return Err(SourceError::NoDir { dir: shown });
    }
    let record_path = dir.join("sweep.json");
    let counted = journal_count(dir);
    match (counted, record_path.exists()) {
        (Some((done, total)), has) if done < total || !has => {
            let files = if has { "" } else { ", no sweep.json" };
            return Err(SourceError::Unfinished { dir: shown, done, total, files });
        }
        (None, false) => return Err(SourceError::NoSweep { dir: shown }),
        _ => {}
    }
    let damaged = |path: &PathBuf, why: String| SourceError::Damaged {
        path: printable(&path.display().to_string()),
        why: printable(&why),
    };
    let text = std::fs::read_to_string(&record_path).map_err(|e| damaged(&record_path, e.to_string()))?;
    let rec: SweepRecord = serde_json::from_str(&text).map_err(|e| damaged(&record_path, e.to_string()))?;
    let mut params = vec![rec.param.as_str()];
    params.extend(rec.param2.as_deref());
    let (iv, it) = vt_axes(&params, &format!("--from {shown}"))?;
    let number = |s: &String| {
        s.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| damaged(&record_path, format!("value '{s}' is not a number")))
    };
    let axes = [
        rec.values.iter().map(number).collect::<Result<Vec<f64>, _>>()?,
        rec.values2.as_ref().map_or(Ok(Vec::new()), |v| v.iter().map(number).collect())?,
    ];
    let grid: Vec<[f64; 2]> = axes[0].iter().flat_map(|&a| axes[1].iter().map(move |&b| [a, b])).collect();
    if rec.replicas == 0 || rec.seeds.len() != grid.len() || rec.seeds.iter().any(|s| s.len() != rec.replicas) {
        return Err(damaged(&record_path, "its seeds are not one per grid point and replica".to_string()));
    }
    let runs_path = dir.join("runs.csv");
    let runs_text = std::fs::read_to_string(&runs_path).map_err(|e| damaged(&runs_path, e.to_string()))?;
    let mut lines = runs_text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let col = |name: &str| {
        header.iter().position(|h| *h == name).ok_or_else(|| damaged(&runs_path, format!("no column {name}")))
    };
    let (cv, ct) = (col(params[iv])?, col(params[it])?);
    let (cseed, cf, cfj, creg) = (col("seed")?, col("friction_mean")?, col("friction_per_junction")?, col("regime")?);
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    if rows.len() != grid.len() * rec.replicas {
        return Err(damaged(
            &runs_path,
            format!("{} rows for {} grid points x {} replicas", rows.len(), grid.len(), rec.replicas),
        ));
    }
    let mut points = Vec::with_capacity(grid.len());
    for (g, xy) in grid.iter().enumerate() {
        let (v, t) = (xy[iv], xy[it]);
        let mut runs = Vec::with_capacity(rec.replicas);
        for r in 0..rec.replicas {
            let k = g * rec.replicas + r;
            let row = &rows[k];
            let bad = |why: String| damaged(&runs_path, format!("line {}: {why}", k + 2));
            let cell = |c: usize| row.get(c).copied().ok_or_else(|| bad(format!("{} fields", row.len())));
            let num = |c: usize| {
                let s = cell(c)?;
                s.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| bad(format!("'{s}' is not a number")))
            };
            if num(cv)? != v || num(ct)? != t {
                return Err(bad(format!(
                    "not the grid point {} = {v}, {} = {t} of sweep.json",
                    params[iv], params[it]
                )));
            }
            if cell(cseed)?.parse::<u64>().ok() != Some(rec.seeds[g][r]) {
                return Err(bad(format!("not the seed {} of sweep.json", rec.seeds[g][r])));
            }
            let regime = regime(cell(creg)?).ok_or_else(|| bad(format!("regime '{}'", cell(creg).unwrap_or(""))))?;
            runs.push(RunRecord { friction_mean: num(cf)?, friction_per_junction: num(cfj)?, regime });
        }
        points.push(PointRuns { v, t, runs });
    }
    Ok(LawInput { scene: rec.scene, replicas: rec.replicas, points })
}

/// The least temperature a law is fitted at: `1/T` and its square stay finite.
pub const T_MIN: f64 = 1e-150;

/// Checks that every `V` and `T` is > 0, that `T` is at least [`T_MIN`], that the slip rate
/// and the temperature in kelvin are positive normal numbers in `scales`, and that no grid
/// point is there twice; returns the points sorted by `T`, then `V` (the order of the tables).
pub fn checked_points<'a>(input: &'a LawInput, scales: &Scales) -> Result<Vec<&'a PointRuns>, SourceError> {
    for p in &input.points {
        if p.v.is_nan() || p.v <= 0.0 {
            return Err(SourceError::NotPositive { field: V_FIELD, value: p.v });
        }
        if p.t.is_nan() || p.t <= 0.0 {
            return Err(SourceError::NotPositive { field: T_FIELD, value: p.t });
        }
        if p.t < T_MIN {
            return Err(SourceError::TooCold { value: p.t });
        }
        let (slip, kelvin) = (scales.slip_rate(p.v), scales.kelvin(p.t));
        if !slip.is_normal() {
            let (field, what, unit) = (V_FIELD, "slip rate V l0 / t0", "m/s");
            return Err(SourceError::Unrepresentable { field, value: p.v, what, physical: slip, unit });
        }
        if !kelvin.is_normal() {
            let (field, what, unit) = (T_FIELD, "temperature T t_ref", "K");
            return Err(SourceError::Unrepresentable { field, value: p.t, what, physical: kelvin, unit });
        }
    }
    let mut sorted: Vec<&PointRuns> = input.points.iter().collect();
    sorted.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.v.total_cmp(&b.v)));
    if let Some(w) = sorted.windows(2).find(|w| w[0].v == w[1].v && w[0].t == w[1].t) {
        return Err(SourceError::Duplicate { field: V_FIELD, value: w[0].v, other: T_FIELD, other_value: w[0].t });
    }
    Ok(sorted)
}
