//! `compare.svg`: for each observable a log-log panel of |error| against wall time, one line
//! per engine, the 95 % interval of each point as an error bar (drawn to the bottom of the
//! panel when the interval contains 0), and each engine's sampling floor dashed. Points that
//! diverged or lie beyond the plate step's stability are not drawn; a note names them.

use plotters::element::DashedPathElement;
use plotters::prelude::*;

use super::{FONT, PlotError, err as e, svg_text};
use crate::scene::EngineKind;
use crate::studies::compare::{Status, Study};
use crate::studies::format::sig;

const FIXED: RGBColor = RGBColor(31, 119, 180);
const EXACT: RGBColor = RGBColor(214, 39, 40);
const PANEL_H: u32 = 440;
const WIDTH: u32 = 1200;

/// A drawable point: wall time, |error|, error-bar ends, floor, label.
struct Dot {
    x: f64,
    y: f64,
    lo: Option<f64>,
    hi: f64,
    floor: f64,
    label: String,
}

fn dots(study: &Study, i: usize, engine: EngineKind) -> Vec<Dot> {
    study
        .points
        .iter()
        .filter(|p| p.engine == engine && p.status == Status::Ok && p.wall_seconds > 0.0)
        .filter(|p| p.obs[i].error.is_finite())
        .map(|p| {
            let o = &p.obs[i];
            let contains_zero = o.ci_low <= 0.0 && o.ci_high >= 0.0;
            Dot {
                x: p.wall_seconds,
                y: o.error.abs(),
                lo: (!contains_zero).then(|| o.ci_low.abs().min(o.ci_high.abs())),
                hi: o.ci_low.abs().max(o.ci_high.abs()),
                floor: o.floor,
                label: match p.dt {
                    Some(dt) => format!("dt {}", sig(dt, 3)),
                    None => format!("x{}", p.replicas),
                },
            }
        })
        .collect()
}

/// The figure's legend, in pixels from the top left of `area`.
fn legend<DB: DrawingBackend>(area: &DrawingArea<DB, plotters::coord::Shift>, y: i32) -> Result<(), PlotError> {
    let entries = [
        (FIXED, false, "fixed-step engine (label: dt)"),
        (FIXED, true, "fixed-step sampling floor"),
        (EXACT, false, "exact engine (label: replicas)"),
        (EXACT, true, "exact sampling floor"),
    ];
    let mut x = 16;
    for (color, dashed, text) in entries {
        let line = vec![(x, y), (x + 30, y)];
        if dashed {
            area.draw(&DashedPathElement::new(line, 6, 4, color.stroke_width(1))).map_err(e)?;
        } else {
            area.draw(&PathElement::new(line, color.stroke_width(2))).map_err(e)?;
            area.draw(&Circle::new((x + 15, y), 4, color.filled())).map_err(e)?;
        }
        area.draw_text(text, &(FONT, 15).into_font().color(&BLACK), (x + 38, y - 8)).map_err(e)?;
        x += 290;
    }
    Ok(())
}

/// The SVG text of the diagram.
pub fn svg(study: &Study) -> Result<String, PlotError> {
    let nobs = study.observables.len();
    let rows = nobs.div_ceil(2) as u32;
    let notes = notes(study);
    let notes_h = 24 * notes.len() as u32 + 50;
    let height = 50 + rows * PANEL_H + notes_h;
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(e)?;
        let (title, rest) = root.split_vertically(50);
        let (grid, foot) = rest.split_vertically(rows * PANEL_H);
        title
            .draw_text(
                &format!(
                    "{}: |error| against wall time (fixed-step: {} replicas per dt; exact: 1..{} replicas; reference: \
                     exact, {} replicas)",
                    svg_text(&study.scene.name),
                    study.replicas,
                    study.replicas,
                    study.reference.replicas
                ),
                &(FONT, 18).into_font().color(&BLACK),
                (16, 16),
            )
            .map_err(e)?;
        let panels = grid.split_evenly((rows as usize, 2));
        for (i, area) in panels.iter().enumerate().take(nobs) {
            panel(area, study, i)?;
        }
        legend(&foot, 16)?;
        for (k, line) in notes.iter().enumerate() {
            foot.draw_text(line, &(FONT, 15).into_font().color(&BLACK), (16, 40 + 24 * k as i32)).map_err(e)?;
        }
        root.present().map_err(e)?;
    }
    Ok(buf)
}

fn notes(study: &Study) -> Vec<String> {
    let mut v = vec![
        "Error bars: 95 % intervals of the error (to the panel's bottom when they contain 0). Dashed: the sampling \
         floor, the error's standard deviation from sampling alone."
            .to_string(),
    ];
    for p in study.points.iter().filter(|p| p.status != Status::Ok) {
        let dt = sig(p.dt.unwrap_or(f64::NAN), 3);
        let g = crate::studies::compare::report::growth_text(p.plate_growth);
        v.push(match p.status {
            Status::Diverged => format!(
                "Not drawn: fixed dt = {dt} diverged in {} of {} replicas (plate growth {g} per step).",
                p.diverged_replicas, p.replicas
            ),
            _ => format!(
                "Not drawn: fixed dt = {dt} is unstable (plate growth {g} per step with every junction attached)."
            ),
        });
    }
    v
}

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    study: &Study,
    i: usize,
) -> Result<(), PlotError> {
    let o = study.observables[i];
    let fixed = dots(study, i, EngineKind::Fixed);
    let exact = dots(study, i, EngineKind::Exact);
    let all: Vec<&Dot> = fixed.iter().chain(&exact).collect();
    let caption = format!("{} ({})", o.label(), o.key());
    if all.is_empty() {
        area.draw_text(&format!("{caption}: nothing to draw"), &(FONT, 16).into_font().color(&BLACK), (20, 20))
            .map_err(e)?;
        return Ok(());
    }
    let xs = all.iter().map(|d| d.x);
    let (xmin, xmax) = (xs.clone().fold(f64::INFINITY, f64::min), xs.fold(0.0, f64::max));
    let ys = all.iter().flat_map(|d| [d.y, d.floor, d.lo.unwrap_or(f64::NAN)]).filter(|y| *y > 0.0 && y.is_finite());
    let ymin = ys.fold(f64::INFINITY, f64::min);
    let ymax = all.iter().flat_map(|d| [d.hi, d.y, d.floor]).filter(|y| y.is_finite()).fold(0.0, f64::max);
    let (ylo, yhi) = if ymin.is_finite() && ymax > 0.0 { (ymin / 3.0, ymax * 2.0) } else { (1e-3, 1.0) };
    let (xlo, xhi) = super::drawable(true, xmin / 1.6, xmax * 1.6);
    let (ylo, yhi) = super::drawable(true, ylo, yhi);
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 17))
        .margin(12)
        .margin_right(60)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((xlo..xhi).log_scale(), (ylo..yhi).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .light_line_style(RGBColor(238, 238, 238))
        .x_desc("wall time, s (sum over replicas)")
        .y_desc("|error|")
        .x_label_formatter(&|v| sig(*v, 2))
        .y_label_formatter(&|v| sig(*v, 2))
        .draw()
        .map_err(e)?;
    for (dots, color) in [(&fixed, FIXED), (&exact, EXACT)] {
        if dots.is_empty() {
            continue;
        }
        chart
            .draw_series(LineSeries::new(dots.iter().map(|d| (d.x, d.y.max(ylo))), color.stroke_width(2)))
            .map_err(e)?;
        chart.draw_series(dots.iter().map(|d| Circle::new((d.x, d.y.max(ylo)), 4, color.filled()))).map_err(e)?;
        chart
            .draw_series(dots.iter().map(|d| {
                PathElement::new(vec![(d.x, d.lo.unwrap_or(ylo).max(ylo)), (d.x, d.hi.min(yhi))], color.stroke_width(1))
            }))
            .map_err(e)?;
        chart
            .draw_series(DashedLineSeries::new(
                dots.iter().map(|d| (d.x, d.floor.max(ylo))),
                6,
                4,
                color.stroke_width(1),
            ))
            .map_err(e)?;
        chart
            .draw_series(dots.iter().map(|d| {
                EmptyElement::at((d.x, d.y.max(ylo)))
                    + Text::new(d.label.clone(), (6, -16), (FONT, 12).into_font().color(&color))
            }))
            .map_err(e)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::tests::{AWKWARD, awkward_texts};
    use crate::studies::compare::{Observable, Point, PointObs, Reference};
    use crate::studies::stats::ReplicaStats;

    /// A point of engine `engine` with one observable's error 0.01.
    fn point(engine: EngineKind, dt: Option<f64>) -> Point {
        let obs = PointObs { estimate: 0.51, se: 0.002, error: 0.01, ci_low: 0.006, ci_high: 0.014, floor: 0.002 };
        Point {
            engine,
            dt,
            replicas: 4,
            wall_seconds: 1.0,
            cpu_seconds: 1.0,
            status: Status::Ok,
            diverged_replicas: 0,
            plate_growth: dt.map(|_| 0.5),
            obs: vec![obs],
        }
    }

    /// The scene's name in the figure's title: escaped as text, the SVG well-formed.
    #[test]
    fn the_scene_name_is_escaped() {
        let mut scene = crate::test_scenes::fig1();
        scene.name = AWKWARD.into();
        let stats = vec![ReplicaStats { n: 16, mean: 0.5, sd: 0.01, se: 0.0025 }];
        let study = Study {
            scene,
            observables: vec![Observable::AttachedFraction],
            replicas: 4,
            exact_rtol: None,
            reference: Reference { replicas: 16, wall_seconds: 4.0, cpu_seconds: 4.0, stats },
            points: vec![point(EngineKind::Exact, None), point(EngineKind::Fixed, Some(0.5))],
            threads: 1,
        };
        assert_eq!(awkward_texts(&svg(&study).unwrap()), 1);
    }
}
