//! A fit's files: `fit.json` (parameters with their intervals, misfit, degrees of freedom,
//! p-value, evaluations), `fit.csv` (per data point: conditions, data, sigma, fitted value,
//! band, residual), `fit.toml` (the scene with the fitted values, for `stickslip run`) and
//! `fit.svg` ([`crate::plot::fit`]); [`crate::plot::files::write_fit`] writes them.

use serde_json::{Map, Value, json};

use super::model::Problem;
use super::solve::FitResult;
use crate::scene::error::compact;

/// The method of the intervals, as `fit.json` states it.
pub const METHOD: &str = "profile likelihood: 95 % interval where the misfit, re-optimised over the other free parameters, rises by the threshold above its minimum";

/// A number for JSON: `null` when not finite.
fn num(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// The flags of parameter `j`'s interval.
pub fn flags(r: &FitResult, j: usize) -> Vec<String> {
    let iv = &r.intervals[j];
    let mut f = Vec::new();
    if iv.flat() {
        f.push("flat profile: no visible effect on the data within the bounds".to_string());
    } else if !iv.determined() {
        f.push("undetermined: the interval reaches both bounds".to_string());
    }
    if iv.low.at_bound {
        f.push("reaches lower bound".to_string());
    }
    if iv.high.at_bound {
        f.push("reaches upper bound".to_string());
    }
    if iv.min_rise < -0.5 {
        f.push(format!("the profile found a misfit {:.3} below the optimum: the optimum may be local", -iv.min_rise));
    }
    f
}

/// The warning when the simulation's noise is not small beside the data's
/// ([`super::solve::NOISE_RATIO_WARN`]), naming the remedy.
pub fn noise_warning(r: &FitResult) -> Option<String> {
    (r.noise_ratio > super::solve::NOISE_RATIO_WARN).then(|| {
        format!(
            "the simulation's standard error reaches {:.2} of sigma at the optimum: the intervals may be too narrow; raise --replicas or run.t_end",
            r.noise_ratio
        )
    })
}

/// `fit.json`.
pub fn fit_json(prob: &Problem, r: &FitResult, data_path: &str) -> String {
    let mut params = Map::new();
    for (j, f) in prob.free.iter().enumerate() {
        let iv = &r.intervals[j];
        params.insert(
            f.field.clone(),
            json!({
                "value": num(r.best.values[j]),
                "low": num(f.value(iv.low.y)),
                "high": num(f.value(iv.high.y)),
                "determined": iv.determined(),
                "flags": flags(r, j),
                "start": num(f.start),
                "bounds": [num(f.low), num(f.high)],
                "scale": if f.log { "log" } else { "lin" },
                "profile": iv.profile.iter().map(|&(y, d)| json!([num(f.value(y)), num(d)])).collect::<Vec<_>>(),
            }),
        );
    }
    let value = json!({
        "scene": prob.base.name,
        "data": data_path,
        "points": prob.data.len(),
        "conditions": prob.data.columns,
        "replicas": prob.replicas,
        "seed": prob.base.run.seed,
        "parameters": params,
        "misfit": num(r.chi2),
        "dof": r.dof,
        "p_value": r.p_value.map_or(Value::Null, num),
        "sigma": if prob.data.has_sigma { "given (data column sigma, plus the simulation's standard error)" } else { "estimated from the residuals: sqrt(SSR / dof); misfit = dof by construction, no p-value" },
        "sigma_estimate": r.sigma_estimate.map_or(Value::Null, num),
        "method": METHOD,
        "threshold": num(r.threshold),
        "band_threshold": num(r.band_threshold),
        "simulation_noise": num(r.noise_ratio),
        "evaluations": r.evaluations,
        "evaluations_search": r.search_evaluations,
        "evaluations_profiles": r.evaluations - r.search_evaluations,
    });
    let mut s = serde_json::to_string_pretty(&value).expect("JSON values serialize");
    s.push('\n');
    s
}

/// A number of `fit.csv`: the shortest text that reads back as the same `f64`, in exponent
/// form beyond 20 characters ([`compact`]: `1e100`, not 101 digits); empty when not finite.
fn csv_number(v: f64) -> String {
    if v.is_finite() { compact(v) } else { String::new() }
}

/// `fit.csv`: one row per data point, numbers as `csv_number` writes them (the shortest
/// text that reads back the same, in exponent form beyond 20 characters).
pub fn fit_csv(prob: &Problem, r: &FitResult) -> String {
    let mut out = prob.data.columns.join(",");
    if !out.is_empty() {
        out.push(',');
    }
    out.push_str("line,friction,sigma,fitted,fitted_se,band_low,band_high,residual,normalized_residual\n");
    let sigma = r.sigma_estimate;
    for (i, p) in prob.data.points.iter().enumerate() {
        let s = p.sigma.or(sigma).unwrap_or(f64::NAN);
        let scale = (s * s + r.best.se[i] * r.best.se[i]).sqrt();
        let res = p.friction - r.best.mean[i];
        let mut row: Vec<String> = p.text.clone();
        row.push(p.line.to_string());
        for v in [p.friction, s, r.best.mean[i], r.best.se[i], r.band[i].0, r.band[i].1, res, res / scale] {
            row.push(csv_number(v));
        }
        out.push_str(&row.join(","));
        out.push('\n');
    }
    out
}

/// `fit.toml`: the scene with the fitted values.
pub fn fit_toml(prob: &Problem, r: &FitResult) -> Result<String, String> {
    let scene = prob.base.with_overrides(&prob.assignments(&r.best.values)).map_err(|e| e.to_string())?;
    let mut head = format!(
        "# The scene {} with the values fitted by `stickslip fit` ({} free: {}); run it with `stickslip run fit.toml`.\n",
        prob.base.name,
        prob.free.len(),
        prob.free.iter().map(|f| f.field.as_str()).collect::<Vec<_>>().join(", ")
    );
    head.push_str(&toml::to_string(&scene.to_file()).map_err(|e| e.to_string())?);
    Ok(head)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::data::DataSet;
    use crate::fit::free::parse_free;
    use crate::fit::model::Evaluation;

    /// Data, fitted values and band from `1e-100` to `1e100`: every number of `fit.csv` in
    /// at most 24 characters, reading back as the same `f64`.
    #[test]
    fn fit_csv_writes_long_numbers_short_and_exact() {
        let base = crate::test_scenes::fig1();
        let data = DataSet::parse("plate.v,friction,sigma\n0.1,1e100,1e100\n1,1e-100,1e-100\n", "d.csv", &base, 1.0)
            .expect("data in the window");
        let free = parse_free(&["junctions.k0".to_string()], &base, &data).unwrap();
        let prob = Problem::new(base, data, free, 1).unwrap();
        let best = Evaluation { values: vec![0.1], mean: vec![1e100 / 3.0, 2e-100 / 3.0], se: vec![1e-100, 1e-100] };
        let r = FitResult {
            best_y: vec![0.5],
            best,
            score: 1.0,
            sigma_estimate: None,
            chi2: 1.0,
            dof: 1,
            p_value: None,
            threshold: 3.84,
            band_threshold: 3.84,
            intervals: Vec::new(),
            band: vec![(1e99, 1e100), (1e-100, 1e-99 / 3.0)],
            noise_ratio: 0.0,
            evaluations: 1,
            search_evaluations: 1,
        };
        let csv = fit_csv(&prob, &r);
        let rows: Vec<&str> = csv.lines().skip(1).collect();
        assert!(rows[0].starts_with("0.1,2,1e100,1e100,3.333333333333333e99,1e-100,1e99,1e100,"), "{csv}");
        assert!(rows[1].starts_with("1,3,1e-100,1e-100,6.666666666666667e-101,1e-100,1e-100,"), "{csv}");
        for (i, row) in rows.iter().enumerate() {
            let p = &prob.data.points[i];
            let s = p.sigma.unwrap();
            let res = p.friction - r.best.mean[i];
            let scale = (s * s + r.best.se[i] * r.best.se[i]).sqrt();
            let want = [p.friction, s, r.best.mean[i], r.best.se[i], r.band[i].0, r.band[i].1, res, res / scale];
            let cells: Vec<&str> = row.split(',').skip(2).collect();
            assert_eq!(cells.len(), want.len(), "{row}");
            for (cell, v) in cells.iter().zip(want) {
                assert!(cell.len() <= 24, "{cell}");
                assert_eq!(cell.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{cell}");
            }
        }
    }
}
