//! `bench.svg`: a scaling study ([`crate::studies::scaling`]) on log-log axes, three panels
//! against `N`: nanoseconds per event (exact) and per junction-step (fixed); set-up time;
//! bytes per junction, estimated and measured.

use super::{Axis, Panel, PlotError, Series, render_svg};
use crate::scene::EngineKind;
use crate::studies::scaling::Row;

/// The figure's SVG text.
pub fn scaling_svg(scene: &str, rows: &[Row]) -> Result<String, PlotError> {
    let engines = [(EngineKind::Exact, "exact", super::PALETTE[0]), (EngineKind::Fixed, "fixed", super::PALETTE[1])];
    let series = |label: &dyn Fn(&str) -> String, value: &dyn Fn(&Row) -> Option<f64>, offset: usize| {
        engines
            .iter()
            .map(|&(engine, name, _)| {
                let points: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| r.engine == engine)
                    .filter_map(|r| value(r).filter(|v| v.is_finite() && *v > 0.0).map(|v| (r.n as f64, v)))
                    .collect();
                let color = super::PALETTE[(offset + engines.iter().position(|e| e.0 == engine).unwrap_or(0)) % 6];
                let mut s = Series::line(label(name), points, color);
                s.markers = true;
                s
            })
            .collect::<Vec<_>>()
    };
    let n_axis = || Axis::log("junctions N");
    let cost = Panel {
        title: format!("{scene}: run time per event (exact) and per junction-step (fixed)"),
        x: n_axis(),
        y: Axis::log("ns per unit of work"),
        series: series(
            &|e| if e == "exact" { "exact, ns per event".into() } else { "fixed, ns per junction-step".into() },
            &|r| Some(r.ns_per_unit()),
            0,
        ),
        bands: Vec::new(),
    };
    let setup = Panel {
        title: "set-up time (engine and initial state)".into(),
        x: n_axis(),
        y: Axis::log("seconds"),
        series: series(&|e| e.to_string(), &|r| Some(r.setup_seconds), 0),
        bands: Vec::new(),
    };
    let mut memory =
        series(&|e| format!("{e}, estimated (engine state)"), &|r| Some(r.estimated_bytes_per_junction), 0);
    memory.extend(series(&|e| format!("{e}, measured (peak RSS rise)"), &|r| r.measured_bytes_per_junction, 2));
    let memory = Panel {
        title: "memory per junction".into(),
        x: n_axis(),
        y: Axis::log("bytes per junction"),
        series: memory,
        bands: Vec::new(),
    };
    render_svg(&[cost, setup, memory], 800, 320)
}
