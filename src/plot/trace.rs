//! `trace.svg`: the friction per junction and the attached fraction against time, two
//! panels, drawn from a run's `trace.csv` after the run has finished.
//!
//! A long trace is thinned to at most [`BUCKETS`] time buckets, each keeping its lowest and
//! highest point (in time order), so the envelope of the curve, every spike included, is
//! drawn exactly; a trace with fewer samples than buckets is drawn sample by sample.

use std::io::{BufRead, BufReader};
use std::path::Path;

use super::{Axis, PALETTE, Panel, PlotError, Series, render_svg};
use crate::output::TRACE_SVG;
use crate::output::atomic::{WriteFileError, write_files};
use crate::scene::Scene;

pub use crate::output::TRACE_SVG_BUCKETS as BUCKETS;

/// A point `(t, y)`.
type Point = (f64, f64);

/// Min/max thinning of a time series over `[0, t_end]`.
#[derive(Clone, Debug)]
pub struct Thinner {
    t_end: f64,
    /// Per bucket, its lowest and highest point.
    buckets: Vec<Option<(Point, Point)>>,
}

impl Thinner {
    pub fn new(t_end: f64, buckets: usize) -> Self {
        Thinner { t_end, buckets: vec![None; buckets.max(1)] }
    }
    pub fn push(&mut self, t: f64, y: f64) {
        let n = self.buckets.len();
        let k = ((t / self.t_end * n as f64).floor().max(0.0) as usize).min(n - 1);
        let b = &mut self.buckets[k];
        match b {
            None => *b = Some(((t, y), (t, y))),
            Some((lo, hi)) => {
                if y < lo.1 {
                    *lo = (t, y);
                }
                if y > hi.1 {
                    *hi = (t, y);
                }
            }
        }
    }
    /// The kept points in time order.
    pub fn points(&self) -> Vec<(f64, f64)> {
        let mut out = Vec::with_capacity(2 * self.buckets.len());
        for &(lo, hi) in self.buckets.iter().flatten() {
            if lo == hi {
                out.push(lo);
            } else if lo.0 <= hi.0 {
                out.extend([lo, hi]);
            } else {
                out.extend([hi, lo]);
            }
        }
        out
    }
}

/// Why `trace.svg` could not be written.
#[derive(Debug, thiserror::Error)]
pub enum TracePlotError {
    #[error("cannot read {path}: {message}")]
    Read { path: String, message: String },
    #[error(transparent)]
    Plot(#[from] PlotError),
    #[error(transparent)]
    Write(#[from] WriteFileError),
}

/// The two panels of a run's trace: `(t, F/N)` and `(t, n)` points.
pub fn trace_panels(scene: &Scene, friction: Vec<(f64, f64)>, attached: Vec<(f64, f64)>) -> Vec<Panel> {
    let x = Axis::linear("time t (units of M/eta)").with_range(0.0, scene.run.t_end);
    let engine = match scene.run.engine {
        crate::scene::EngineKind::Exact => "exact engine".to_string(),
        crate::scene::EngineKind::Fixed => format!("fixed engine, dt = {}", scene.fixed.dt),
    };
    vec![
        Panel {
            title: format!(
                "{}: friction per junction ({engine}, V = {}, N = {})",
                scene.name, scene.plate.v, scene.junctions.n
            ),
            x: x.clone(),
            y: Axis::linear("F / N  (kB T / l0)"),
            series: vec![Series::line("", friction, PALETTE[0])],
            bands: vec![],
        },
        Panel {
            title: format!("{}: attached fraction", scene.name),
            x,
            y: Axis::linear("attached fraction n").with_range(0.0, 1.0),
            series: vec![Series::line("", attached, PALETTE[1])],
            bands: vec![],
        },
    ]
}

/// Reads `dir/trace.csv` and writes `dir/trace.svg` (atomically).
pub fn write_trace_svg(dir: &Path, scene: &Scene) -> Result<(), TracePlotError> {
    let path = dir.join("trace.csv");
    let shown = path.display().to_string();
    let read_err = |message: String| TracePlotError::Read { path: shown.clone(), message };
    let file = std::fs::File::open(&path).map_err(|e| read_err(e.to_string()))?;
    let n = scene.junctions.n as f64;
    let (mut f, mut a) = (Thinner::new(scene.run.t_end, BUCKETS), Thinner::new(scene.run.t_end, BUCKETS));
    for (i, line) in BufReader::new(file).lines().enumerate() {
        let line = line.map_err(|e| read_err(e.to_string()))?;
        if i == 0 {
            continue;
        }
        let cols: Vec<f64> = line
            .split(',')
            .map(|c| c.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|e| read_err(format!("line {}: {e}", i + 1)))?;
        if cols.len() != 6 {
            return Err(read_err(format!("line {}: expected 6 columns, found {}", i + 1, cols.len())));
        }
        f.push(cols[0], cols[3] / n);
        a.push(cols[0], cols[5]);
    }
    let svg = render_svg(&trace_panels(scene, f.points(), a.points()), 1000, 380)?;
    Ok(write_files(dir, &[(TRACE_SVG, svg)])?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_series_are_kept_whole() {
        let mut t = Thinner::new(10.0, 100);
        let pts: Vec<(f64, f64)> = (0..=10).map(|i| (i as f64, (i * i) as f64)).collect();
        pts.iter().for_each(|&(x, y)| t.push(x, y));
        assert_eq!(t.points(), pts);
    }

    #[test]
    fn long_series_keep_their_extremes() {
        let mut t = Thinner::new(1.0, 10);
        for i in 0..=10_000 {
            let x = i as f64 / 10_000.0;
            t.push(x, if i == 5_003 { 100.0 } else { (x * 50.0).sin() });
        }
        let p = t.points();
        assert!(p.len() <= 20);
        assert!(p.iter().any(|&(_, y)| y == 100.0));
        assert!(p.windows(2).all(|w| w[0].0 < w[1].0));
    }
}
