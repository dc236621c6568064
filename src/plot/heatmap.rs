//! A heat map: a grid of cells coloured by a value (viridis, colour-blind safe), a colour
//! bar, the boundaries between cells of different class drawn as a white line with a black
//! halo (visible on every colour), and each cell's class label when the grid is small
//! enough to read.

use std::ops::Range;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{Axis, FONT, PlotError, cell_edges, err, svg_text};

/// Viridis at 9 evenly spaced stops (matplotlib's table).
const VIRIDIS: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (71, 44, 122),
    (59, 81, 139),
    (44, 113, 142),
    (33, 144, 141),
    (39, 173, 129),
    (92, 200, 99),
    (170, 220, 50),
    (253, 231, 37),
];
/// Colour of a cell without a value.
const NO_VALUE: RGBColor = RGBColor(200, 200, 200);
/// Most cells that get a class label.
const MAX_LABELLED: usize = 400;
/// Most tick labels along an axis (ticks sit at cell centres).
const MAX_TICKS: usize = 12;

/// Every k-th cell centre, so that at most [`MAX_TICKS`] remain.
fn ticks(centres: &[f64]) -> Vec<f64> {
    let step = centres.len().div_ceil(MAX_TICKS).max(1);
    centres.iter().step_by(step).copied().collect()
}

/// A tick label: 3 significant digits, plain.
fn tick_label(v: f64) -> String {
    let s = format!("{:.3}", crate::studies::format::sig(v, 3).parse::<f64>().unwrap_or(v));
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() { "0".to_string() } else { s.to_string() }
}

/// Viridis at `f` in `[0, 1]` (clamped), linearly interpolated between stops.
pub fn viridis(f: f64) -> RGBColor {
    let f = if f.is_finite() { f.clamp(0.0, 1.0) } else { 0.0 };
    let x = f * (VIRIDIS.len() - 1) as f64;
    let k = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let t = x - k as f64;
    let (a, b) = (VIRIDIS[k], VIRIDIS[k + 1]);
    let lerp = |p: u8, q: u8| (p as f64 + t * (q as f64 - p as f64)).round() as u8;
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// A heat map over the grid `xs x ys`.
#[derive(Clone, Debug)]
pub struct HeatMap {
    pub title: String,
    pub x: Axis,
    pub y: Axis,
    /// Cell centres along x and y, increasing.
    pub xs: Vec<f64>,
    pub ys: Vec<f64>,
    /// `values[i][j]` at `(xs[i], ys[j])`; non-finite: no value (grey).
    pub values: Vec<Vec<f64>>,
    /// `classes[i][j]`: the cell's class label; a boundary is drawn between neighbouring
    /// cells whose labels differ.
    pub classes: Vec<Vec<String>>,
    /// The colour bar's label.
    pub value_label: String,
}

/// Draws `h` into a `width x height` SVG (the colour bar takes the right 130 pixels).
pub fn render_heatmap(h: &HeatMap, width: u32, height: u32) -> Result<String, PlotError> {
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (main, bar) = root.split_horizontally(width.saturating_sub(130));
        let top = h.values.iter().flatten().copied().filter(|v| v.is_finite()).fold(0.0f64, f64::max);
        let top = if top > 0.0 { top } else { 1.0 };
        draw_grid(&main, h, top)?;
        draw_bar(&bar, &h.value_label, top)?;
        root.present().map_err(err)?;
    }
    Ok(buf)
}

fn draw_grid<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, h: &HeatMap, top: f64) -> Result<(), PlotError> {
    let (xe, ye) = (cell_edges(&h.xs, &h.x), cell_edges(&h.ys, &h.y));
    if xe.is_empty() || ye.is_empty() {
        return Err(PlotError("a heat map needs at least one cell".into()));
    }
    let axis = |a: &Axis, e: &[f64], centres: &[f64]| CellAxis {
        lo: e[0],
        hi: e[e.len() - 1],
        log: a.log,
        ticks: ticks(centres),
    };
    draw_cells(area, h, top, axis(&h.x, &xe, &h.xs), axis(&h.y, &ye, &h.ys), &xe, &ye)
}

/// A linear or log axis over `[lo, hi]` whose tick marks sit at given points (the cell
/// centres) and read as [`tick_label`]s.
#[derive(Clone, Debug)]
struct CellAxis {
    lo: f64,
    hi: f64,
    log: bool,
    ticks: Vec<f64>,
}

impl CellAxis {
    fn scale(&self, v: f64) -> f64 {
        if self.log { v.ln() } else { v }
    }
}

impl Ranged for CellAxis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;
    /// As plotters' numeric axes: the fraction of the way along the axis, in pixels.
    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let (a, b) = (self.scale(self.lo), self.scale(self.hi));
        let f = (self.scale(*v) - a) / (b - a);
        let length = limit.1 - limit.0;
        if !f.is_finite() || length == 0 {
            return if f.is_finite() || f.is_nan() {
                limit.0
            } else if f > 0.0 {
                limit.1
            } else {
                limit.0
            };
        }
        if length > 0 {
            limit.0 + (length as f64 * f + 1e-3).floor() as i32
        } else {
            limit.0 + (length as f64 * f - 1e-3).ceil() as i32
        }
    }
    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        let step = self.ticks.len().div_ceil(hint.max_num_points().max(1)).max(1);
        self.ticks.iter().step_by(step).copied().collect()
    }
    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

impl ValueFormatter<f64> for CellAxis {
    fn format(value: &f64) -> String {
        tick_label(*value)
    }
}

fn draw_cells<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    h: &HeatMap,
    top: f64,
    xr: CellAxis,
    yr: CellAxis,
    xe: &[f64],
    ye: &[f64],
) -> Result<(), PlotError> {
    let mut chart = ChartBuilder::on(area)
        .caption(svg_text(&h.title), (FONT, 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(xr, yr)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(svg_text(&h.x.label))
        .y_desc(svg_text(&h.y.label))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .draw()
        .map_err(err)?;
    let (nx, ny) = (h.xs.len(), h.ys.len());
    for i in 0..nx {
        for j in 0..ny {
            let v = h.values[i][j];
            let color = if v.is_finite() { viridis(v / top) } else { NO_VALUE };
            chart
                .draw_series(std::iter::once(Rectangle::new([(xe[i], ye[j]), (xe[i + 1], ye[j + 1])], color.filled())))
                .map_err(err)?;
        }
    }
    // Boundaries between cells of different class: vertical ones between (i, j) and
    // (i + 1, j), horizontal ones between (i, j) and (i, j + 1).
    let mut segments = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            if i + 1 < nx && h.classes[i][j] != h.classes[i + 1][j] {
                segments.push([(xe[i + 1], ye[j]), (xe[i + 1], ye[j + 1])]);
            }
            if j + 1 < ny && h.classes[i][j] != h.classes[i][j + 1] {
                segments.push([(xe[i], ye[j + 1]), (xe[i + 1], ye[j + 1])]);
            }
        }
    }
    for (color, w) in [(BLACK, 5), (WHITE, 2)] {
        chart.draw_series(segments.iter().map(|s| PathElement::new(s.to_vec(), color.stroke_width(w)))).map_err(err)?;
    }
    if nx * ny <= MAX_LABELLED {
        let size = if nx.max(ny) > 12 { 11 } else { 14 };
        for i in 0..nx {
            for j in 0..ny {
                let v = h.values[i][j];
                // Dark text on the bright end of the map, white on the dark end.
                let ink = if v.is_finite() && v / top > 0.6 { BLACK } else { WHITE };
                let style =
                    TextStyle::from((FONT, size).into_font()).color(&ink).pos(Pos::new(HPos::Center, VPos::Center));
                chart
                    .draw_series(std::iter::once(Text::new(svg_text(&h.classes[i][j]), (h.xs[i], h.ys[j]), style)))
                    .map_err(err)?;
            }
        }
    }
    Ok(())
}

fn draw_bar<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, label: &str, top: f64) -> Result<(), PlotError> {
    let mut chart = ChartBuilder::on(area)
        .margin_top(40)
        .margin_bottom(57)
        .margin_right(10)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..1.0, 0.0..top)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(svg_text(label))
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 13))
        .draw()
        .map_err(err)?;
    let steps = 100;
    chart
        .draw_series((0..steps).map(|k| {
            let (a, b) = (top * k as f64 / steps as f64, top * (k + 1) as f64 / steps as f64);
            Rectangle::new([(0.0, a), (1.0, b)], viridis((k as f64 + 0.5) / steps as f64).filled())
        }))
        .map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_at_cell_centres_read_well() {
        assert_eq!(ticks(&[1.0, 2.0, 3.0]), vec![1.0, 2.0, 3.0]);
        assert_eq!(ticks(&(0..30).map(f64::from).collect::<Vec<_>>()).len(), 10);
        assert_eq!(tick_label(0.264438), "0.264");
        assert_eq!(tick_label(1500.0), "1500");
        assert_eq!(tick_label(3.23165), "3.23");
        assert_eq!(tick_label(10.0), "10");
        assert_eq!(tick_label(0.0), "0");
    }

    #[test]
    fn viridis_ends_and_clamps() {
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        assert_eq!(viridis(2.0), viridis(1.0));
        assert_eq!(viridis(f64::NAN), viridis(0.0));
        assert_eq!(viridis(0.5), RGBColor(33, 144, 141));
    }

    /// A name from the user in a heat map's title, axis labels, cell labels and colour bar:
    /// escaped as text, the SVG well-formed.
    #[test]
    fn names_are_escaped_in_heat_maps() {
        use crate::plot::tests::{AWKWARD, awkward_texts};
        let h = HeatMap {
            title: AWKWARD.into(),
            x: Axis::linear(AWKWARD),
            y: Axis::linear(AWKWARD),
            xs: vec![1.0, 2.0],
            ys: vec![1.0],
            values: vec![vec![0.5], vec![1.0]],
            classes: vec![vec![AWKWARD.into()], vec!["SI".into()]],
            value_label: AWKWARD.into(),
        };
        let svg = render_heatmap(&h, 700, 400).unwrap();
        assert_eq!(awkward_texts(&svg), 5, "{svg}");
    }

    #[test]
    fn a_heat_map_is_deterministic_and_draws_its_boundary() {
        let h = HeatMap {
            title: "map".into(),
            x: Axis::log("x"),
            y: Axis::linear("y"),
            xs: vec![0.1, 1.0, 10.0],
            ys: vec![1.0, 2.0],
            values: vec![vec![0.0, 0.1], vec![0.5, f64::NAN], vec![1.0, 0.2]],
            classes: vec![
                vec!["SI".into(), "SI".into()],
                vec!["SS".into(), "SI".into()],
                vec!["SS".into(), "SI".into()],
            ],
            value_label: "amplitude".into(),
        };
        let a = render_heatmap(&h, 700, 400).unwrap();
        assert_eq!(a, render_heatmap(&h, 700, 400).unwrap());
        assert!(a.starts_with("<svg") && a.trim_end().ends_with("</svg>"));
        // Boundary: SI|SS between columns 0 and 1 at j = 0, SS/SI between rows at i = 1, 2:
        // three segments, each drawn twice (halo and line).
        assert_eq!(a.matches("stroke-width=\"5\"").count(), 3, "{a}");
        assert!(a.contains("fill=\"#C8C8C8\"") || a.to_lowercase().contains("fill=\"#c8c8c8\""), "no grey cell");
    }
}
