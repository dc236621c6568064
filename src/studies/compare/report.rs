//! The study's files: `compare.csv` (every number), `compare.md` (tables and a reading).
//!
//! **The reading** answers "at what accuracy does each engine win, and by how much" with a
//! cost model whose every input is measured by the study. To reach a root-mean-square error
//! `e` in an observable:
//! - the exact engine needs `max(1, sd_ref^2 / e^2)` replicas at `c_exact` seconds each
//!   (`sd_ref` the reference's spread over replicas, `c_exact` the mean wall time of the
//!   study's exact replicas): it has no bias, so only sampling error;
//! - the fixed engine at step `dt` has bias `b(dt)` (its measured error), so it reaches `e`
//!   only if `e > |b|`, with `max(1, sd^2 / (e^2 - b^2))` replicas at `c(dt)` seconds each
//!   (`sd`, `c` its own spread and mean wall time per replica); the cheapest stable `dt` is
//!   taken.
//!
//! The ratio of the two costs is evaluated on a logarithmic grid of `e`, from twice the
//! reference's standard error (smaller errors cannot be resolved against this reference) to
//! the larger of one exact replica's spread and the largest measured bias. The cost curves
//! can cross more than once (when one exact replica costs less than one fixed-step replica,
//! both engines need a single replica at large errors and the exact engine wins there
//! again), so the reading names every range of the grid where each engine is cheaper.

use std::fmt::Write as _;

use super::fit::{BiasFit, bias_fit};
use super::{Observable, Point, Status, Study};
use crate::output::csv::push_f64;
use crate::scene::EngineKind;
use crate::studies::format::sig;

fn cell(line: &mut String, v: f64) {
    line.push(',');
    if v.is_finite() {
        push_f64(line, v);
    }
}

/// The columns of `compare.csv`; `wall_seconds` and `cpu_seconds` are the only ones that
/// depend on the machine and its load.
pub fn csv_header(observables: &[Observable]) -> String {
    let mut h = String::from(
        "engine,dt,replicas,simulated_time,status,diverged_replicas,plate_growth,wall_seconds,cpu_seconds",
    );
    for o in observables {
        for c in ["estimate", "se", "error", "ci_low", "ci_high", "floor"] {
            let _ = write!(h, ",{}_{c}", o.key());
        }
    }
    h
}

/// `compare.csv`: the reference row, then one row per point (exact, then fixed).
pub fn csv(study: &Study) -> String {
    let t_end = study.scene.run.t_end;
    let mut out = csv_header(&study.observables);
    out.push('\n');
    let r = &study.reference;
    let mut line = String::from("reference,");
    let _ = write!(line, ",{}", r.replicas);
    cell(&mut line, r.replicas as f64 * t_end);
    line.push_str(",ok,0,");
    cell(&mut line, r.wall_seconds);
    cell(&mut line, r.cpu_seconds);
    for s in &r.stats {
        cell(&mut line, s.mean);
        cell(&mut line, s.se);
        line.push_str(",,,,");
    }
    out.push_str(&line);
    out.push('\n');
    for p in &study.points {
        let mut line = String::from(engine_name(p.engine));
        cell(&mut line, p.dt.unwrap_or(f64::NAN));
        let _ = write!(line, ",{}", p.replicas);
        cell(&mut line, p.replicas as f64 * t_end);
        let _ = write!(line, ",{},{}", p.status.as_str(), p.diverged_replicas);
        cell(&mut line, p.plate_growth.unwrap_or(f64::NAN));
        cell(&mut line, p.wall_seconds);
        cell(&mut line, p.cpu_seconds);
        for o in &p.obs {
            for v in [o.estimate, o.se, o.error, o.ci_low, o.ci_high, o.floor] {
                cell(&mut line, v);
            }
        }
        out.push_str(&line);
        out.push('\n');
    }
    out
}

fn engine_name(e: EngineKind) -> &'static str {
    match e {
        EngineKind::Exact => "exact",
        EngineKind::Fixed => "fixed",
    }
}

/// A step, as short as it reads back exactly.
fn dt_label(dt: f64) -> String {
    format!("{dt}")
}

/// The cost (seconds) of the cheapest way each engine reaches RMS error `e`.
struct CostModel {
    /// Exact engine: seconds per replica and spread of one replica.
    c_exact: f64,
    sd_exact: f64,
    /// Fixed engine, stable points: (dt, seconds per replica, spread, bias).
    fixed: Vec<(f64, f64, f64, f64)>,
}

impl CostModel {
    fn new(study: &Study, i: usize, fit: Option<&BiasFit>) -> CostModel {
        let fit = fit.filter(|f| f.accepted());
        let fixed = study
            .points
            .iter()
            .filter(|p| p.engine == EngineKind::Fixed && p.status == Status::Ok && p.obs[i].error.is_finite())
            .map(|p| {
                let o = &p.obs[i];
                let dt = p.dt.unwrap();
                let bias = fit.map_or(o.error, |f| f.at(dt).0);
                (dt, p.wall_seconds / p.replicas as f64, o.se * (p.replicas as f64).sqrt(), bias)
            })
            .collect();
        CostModel { c_exact: exact_cost_per_replica(study), sd_exact: study.reference.stats[i].sd, fixed }
    }
    fn exact(&self, e: f64) -> f64 {
        self.c_exact * (self.sd_exact * self.sd_exact / (e * e)).max(1.0)
    }
    /// Cheapest fixed cost and its step; `None` if no step reaches `e`.
    fn fixed(&self, e: f64) -> Option<(f64, f64)> {
        self.fixed
            .iter()
            .filter(|f| e > f.3.abs())
            .map(|&(dt, c, sd, b)| (c * (sd * sd / (e * e - b * b)).max(1.0), dt))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }
}

/// `error` and, in parentheses, as a percentage of `reference`.
fn with_pct(error: f64, reference: f64) -> String {
    with_pct_to(error, reference, 2)
}

/// [`with_pct`] to `digits` significant digits.
fn with_pct_to(error: f64, reference: f64, digits: usize) -> String {
    if reference != 0.0 && reference.is_finite() {
        format!("{} ({} %)", sig(error, digits), sig(100.0 * error / reference.abs(), digits))
    } else {
        sig(error, digits)
    }
}

/// Mean cost of one exact replica (wall seconds), over the reference and the exact points;
/// over the points alone when they run at another tolerance than the reference
/// (`--exact-rtol`).
fn exact_cost_per_replica(study: &Study) -> f64 {
    let exact = study.points.iter().filter(|p| p.engine == EngineKind::Exact);
    // The reference's replicas cost what the points' do only at the same tolerance.
    let (ref_wall, ref_reps) = match study.exact_rtol {
        None => (study.reference.wall_seconds, study.reference.replicas),
        Some(_) => (0.0, 0),
    };
    let wall: f64 = exact.clone().map(|p| p.wall_seconds).sum::<f64>() + ref_wall;
    let reps: usize = exact.map(|p| p.replicas).sum::<usize>() + ref_reps;
    wall / reps as f64
}

/// The fitted bias of every observable at `dt`, as text.
fn fitted_biases(study: &Study, fits: &[Option<BiasFit>], dt: f64) -> String {
    study
        .observables
        .iter()
        .enumerate()
        .map(|(i, o)| match &fits[i] {
            Some(f) if f.accepted() => {
                let (b, se) = f.at(dt);
                format!("{} {} +- {}", o.key(), with_pct(b, study.reference.stats[i].mean), sig(se, 1))
            }
            _ => format!("{} (no bias model)", o.key()),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The first line of the reading: the per-replica costs, the step at which they are equal,
/// and the fitted bias there and at the largest stable step.
fn cost_line(study: &Study, fits: &[Option<BiasFit>]) -> String {
    let c_e = exact_cost_per_replica(study);
    // Stable fixed points, largest step first.
    let mut fixed: Vec<&Point> =
        study.points.iter().filter(|p| p.engine == EngineKind::Fixed && p.status == Status::Ok).collect();
    fixed.sort_by(|a, b| b.dt.unwrap().total_cmp(&a.dt.unwrap()));
    if fixed.is_empty() {
        return format!("One exact replica costs {} s; no fixed-step point is stable.", sig(c_e, 2));
    }
    let cost = |p: &Point| p.wall_seconds / p.replicas as f64;
    let (first, last) = (fixed[0], fixed[fixed.len() - 1]);
    let (dt0, dt1) = (first.dt.unwrap(), last.dt.unwrap());
    let head = format!("Per replica, the exact engine costs {} s (wall); the fixed-step engine", sig(c_e, 2));
    let range = if fixed.len() == 1 {
        format!("{} s at dt = {}", sig(cost(first), 2), dt_label(dt0))
    } else {
        format!(
            "{} s at dt = {} to {} s at dt = {}",
            sig(cost(first), 2),
            dt_label(dt0),
            sig(cost(last), 2),
            dt_label(dt1)
        )
    };
    if cost(first) >= c_e {
        return format!(
            "{head} costs more at every stable step tried ({range}), by at least x{}, and is biased on top (fitted \
             bias at dt = {}: {}).",
            sig(cost(first) / c_e, 2),
            dt_label(dt0),
            fitted_biases(study, fits, dt0)
        );
    }
    if cost(last) < c_e {
        return format!(
            "{head} costs less at every stable step tried ({range}); fitted bias at dt = {}: {}; at dt = {}: {}.",
            dt_label(dt0),
            fitted_biases(study, fits, dt0),
            dt_label(dt1),
            fitted_biases(study, fits, dt1)
        );
    }
    // Log-log interpolation of the step at which the costs are equal.
    let k = fixed.windows(2).position(|w| cost(w[0]) < c_e && cost(w[1]) >= c_e).unwrap_or(0);
    let (a, b) = (fixed[k], fixed[k + 1]);
    let f = (c_e / cost(a)).ln() / (cost(b) / cost(a)).ln();
    let dt_eq = (a.dt.unwrap().ln() + f * (b.dt.unwrap().ln() - a.dt.unwrap().ln())).exp();
    format!(
        "{head} costs as much at dt = {} ({range}), where its fitted bias is {}. Larger steps are cheaper, by up to \
         x{} at dt = {}, and more biased ({}).",
        sig(dt_eq, 2),
        fitted_biases(study, fits, dt_eq),
        sig(c_e / cost(first), 2),
        dt_label(dt0),
        fitted_biases(study, fits, dt0)
    )
}

/// A point of the reading's grid: error, exact cost, cheapest fixed cost and its step.
type GridPoint = (f64, f64, Option<(f64, f64)>);

/// Whether the fixed-step engine is the cheaper at `g`.
fn fixed_wins(g: &GridPoint) -> bool {
    g.2.is_some_and(|(c, _)| c < g.1)
}

/// Fixed cost over exact cost at `g` (infinite where no step gets there).
fn ratio(g: &GridPoint) -> f64 {
    g.2.map_or(f64::INFINITY, |(c, _)| c / g.1)
}

/// Both engines' costs at `g`, as text.
fn costs_at(g: &GridPoint, reference: f64) -> String {
    match g.2 {
        Some((c, dt)) => format!(
            "at error {}: exact {} s, fixed {} s at dt = {}",
            with_pct(g.0, reference),
            sig(g.1, 2),
            sig(c, 2),
            dt_label(dt)
        ),
        None => format!("at error {}: exact {} s, no step tried gets there", with_pct(g.0, reference), sig(g.1, 2)),
    }
}

/// The maximal runs of consecutive grid points on which the same engine is the cheaper:
/// (fixed-step cheaper, first index, last index).
fn runs(grid: &[GridPoint]) -> Vec<(bool, usize, usize)> {
    let mut out: Vec<(bool, usize, usize)> = Vec::new();
    for (k, g) in grid.iter().enumerate() {
        let fixed = fixed_wins(g);
        match out.last_mut() {
            Some(run) if run.0 == fixed => run.2 = k,
            _ => out.push((fixed, k, k)),
        }
    }
    out
}

/// Where on the grid one engine is the cheaper, by the errors that bound it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Range {
    Below(f64),
    Above(f64),
    Between(f64, f64),
    At(f64),
}

/// The ranges of the runs of one engine (`fixed`), of a grid on which each engine wins
/// somewhere. Every bound is an end of a run of the fixed-step engine: its ranges include
/// their bounds, the exact engine's exclude them.
fn ranges(grid: &[GridPoint], runs: &[(bool, usize, usize)], fixed: bool) -> Vec<Range> {
    let e = |k: usize| grid[k].0;
    let last = grid.len() - 1;
    let range = |&(_, s, t): &(bool, usize, usize)| match (fixed, s, t) {
        (true, s, t) if s == t => Range::At(e(s)),
        (true, 0, t) => Range::Below(e(t)),
        (true, s, t) if t == last => Range::Above(e(s)),
        (true, s, t) => Range::Between(e(s), e(t)),
        (false, 0, t) => Range::Below(e(t + 1)),
        (false, s, t) if t == last => Range::Above(e(s - 1)),
        (false, s, t) => Range::Between(e(s - 1), e(t + 1)),
    };
    runs.iter().filter(|r| r.0 == fixed).map(range).collect()
}

/// The fewest significant digits, at least 2, at which distinct `values` print distinct.
fn distinct_digits(values: &[f64]) -> usize {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    v.dedup();
    (2..6).find(|&d| v.windows(2).all(|w| sig(w[0], d) != sig(w[1], d))).unwrap_or(6)
}

/// `ranges` as text, e.g. "below error A, between B and C and above D", the errors to
/// `digits` significant digits.
fn ranges_text(ranges: &[Range], reference: f64, digits: usize) -> String {
    let e = |v: f64| with_pct_to(v, reference, digits);
    let parts: Vec<String> = ranges
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let (one, two) = if i == 0 { ("error ", "errors ") } else { ("", "") };
            match *r {
                Range::Below(a) => format!("below {one}{}", e(a)),
                Range::Above(a) => format!("above {one}{}", e(a)),
                Range::At(a) => format!("at {one}{}", e(a)),
                Range::Between(a, b) => format!("between {two}{} and {}", e(a), e(b)),
            }
        })
        .collect();
    match parts.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        _ => parts.concat(),
    }
}

/// The reading of a grid on which each engine is the cheaper somewhere: every range of
/// each, an example of the exact engine's (the smallest error where it wins) and the
/// fixed-step engine's largest factor.
fn split_reading(grid: &[GridPoint], reference: f64) -> String {
    let runs = runs(grid);
    let (exact, fixed) = (ranges(grid, &runs, false), ranges(grid, &runs, true));
    let bounds: Vec<f64> = exact
        .iter()
        .flat_map(|r| match *r {
            Range::Below(a) | Range::Above(a) | Range::At(a) => vec![a],
            Range::Between(a, b) => vec![a, b],
        })
        .collect();
    let digits = distinct_digits(&bounds);
    // With one crossing the fixed-step range is the other side of the exact engine's bound.
    let fixed_text = match (runs.len(), fixed.as_slice()) {
        (2, [Range::Below(_)]) => "below it".to_string(),
        (2, [Range::Above(_)]) => "above it".to_string(),
        _ => ranges_text(&fixed, reference, digits),
    };
    let example = grid.iter().find(|g| !fixed_wins(g)).unwrap();
    let best = grid.iter().filter(|g| fixed_wins(g)).min_by(|a, b| ratio(a).total_cmp(&ratio(b))).unwrap();
    format!(
        "the exact engine is cheaper {} ({}); the fixed-step engine is cheaper {fixed_text}, by up to x{} ({}).",
        ranges_text(&exact, reference, digits),
        costs_at(example, reference),
        sig(1.0 / ratio(best), 2),
        costs_at(best, reference)
    )
}

/// The examples of a grid on which the exact engine is cheaper everywhere: both engines'
/// costs at the smallest error and where the fixed-step engine comes closest, or the first
/// alone when that is where it comes closest (or no step gets to any error of the grid).
fn exact_examples(grid: &[GridPoint], reference: f64) -> String {
    let closest = (0..grid.len()).min_by(|&a, &b| ratio(&grid[a]).total_cmp(&ratio(&grid[b]))).unwrap_or(0);
    let first = costs_at(&grid[0], reference);
    if closest == 0 { first } else { format!("{first}; {}", costs_at(&grid[closest], reference)) }
}

/// The reading: the per-replica cost line, then one line per observable saying where each
/// engine is cheaper and by what factor.
pub fn reading(study: &Study) -> Vec<String> {
    let fits: Vec<Option<BiasFit>> = (0..study.observables.len()).map(|i| bias_fit(study, i)).collect();
    let mut lines = vec![cost_line(study, &fits)];
    for (i, o) in study.observables.iter().enumerate() {
        let m = CostModel::new(study, i, fits[i].as_ref());
        let reference = study.reference.stats[i].mean;
        let se_ref = study.reference.stats[i].se;
        let max_bias = m.fixed.iter().map(|f| f.3.abs()).fold(0.0, f64::max);
        let (lo, hi) = (2.0 * se_ref, m.sd_exact.max(max_bias));
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
            lines.push(format!("`{}`: not enough data for a reading.", o.key()));
            continue;
        }
        let n = 60;
        let grid: Vec<GridPoint> = (0..=n)
            .map(|k| {
                let e = lo * (hi / lo).powf(k as f64 / n as f64);
                (e, m.exact(e), m.fixed(e))
            })
            .collect();
        let mut line = format!("`{}`: ", o.key());
        let fixed_anywhere = grid.iter().any(fixed_wins);
        let exact_anywhere = grid.iter().any(|g| !fixed_wins(g));
        match (fixed_anywhere, exact_anywhere) {
            (false, _) => {
                let _ = write!(
                    line,
                    "the exact engine is cheaper at every error from {} to {}; {}.",
                    with_pct(lo, reference),
                    with_pct(hi, reference),
                    exact_examples(&grid, reference)
                );
            }
            (true, false) => {
                let at = grid.iter().max_by(|a, b| ratio(a).total_cmp(&ratio(b))).unwrap();
                let _ = write!(
                    line,
                    "the fixed-step engine is cheaper at every error from {} to {}, by at least x{} ({}).",
                    with_pct(lo, reference),
                    with_pct(hi, reference),
                    sig(1.0 / ratio(at), 2),
                    costs_at(at, reference)
                );
            }
            (true, true) => line.push_str(&split_reading(&grid, reference)),
        }
        lines.push(line);
    }
    lines
}

/// `compare.md`: what was run, the reading, one table per observable.
pub fn markdown(study: &Study, command: &str) -> String {
    let s = &study.scene;
    let j = &s.junctions;
    let mut md = String::new();
    let _ = writeln!(md, "# Work-precision comparison: `{}`\n", s.name);
    let _ = writeln!(md, "Command: `{command}`\n");
    let _ = writeln!(
        md,
        "Scene: N = {}, {:?} bonds, {:?} force law, V = {}, window [{}, {}]. Reference: exact engine, {} replicas \
         ({} s). Fixed-step points: {} replicas each. Exact points: 1 to {} replicas of the same window{}. Error = \
         estimate - reference, with its 95 % interval; floor = its standard deviation from sampling alone. Wall \
         times are summed over replicas (one core){}.\n",
        j.n,
        j.bond,
        j.force_law,
        s.plate.v,
        s.run.t_warmup,
        s.run.t_end,
        study.reference.replicas,
        sig(study.reference.wall_seconds, 3),
        study.replicas,
        study.replicas,
        match study.exact_rtol {
            Some(r) => format!(
                ", at exact.rtol = {} (the reference at the scene's {}; their errors include what the looser \
                 tolerance costs)",
                ryu::Buffer::new().format(r),
                ryu::Buffer::new().format(s.exact.rtol)
            ),
            None => String::new(),
        },
        if study.threads == 1 {
            ", replicas run one at a time".to_string()
        } else {
            format!(
                ", replicas run {} at a time (side by side they share the machine, and each replica's time includes \
                 what that costs it)",
                study.threads
            )
        }
    );
    let _ = writeln!(md, "## Reading\n");
    for l in reading(study) {
        let _ = writeln!(md, "- {l}");
    }
    let _ = writeln!(
        md,
        "\n(Cost to reach an RMS error e: exact `c sd^2/e^2`, fixed at dt `c(dt) sd(dt)^2/(e^2 - b(dt)^2)`, at least \
         one replica; c, sd, b measured here. See `src/studies/compare/report.rs`.)\n"
    );
    let bad: Vec<String> = study
        .points
        .iter()
        .filter(|p| p.status != Status::Ok)
        .map(|p| {
            let g = growth_text(p.plate_growth);
            match p.status {
                Status::Diverged => format!(
                    "dt = {}: diverged in {} of {} replicas (plate growth factor {g} per step)",
                    dt_label(p.dt.unwrap()),
                    p.diverged_replicas,
                    p.replicas
                ),
                _ => format!(
                    "dt = {}: unstable (plate growth factor {g} per step with every junction attached); its numbers \
                     are the scheme's, not the model's",
                    dt_label(p.dt.unwrap())
                ),
            }
        })
        .collect();
    if !bad.is_empty() {
        let _ = writeln!(md, "Beyond the plate step's stability: {}.\n", bad.join("; "));
    }
    for (i, o) in study.observables.iter().enumerate() {
        let r = &study.reference.stats[i];
        let _ = writeln!(
            md,
            "## {} (`{}`)\n\nReference {} +- {} (standard error; spread of one replica {}).\n",
            o.label(),
            o.key(),
            sig(r.mean, 6),
            sig(r.se, 2),
            sig(r.sd, 3)
        );
        let _ = writeln!(
            md,
            "| engine | dt | replicas | wall s | cpu s | status | estimate | error | 95 % interval | floor |"
        );
        let _ = writeln!(md, "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
        for p in &study.points {
            let ob = &p.obs[i];
            let dt = p.dt.map(dt_label).unwrap_or_else(|| "-".into());
            let status = match p.status {
                Status::Diverged => format!("diverged ({}/{})", p.diverged_replicas, p.replicas),
                st => st.as_str().to_string(),
            };
            let interval = if ob.ci_low.is_finite() {
                format!("[{}, {}]", sig(ob.ci_low, 3), sig(ob.ci_high, 3))
            } else {
                "-".to_string()
            };
            let _ = writeln!(
                md,
                "| {} | {dt} | {} | {} | {} | {status} | {} | {} | {interval} | {} |",
                engine_name(p.engine),
                p.replicas,
                sig(p.wall_seconds, 3),
                sig(p.cpu_seconds, 3),
                sig(ob.estimate, 6),
                sig(ob.error, 3),
                sig(ob.floor, 2)
            );
        }
        md.push('\n');
    }
    md
}

/// A point's plate growth factor per step as the reports print it: three significant
/// digits, "beyond 1e308" when it overflows (a plate constant near the floating-point
/// limit), "unknown" when it was not computed.
pub(crate) fn growth_text(growth: Option<f64>) -> String {
    match growth {
        Some(g) if g.is_finite() => sig(g, 3),
        Some(g) if g > 0.0 => "beyond 1e308".to_string(),
        _ => "unknown".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::studies::compare::{PointObs, Reference};

    /// The exact replica's cost counts the reference's replicas only when they ran at the
    /// points' tolerance.
    #[test]
    fn the_reference_counts_in_the_exact_cost_only_at_the_same_tolerance() {
        let point = |replicas: usize, wall: f64| Point {
            engine: EngineKind::Exact,
            dt: None,
            replicas,
            wall_seconds: wall,
            cpu_seconds: wall,
            status: Status::Ok,
            diverged_replicas: 0,
            plate_growth: None,
            obs: Vec::new(),
        };
        let mut study = Study {
            scene: crate::test_scenes::fig1(),
            observables: Vec::new(),
            replicas: 4,
            exact_rtol: None,
            reference: Reference { replicas: 10, wall_seconds: 5.0, cpu_seconds: 5.0, stats: Vec::new() },
            points: vec![point(1, 0.25), point(2, 0.5), point(4, 1.0)],
            threads: 1,
        };
        assert_eq!(exact_cost_per_replica(&study), 6.75 / 17.0);
        study.exact_rtol = Some(1e-6);
        assert_eq!(exact_cost_per_replica(&study), 1.75 / 7.0);
    }

    /// A study of `attached_fraction_mean` (reference 0.5, one replica's spread 0.01, standard
    /// error 0.001, one exact replica 0.01 s) with one fixed step whose replica costs
    /// `cost` s, spreads by `sd` and is biased by `bias`: the reading's grid runs from error
    /// 0.002 to 0.01.
    fn one_step(cost: f64, sd: f64, bias: f64) -> Study {
        use crate::studies::stats::ReplicaStats;
        let obs = PointObs { estimate: 0.5 + bias, se: sd / 4.0, error: bias, ci_low: 0.0, ci_high: 1.0, floor: 0.01 };
        let fixed = Point {
            engine: EngineKind::Fixed,
            dt: Some(0.5),
            replicas: 16,
            wall_seconds: 16.0 * cost,
            cpu_seconds: 16.0 * cost,
            status: Status::Ok,
            diverged_replicas: 0,
            plate_growth: Some(0.5),
            obs: vec![obs],
        };
        let stats = vec![ReplicaStats { n: 100, mean: 0.5, sd: 0.01, se: 0.001 }];
        Study {
            scene: crate::test_scenes::fig1(),
            observables: vec![Observable::AttachedFraction],
            replicas: 16,
            exact_rtol: None,
            reference: Reference { replicas: 100, wall_seconds: 1.0, cpu_seconds: 1.0, stats },
            points: vec![fixed],
            threads: 1,
        }
    }

    /// The reading's line of the one observable of `one_step`.
    fn line(cost: f64, sd: f64, bias: f64) -> String {
        reading(&one_step(cost, sd, bias)).pop().unwrap()
    }

    /// A fixed-step replica dearer than an exact one but with less spread: the fixed-step
    /// engine wins only between two crossings, and the exact engine below and above them.
    #[test]
    fn a_reading_names_both_crossings_of_cost_curves_that_cross_twice() {
        assert_eq!(
            line(0.011, 0.005, 0.003),
            "`attached_fraction_mean`: the exact engine is cheaper below error 0.0036 (0.72 %) and above 0.0095 (1.9 \
             %) (at error 0.0020 (0.40 %): exact 0.25 s, no step tried gets there); the fixed-step engine is cheaper \
             between errors 0.0036 (0.72 %) and 0.0095 (1.9 %), by up to x2.7 (at error 0.0058 (1.2 %): exact 0.029 \
             s, fixed 0.011 s at dt = 0.5)."
        );
    }

    /// One crossing, either way round: the fixed-step engine's side is "above it" or
    /// "below it".
    #[test]
    fn a_reading_of_cost_curves_that_cross_once_names_the_one_crossing() {
        assert_eq!(
            line(0.009, 0.005, 0.003),
            "`attached_fraction_mean`: the exact engine is cheaper below error 0.0034 (0.68 %) (at error 0.0020 (0.40 \
             %): exact 0.25 s, no step tried gets there); the fixed-step engine is cheaper above it, by up to x3.2 (at \
             error 0.0058 (1.2 %): exact 0.029 s, fixed 0.0090 s at dt = 0.5)."
        );
        assert_eq!(
            line(0.011, 0.001, 0.0),
            "`attached_fraction_mean`: the exact engine is cheaper above error 0.0095 (1.9 %) (at error 0.0097 (1.9 \
             %): exact 0.011 s, fixed 0.011 s at dt = 0.5); the fixed-step engine is cheaper below it, by up to x23 \
             (at error 0.0020 (0.40 %): exact 0.25 s, fixed 0.011 s at dt = 0.5)."
        );
    }

    /// Curves that never cross: one engine is cheaper at every error of the grid.
    #[test]
    fn a_reading_of_cost_curves_that_never_cross_names_one_engine() {
        assert!(
            line(0.02, 0.01, 0.003)
                .starts_with("`attached_fraction_mean`: the exact engine is cheaper at every error from 0.0020 (0.40 %) to 0.010 (2.0 %); "),
            "{}",
            line(0.02, 0.01, 0.003)
        );
        assert!(
            line(0.001, 0.005, 1e-4).starts_with(
                "`attached_fraction_mean`: the fixed-step engine is cheaper at every error from 0.0020 (0.40 %) to 0.010 \
                 (2.0 %), by at least x"
            ),
            "{}",
            line(0.001, 0.005, 1e-4)
        );
    }

    /// No fixed step gets to any error of the grid (its bias exceeds them all): the
    /// exact engine's costs are given once.
    #[test]
    fn a_reading_where_no_step_gets_to_any_error_gives_one_example() {
        assert_eq!(
            line(0.02, 0.01, 0.02),
            "`attached_fraction_mean`: the exact engine is cheaper at every error from 0.0020 (0.40 %) to 0.020 \
             (4.0 %); at error 0.0020 (0.40 %): exact 0.25 s, no step tried gets there."
        );
    }

    /// Bounds a grid step apart print with enough digits to tell them apart.
    #[test]
    fn bounds_print_distinct() {
        assert_eq!(distinct_digits(&[0.0036, 0.0095]), 2);
        assert_eq!(distinct_digits(&[0.001481, 0.001549, 0.001481]), 3);
        assert_eq!(distinct_digits(&[0.5]), 2);
        let r = [Range::Below(0.001481), Range::Above(0.001549)];
        assert_eq!(ranges_text(&r, 0.5, 3), "below error 0.00148 (0.296 %) and above 0.00155 (0.310 %)");
        let r = [Range::At(0.001), Range::Between(0.002, 0.003), Range::Above(0.004)];
        assert_eq!(ranges_text(&r, 0.0, 2), "at error 0.0010, between 0.0020 and 0.0030 and above 0.0040");
    }
}
