//! `sweep.svg`: mean friction per junction against the swept value, with 95% confidence
//! bars, and the sliding ("SI") and stick-slip ("SS") regions shaded as in the letter's
//! Fig. 2. A value whose replicas split evenly belongs to no region.

use super::{Axis, BAND_SMOOTH, BAND_STICK_SLIP, PALETTE, Panel, PlotError, Series, bands_from_classes, render_svg};
use crate::studies::sweep::{Majority, Sweep, SweepOutcome};

/// The panel of a sweep.
pub fn sweep_panel(sweep: &Sweep, outcome: &SweepOutcome) -> Panel {
    let x = if sweep.log_x { Axis::log(sweep.param.as_str()) } else { Axis::linear(sweep.param.as_str()) };
    let xs: Vec<f64> = outcome.rows.iter().map(|r| r.value.x).collect();
    let points = outcome.rows.iter().map(|r| (r.value.x, r.friction_per_junction.0)).collect();
    let errors = outcome.rows.iter().map(|r| r.friction_per_junction.1).collect();
    let bands = bands_from_classes(&xs, &x, |i| match outcome.rows[i].regime {
        Majority::Smooth => Some(("SI".to_string(), BAND_SMOOTH)),
        Majority::StickSlip => Some(("SS".to_string(), BAND_STICK_SLIP)),
        Majority::Mixed => None,
    });
    let replicas = sweep.replicas;
    Panel {
        title: format!(
            "{}: friction per junction against {} ({}; SI sliding, SS stick-slip)",
            sweep.base.name,
            sweep.param,
            if replicas == 1 { "1 replica, no CI".to_string() } else { format!("{replicas} replicas, 95% CI") }
        ),
        x,
        y: Axis::linear("mean friction per junction F/N  (kB T / l0)"),
        series: vec![Series::with_errors("", points, errors, PALETTE[0])],
        bands,
    }
}

/// The SVG text of `sweep.svg`.
pub fn sweep_svg(sweep: &Sweep, outcome: &SweepOutcome) -> Result<String, PlotError> {
    render_svg(&[sweep_panel(sweep, outcome)], 1000, 600)
}
