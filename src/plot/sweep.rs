//! `sweep.svg`.
//!
//! - One swept field: mean friction per junction against the value, with 95 % confidence
//!   bars, and the sliding ("SI") and stick-slip ("SS") regions shaded as in the letter's
//!   Fig. 2, and fixed steps whose plate step failed ("UN", unstable) in grey. A value whose
//!   replicas split evenly belongs to no region.
//! - Two swept fields: the regime map, a heat map of the oscillation amplitude per junction
//!   (mean over replicas) over the grid, with the boundary between sliding ("SI"),
//!   stick-slip ("SS"), evenly split ("SI/SS") and unstable ("UN") cells drawn, each cell
//!   labelled.

use super::heatmap::{HeatMap, render_heatmap};
use super::{
    Axis, BAND_SMOOTH, BAND_STICK_SLIP, BAND_UNSTABLE, PALETTE, Panel, PlotError, Series, bands_from_classes,
    render_svg,
};
use crate::studies::sweep::{Majority, Sweep, SweepAxis, SweepOutcome};

fn axis_of(a: &SweepAxis) -> Axis {
    if a.log { Axis::log(a.param.as_str()) } else { Axis::linear(a.param.as_str()) }
}

fn replicas_note(sweep: &Sweep) -> String {
    match sweep.replicas {
        1 => "1 replica, no CI".to_string(),
        r => format!("{r} replicas, 95% CI"),
    }
}

/// The panel of a 1-D sweep.
pub fn sweep_panel(sweep: &Sweep, outcome: &SweepOutcome) -> Panel {
    let axis = &sweep.axes[0];
    let x = axis_of(axis);
    let xs: Vec<f64> = outcome.rows.iter().map(|r| r.values[0].x).collect();
    let points = outcome.rows.iter().map(|r| (r.values[0].x, r.friction_per_junction.0)).collect();
    let errors = outcome.rows.iter().map(|r| r.friction_per_junction.1).collect();
    let bands = bands_from_classes(&xs, &x, |i| match outcome.rows[i].regime {
        Majority::Smooth => Some(("SI".to_string(), BAND_SMOOTH)),
        Majority::StickSlip => Some(("SS".to_string(), BAND_STICK_SLIP)),
        Majority::Unstable => Some(("UN".to_string(), BAND_UNSTABLE)),
        Majority::Mixed => None,
    });
    Panel {
        title: format!(
            "{}: friction per junction against {} ({}; SI sliding, SS stick-slip, UN unstable step)",
            sweep.base.name,
            axis.param,
            replicas_note(sweep)
        ),
        x,
        y: Axis::linear("mean friction per junction F/N  (kB T / l0)"),
        series: vec![Series::with_errors("", points, errors, PALETTE[0])],
        bands,
    }
}

/// A cell's value on the map: none for an unstable step (its amplitude is the scheme's and
/// would swamp the colour scale).
fn amplitude_per_junction(r: &crate::studies::sweep::Row) -> f64 {
    if r.regime == Majority::Unstable { f64::NAN } else { r.oscillation_amplitude.0 / r.n as f64 }
}

/// The regime map of a 2-D sweep.
pub fn regime_map(sweep: &Sweep, outcome: &SweepOutcome) -> HeatMap {
    let (a, b) = (&sweep.axes[0], &sweep.axes[1]);
    let (nx, ny) = (a.values.len(), b.values.len());
    // Rows are row-major: point i * ny + j has value i of the first field, j of the second.
    let cell = |i: usize, j: usize| &outcome.rows[i * ny + j];
    let label = |m: Majority| match m {
        Majority::Smooth => "SI",
        Majority::StickSlip => "SS",
        Majority::Mixed => "SI/SS",
        Majority::Unstable => "UN",
    };
    HeatMap {
        title: format!(
            "{}: regime map, oscillation amplitude per junction ({}; SI sliding, SS stick-slip, UN unstable step, line: boundary)",
            sweep.base.name,
            replicas_note(sweep).replace(", 95% CI", "")
        ),
        x: axis_of(a),
        y: axis_of(b),
        xs: a.values.iter().map(|v| v.x).collect(),
        ys: b.values.iter().map(|v| v.x).collect(),
        values: (0..nx).map(|i| (0..ny).map(|j| amplitude_per_junction(cell(i, j))).collect()).collect(),
        classes: (0..nx).map(|i| (0..ny).map(|j| label(cell(i, j).regime).to_string()).collect()).collect(),
        value_label: "oscillation amplitude per junction A/N  (kB T / l0)".to_string(),
    }
}

/// The SVG text of `sweep.svg`.
pub fn sweep_svg(sweep: &Sweep, outcome: &SweepOutcome) -> Result<String, PlotError> {
    if sweep.is_map() {
        render_heatmap(&regime_map(sweep, outcome), 1000, 700)
    } else {
        render_svg(&[sweep_panel(sweep, outcome)], 1000, 600)
    }
}
