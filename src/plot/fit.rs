//! `fit.svg`: the data with their error bars against the fitted curve and its band (upper
//! panel), and the normalized residuals (lower panel), against the data's first condition
//! column (on a log axis when all its values are > 0 and span more than a decade), or the
//! point's index without one.

use super::{Axis, PALETTE, Panel, PlotError, Series, render_svg};
use crate::fit::model::Problem;
use crate::fit::solve::FitResult;

/// The figure.
pub fn fit_svg(prob: &Problem, r: &FitResult) -> Result<String, PlotError> {
    let pts = &prob.data.points;
    let (x, label): (Vec<f64>, String) = match prob.data.columns.first() {
        Some(c) => (pts.iter().map(|p| p.conditions[0]).collect(), c.clone()),
        None => ((0..pts.len()).map(|i| i as f64).collect(), "data point".to_string()),
    };
    let (lo, hi) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let axis = if lo > 0.0 && hi / lo > 10.0 { Axis::log(label.as_str()) } else { Axis::linear(label.as_str()) };
    let mut order: Vec<usize> = (0..pts.len()).collect();
    order.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    let sigma = |i: usize| pts[i].sigma.or(r.sigma_estimate).unwrap_or(f64::NAN);
    let data = Series {
        label: if prob.data.has_sigma { "data +- sigma" } else { "data +- estimated sigma" }.to_string(),
        points: order.iter().map(|&i| (x[i], pts[i].friction)).collect(),
        error: Some(order.iter().map(|&i| sigma(i)).collect()),
        color: PALETTE[0],
        line: false,
        markers: true,
    };
    let fitted = Series::line("fitted", order.iter().map(|&i| (x[i], r.best.mean[i])).collect(), PALETTE[1]);
    let band_lo = Series::line("95% band", order.iter().map(|&i| (x[i], r.band[i].0)).collect(), PALETTE[2]);
    let band_hi = Series::line("", order.iter().map(|&i| (x[i], r.band[i].1)).collect(), PALETTE[2]);
    let free = prob.free.iter().map(|f| f.field.as_str()).collect::<Vec<_>>().join(", ");
    let top = Panel {
        title: format!("{}: fit of {free} (chi2 = {:.2}, dof = {})", prob.base.name, r.chi2, r.dof),
        x: axis.clone(),
        y: Axis::linear("mean friction per junction F/N  (kB T / l0)"),
        series: vec![data, band_lo, band_hi, fitted],
        bands: vec![],
    };
    let residuals = order
        .iter()
        .map(|&i| {
            let s = (sigma(i).powi(2) + r.best.se[i].powi(2)).sqrt();
            (x[i], (pts[i].friction - r.best.mean[i]) / s)
        })
        .collect();
    let zero = Series::line("", vec![(x[order[0]], 0.0), (x[*order.last().expect("data")], 0.0)], PALETTE[3]);
    let bottom = Panel {
        title: "normalized residuals (data - fitted) / sqrt(sigma^2 + se^2)".to_string(),
        x: axis,
        y: Axis::linear("residual / s"),
        series: vec![
            zero,
            Series {
                label: String::new(),
                points: residuals,
                error: None,
                color: PALETTE[0],
                line: false,
                markers: true,
            },
        ],
        bands: vec![],
    };
    render_svg(&[top, bottom], 900, 360)
}
