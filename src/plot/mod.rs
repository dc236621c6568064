//! Every figure the program draws, as SVG text (plotters' SVG backend): [`sweep`]
//! (`sweep.svg`: a curve for one swept field, a regime map for two), [`compare`]
//! (`compare.svg`), [`trace`] (`trace.svg`) and [`scaling`] (`bench.svg`), sharing the
//! helpers of this file (panels of line series with error bars, log or linear axes, shaded and labelled bands along the x
//! axis, cell edges around grid points) and [`heatmap`] (a coloured grid with a colour bar
//! and class boundaries).
//!
//! A [`Panel`] is one chart; [`render_svg`] stacks panels vertically into one SVG. Axis
//! ranges are taken from the data (error bars included) unless an [`Axis`] fixes them.
//! Output is deterministic: the same panels give the same bytes.
//!
//! Figures read the results of the runs and studies they draw (`crate::studies`,
//! `crate::fit`, `crate::scene`) and return text, and nothing they read depends on them. A
//! study's or fit's files, figure included, are written by [`files`] (the layer above both); a run's `trace.svg` is
//! drawn from its `trace.csv` after the run, by [`trace::write_trace_svg`].

pub mod compare;
pub mod files;
pub mod fit;
pub mod heatmap;
pub mod scaling;
pub mod sweep;
pub mod trace;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Series colours, in order (a colour-blind-safe palette).
pub const PALETTE: [RGBColor; 6] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
];
/// Band colours: sliding (smooth) and stick-slip regions.
pub const BAND_SMOOTH: RGBColor = RGBColor(0, 114, 178);
pub const BAND_STICK_SLIP: RGBColor = RGBColor(213, 94, 0);
/// Shading of fixed steps whose plate step failed (regime `unstable`).
pub const BAND_UNSTABLE: RGBColor = RGBColor(128, 128, 128);

/// The font family of every text in a figure.
pub const FONT: &str = "sans-serif";

/// Why a plot could not be drawn.
#[derive(Debug, thiserror::Error)]
#[error("cannot draw the plot: {0}")]
pub struct PlotError(pub String);

fn err(e: impl std::fmt::Display) -> PlotError {
    PlotError(e.to_string())
}

/// `s` as a figure shows it: control characters, line separators, U+FFFE and U+FFFF
/// escaped as text (a newline as `\n`, a vertical tab as `\u{b}`), so that a scene's name
/// keeps the SVG well-formed and each text on one line. plotters escapes XML's markup
/// characters (`&`, `<`, `>`, `"`, `'`) itself.
pub(crate) use crate::scene::error::printable as svg_text;

/// One axis: its label, scale and (optionally) fixed range.
#[derive(Clone, Debug)]
pub struct Axis {
    pub label: String,
    /// Logarithmic scale (every value drawn must then be > 0).
    pub log: bool,
    /// Fixed `(lo, hi)`; `None` takes the data's range with a margin.
    pub range: Option<(f64, f64)>,
}

impl Axis {
    pub fn linear(label: impl Into<String>) -> Self {
        Axis { label: label.into(), log: false, range: None }
    }
    pub fn log(label: impl Into<String>) -> Self {
        Axis { label: label.into(), log: true, range: None }
    }
    pub fn with_range(mut self, lo: f64, hi: f64) -> Self {
        self.range = Some((lo, hi));
        self
    }
    /// The point a fraction `frac` of the way from `lo` to `hi` on this axis's scale.
    pub fn at(&self, lo: f64, hi: f64, frac: f64) -> f64 {
        if self.log { (lo.ln() + frac * (hi.ln() - lo.ln())).exp() } else { lo + frac * (hi - lo) }
    }
    /// The middle of `[a, b]` on this axis's scale (geometric mean on a log axis).
    pub fn mid(&self, a: f64, b: f64) -> f64 {
        self.at(a, b, 0.5)
    }
    /// The range to draw for values `vals`: the fixed one, or the data's with a 5% margin.
    fn resolve(&self, vals: impl Iterator<Item = f64>) -> (f64, f64) {
        if let Some(r) = self.range {
            return r;
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in vals.filter(|v| v.is_finite() && (!self.log || *v > 0.0)) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        // No finite value: `lo` is still +inf (never NaN, the values were filtered).
        if lo > hi {
            return if self.log { (0.1, 10.0) } else { (0.0, 1.0) };
        }
        if lo == hi {
            return if self.log {
                (lo / 2.0, hi * 2.0)
            } else {
                (lo - 0.5 * lo.abs().max(1.0), hi + 0.5 * hi.abs().max(1.0))
            };
        }
        (self.at(lo, hi, -0.05), self.at(lo, hi, 1.05))
    }
}

/// A line and/or markers through points, with optional symmetric error bars.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text (no legend entry when empty).
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Half-widths of vertical error bars, one per point (NaN: no bar).
    pub error: Option<Vec<f64>>,
    pub color: RGBColor,
    pub line: bool,
    pub markers: bool,
}

impl Series {
    /// A plain line.
    pub fn line(label: impl Into<String>, points: Vec<(f64, f64)>, color: RGBColor) -> Self {
        Series { label: label.into(), points, error: None, color, line: true, markers: false }
    }
    /// A line with markers and error bars.
    pub fn with_errors(label: impl Into<String>, points: Vec<(f64, f64)>, error: Vec<f64>, color: RGBColor) -> Self {
        Series { label: label.into(), points, error: Some(error), color, line: true, markers: true }
    }
}

/// A shaded vertical band `[from, to]` with a label near the top.
#[derive(Clone, Debug)]
pub struct Band {
    pub from: f64,
    pub to: f64,
    pub label: String,
    pub color: RGBColor,
}

/// One chart.
#[derive(Clone, Debug)]
pub struct Panel {
    pub title: String,
    pub x: Axis,
    pub y: Axis,
    pub series: Vec<Series>,
    pub bands: Vec<Band>,
}

impl Panel {
    fn x_values(&self) -> impl Iterator<Item = f64> + '_ {
        let pts = self.series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
        pts.chain(self.bands.iter().flat_map(|b| [b.from, b.to]))
    }
    fn y_values(&self) -> impl Iterator<Item = f64> + '_ {
        self.series.iter().flat_map(|s| {
            s.points.iter().enumerate().flat_map(move |(i, p)| {
                let e = s.error.as_ref().map_or(0.0, |e| e.get(i).copied().filter(|e| e.is_finite()).unwrap_or(0.0));
                [p.1 - e, p.1 + e]
            })
        })
    }
}

/// Draws `panels` stacked vertically, each `width x panel_height` pixels; returns the SVG.
pub fn render_svg(panels: &[Panel], width: u32, panel_height: u32) -> Result<String, PlotError> {
    let mut buf = String::new();
    {
        let root =
            SVGBackend::with_string(&mut buf, (width, panel_height * panels.len().max(1) as u32)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let areas = root.split_evenly((panels.len().max(1), 1));
        for (area, panel) in areas.iter().zip(panels) {
            draw_panel(area, panel)?;
        }
        root.present().map_err(err)?;
    }
    Ok(buf)
}

/// Widest range a drawn axis spans: 300 decades on a log scale (`1e-300` to `1e300` at
/// most), `+-1e300` on a linear one.
const AXIS_SPAN: f64 = 1e300;

/// `[lo, hi]` narrowed to what an axis can draw ([`AXIS_SPAN`]): a log axis within
/// `[1e-300, 1e300]` and at most 300 decades wide, its lower end raised if wider; a linear
/// one within `+-1e300`. plotters' tick search on a log axis never ends when `hi / lo` is
/// infinite (a range from `1e-300` to `1e300` with its margin), and a range of non-finite
/// width has no ticks; values outside are drawn at the edge or not at all.
pub(crate) fn drawable(log: bool, lo: f64, hi: f64) -> (f64, f64) {
    if log {
        let hi = hi.clamp(1.0 / AXIS_SPAN, AXIS_SPAN);
        let lo = lo.clamp(1.0 / AXIS_SPAN, hi).max(hi / AXIS_SPAN);
        if lo < hi { (lo, hi) } else { (hi / 10.0, hi * 10.0) }
    } else {
        let (lo, hi) = (lo.clamp(-AXIS_SPAN, AXIS_SPAN), hi.clamp(-AXIS_SPAN, AXIS_SPAN));
        if lo < hi { (lo, hi) } else { (lo - 1.0 - lo.abs(), lo + 1.0 + lo.abs()) }
    }
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> Result<(), PlotError> {
    let (x0, x1) = p.x.resolve(p.x_values());
    let (y0, y1) = p.y.resolve(p.y_values());
    let ((x0, x1), (y0, y1)) = (drawable(p.x.log, x0, x1), drawable(p.y.log, y0, y1));
    match (p.x.log, p.y.log) {
        (false, false) => draw_in(area, p, x0..x1, y0..y1, (y0, y1)),
        (true, false) => draw_in(area, p, (x0..x1).log_scale(), y0..y1, (y0, y1)),
        (false, true) => draw_in(area, p, x0..x1, (y0..y1).log_scale(), (y0, y1)),
        (true, true) => draw_in(area, p, (x0..x1).log_scale(), (y0..y1).log_scale(), (y0, y1)),
    }
}

fn draw_in<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    xr: X,
    yr: Y,
    (y0, y1): (f64, f64),
) -> Result<(), PlotError>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area)
        .caption(svg_text(&p.title), (FONT, 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(xr, yr)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(svg_text(&p.x.label))
        .y_desc(svg_text(&p.y.label))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(215, 215, 215))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .draw()
        .map_err(err)?;

    let label_y = p.y.at(y0, y1, 0.93);
    for b in &p.bands {
        chart
            .draw_series(std::iter::once(Rectangle::new([(b.from, y0), (b.to, y1)], b.color.mix(0.14).filled())))
            .map_err(err)?;
        if !b.label.is_empty() {
            let style = TextStyle::from((FONT, 18).into_font()).color(&b.color).pos(Pos::new(HPos::Center, VPos::Top));
            chart
                .draw_series(std::iter::once(Text::new(svg_text(&b.label), (p.x.mid(b.from, b.to), label_y), style)))
                .map_err(err)?;
        }
    }

    let clamp = |y: f64| y.clamp(y0, y1);
    let mut legend = false;
    for s in &p.series {
        let color = s.color;
        let style = color.stroke_width(2);
        if let Some(errors) = &s.error {
            for (&(x, y), &e) in s.points.iter().zip(errors) {
                if !(e.is_finite() && e > 0.0 && y.is_finite()) {
                    continue;
                }
                let (lo, hi) = (clamp(y - e), clamp(y + e));
                chart.draw_series(std::iter::once(PathElement::new(vec![(x, lo), (x, hi)], color))).map_err(err)?;
                let cap = |at: f64| EmptyElement::at((x, at)) + PathElement::new(vec![(-4, 0), (4, 0)], color);
                chart.draw_series([cap(lo), cap(hi)]).map_err(err)?;
            }
        }
        if s.line {
            let ann = chart.draw_series(LineSeries::new(s.points.iter().copied(), style)).map_err(err)?;
            if !s.label.is_empty() {
                legend = true;
                ann.label(svg_text(&s.label))
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
            }
        }
        if s.markers {
            chart.draw_series(s.points.iter().map(|&(x, y)| Circle::new((x, y), 3, color.filled()))).map_err(err)?;
        }
    }
    if legend {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

/// The edges of the cells around points `xs` (increasing) on `axis`'s scale: halfway between
/// neighbours, and half a spacing beyond the first and last points (a single point `x`
/// takes the spacing of `[x, 2x]`). `xs.len() + 1` edges; empty for no points.
pub fn cell_edges(xs: &[f64], axis: &Axis) -> Vec<f64> {
    let n = xs.len();
    if n == 0 {
        return Vec::new();
    }
    (0..=n)
        .map(|i| {
            if n == 1 {
                if i == 0 { axis.at(xs[0], xs[0] * 2.0, -0.5) } else { axis.at(xs[0], xs[0] * 2.0, 0.5) }
            } else if i == 0 {
                axis.at(xs[0], xs[1], -0.5)
            } else if i == n {
                axis.at(xs[n - 2], xs[n - 1], 1.5)
            } else {
                axis.mid(xs[i - 1], xs[i])
            }
        })
        .collect()
}

/// Bands from consecutive classified points: each run of equal classes becomes one band,
/// with boundaries halfway (on `axis`'s scale) between neighbouring points of different
/// class, and the outer edges half a spacing beyond the first and last points
/// ([`cell_edges`]). `class` gives a point's label and colour, or `None` for a point that
/// belongs to no band.
pub fn bands_from_classes(xs: &[f64], axis: &Axis, class: impl Fn(usize) -> Option<(String, RGBColor)>) -> Vec<Band> {
    let n = xs.len();
    let edges = cell_edges(xs, axis);
    let mut out = Vec::new();
    let mut i = 0;
    while i < n {
        let c = class(i);
        let mut j = i + 1;
        while j < n && class(j) == c {
            j += 1;
        }
        if let Some((label, color)) = c {
            out.push(Band { from: edges[i], to: edges[j], label, color });
        }
        i = j;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A name with characters XML refuses (a vertical tab, U+FFFE), a newline and XML's
    /// markup characters.
    pub(super) const AWKWARD: &str = "a\u{b}b\nc & <d> \"e\" \u{fffe}";

    /// [`AWKWARD`] as a figure's text must show it: escaped, on one line.
    pub(super) const AWKWARD_SHOWN: &str = "a\\u{b}b\\nc &amp; &lt;d&gt; &quot;e&quot; \\u{fffe}";

    /// Fails unless `svg` is well-formed XML as far as its texts go: no character XML
    /// refuses (a control character other than tab, newline and carriage return; U+FFFE,
    /// U+FFFF), every `&` an entity, every `<` a tag's; returns how often [`AWKWARD`] shows.
    pub(super) fn awkward_texts(svg: &str) -> usize {
        let refused = |c: char| (c < ' ' && !matches!(c, '\t' | '\n' | '\r')) || matches!(c, '\u{fffe}' | '\u{ffff}');
        assert!(!svg.contains(refused), "a character XML refuses: {svg}");
        for (i, _) in svg.match_indices('&') {
            let entity = ["&amp;", "&lt;", "&gt;", "&quot;", "&apos;"].iter().any(|e| svg[i..].starts_with(e));
            assert!(entity, "a bare &: {}", &svg[i..]);
        }
        for (i, _) in svg.match_indices('<') {
            assert!(svg[i + 1..].starts_with(|c: char| c.is_ascii_alphabetic() || c == '/'), "a bare <: {}", &svg[i..]);
        }
        svg.matches(AWKWARD_SHOWN).count()
    }

    /// A name from the user in a panel's title, axis labels, band and legend: escaped as
    /// text, the SVG well-formed.
    #[test]
    fn names_are_escaped_in_panels() {
        let p = Panel {
            title: AWKWARD.into(),
            x: Axis::linear(AWKWARD),
            y: Axis::linear(AWKWARD),
            series: vec![Series::line(AWKWARD, vec![(1.0, 1.0), (2.0, 2.0)], PALETTE[0])],
            bands: vec![Band { from: 1.0, to: 1.5, label: AWKWARD.into(), color: BAND_SMOOTH }],
        };
        let svg = render_svg(&[p], 600, 400).unwrap();
        assert_eq!(awkward_texts(&svg), 5, "{svg}");
        assert_eq!(svg_text("plain name"), "plain name");
        assert_eq!(svg_text("\u{ffff}"), "\\u{ffff}");
    }

    #[test]
    fn bands_split_halfway_between_classes() {
        let xs = [1.0, 2.0, 3.0, 4.0];
        let a = Axis::linear("x");
        let b = bands_from_classes(&xs, &a, |i| Some((if i < 2 { "A" } else { "B" }.to_string(), BLACK)));
        assert_eq!(b.len(), 2);
        assert_eq!((b[0].from, b[0].to, b[1].from, b[1].to), (0.5, 2.5, 2.5, 4.5));
        let l = Axis::log("x");
        let xs = [1.0, 100.0];
        let b = bands_from_classes(&xs, &l, |i| (i == 1).then(|| ("B".to_string(), BLACK)));
        assert_eq!(b.len(), 1);
        assert!((b[0].from - 10.0).abs() < 1e-12 && (b[0].to - 1000.0).abs() < 1e-9);
    }

    /// Data from `1e-300` to `1e300` on log axes (whose 5 % margins overflow and underflow)
    /// and from `-1.7e308` to `1.7e308` on a linear one: drawn in narrowed ranges, in finite
    /// time (plotters' tick search did not end on a log axis of infinite ratio).
    #[test]
    fn extreme_ranges_are_drawn() {
        for (log, lo, hi) in [(true, 0.0, f64::INFINITY), (true, 1e-320, 1e300), (false, -f64::MAX, f64::MAX)] {
            let (a, b) = drawable(log, lo, hi);
            assert!(a.is_finite() && b.is_finite() && a < b, "{log} {lo} {hi}: {a} {b}");
            if log {
                assert!(a > 0.0 && b / a <= AXIS_SPAN * (1.0 + 1e-15), "{a} {b}");
            } else {
                assert!((b - a).is_finite(), "{a} {b}");
            }
        }
        assert_eq!(drawable(true, 0.5, 20.0), (0.5, 20.0));
        assert_eq!(drawable(false, -1.0, 3.0), (-1.0, 3.0));
        let p = |x: Axis, y: Axis, points: Vec<(f64, f64)>| Panel {
            title: "t".into(),
            x,
            y,
            series: vec![Series::line("s", points, PALETTE[0])],
            bands: vec![],
        };
        let wide = vec![(1e-300, 1e-300), (1.0, 1.0), (1e300, 1e300)];
        let svg = render_svg(&[p(Axis::log("x"), Axis::log("y"), wide)], 400, 300).unwrap();
        assert!(svg.trim_end().ends_with("</svg>"));
        let huge = vec![(-f64::MAX, -f64::MAX), (f64::MAX, f64::MAX)];
        let svg = render_svg(&[p(Axis::linear("x"), Axis::linear("y"), huge)], 400, 300).unwrap();
        assert!(svg.trim_end().ends_with("</svg>"));
    }

    #[test]
    fn svg_is_deterministic_and_well_formed() {
        let p = Panel {
            title: "t".into(),
            x: Axis::log("x"),
            y: Axis::linear("y"),
            series: vec![Series::with_errors("s", vec![(1.0, 1.0), (10.0, 2.0)], vec![0.1, f64::NAN], PALETTE[0])],
            bands: vec![Band { from: 0.5, to: 3.0, label: "SI".into(), color: BAND_SMOOTH }],
        };
        let a = render_svg(std::slice::from_ref(&p), 400, 300).unwrap();
        let b = render_svg(&[p], 400, 300).unwrap();
        assert_eq!(a, b);
        assert!(a.starts_with("<svg") && a.trim_end().ends_with("</svg>"));
        // plotters writes a text element's content on its own line: `<text ...>\nSI\n</text>`.
        let texts: Vec<&str> =
            a.split("</text>").filter_map(|chunk| chunk.rsplit_once('>').map(|(_, t)| t.trim())).collect();
        assert!(texts.contains(&"SI"), "{texts:?}");
    }
}
