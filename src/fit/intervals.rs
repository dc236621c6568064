//! 95 % intervals by profile likelihood.
//!
//! For free parameter `j`, the profile `D_j(y) = min over the others of chi2 - chi2_min`
//! (re-optimising the other parameters with `y_j` held, warm-started from a linear
//! prediction along the profile) is followed from the optimum towards each bound until it
//! exceeds the threshold (`chi2_1(0.95) = 3.84` with sigma given; `F_{1, n-p}(0.95)` with
//! sigma estimated from the residuals): a first point at [`FIRST_OFFSET`], then steps to
//! where a profile rising as the square of the offset would cross the threshold
//! ([`next_offset`]); the bracketed crossing is narrowed by at most [`REFINEMENTS`]
//! root-find steps on `sqrt(rise)` and placed by interpolation of `sqrt(rise)` between the
//! bracketing points ([`crossing`]; exact for a quadratic profile). A side that reaches
//! its bound below the threshold gives the
//! bound as the interval's end, flagged. A parameter both of whose sides reach their bounds
//! is undetermined; one whose profile never rises by [`FLAT`] is flagged as having no
//! visible effect on the data (a flat profile).

use super::optimise::{Settings, minimise};

/// A profile that stays below this rise (chi2 units) over both bounds is flat.
pub const FLAT: f64 = 0.1;

/// One side of an interval.
#[derive(Clone, Debug, PartialEq)]
pub struct End {
    /// Unit coordinate of the end.
    pub y: f64,
    /// The end is the bound: the profile stays below the threshold up to it.
    pub at_bound: bool,
}

/// A profile interval in unit coordinates, and the profile points that made it.
#[derive(Clone, Debug, PartialEq)]
pub struct Interval {
    pub low: End,
    pub high: End,
    /// `(y_j, rise)` at every profile point, in the order made.
    pub profile: Vec<(f64, f64)>,
    /// The largest rise seen.
    pub max_rise: f64,
    /// The lowest rise seen (below 0: the profile found a lower misfit than the optimum).
    pub min_rise: f64,
}

impl Interval {
    pub fn determined(&self) -> bool {
        !(self.low.at_bound && self.high.at_bound)
    }
    pub fn flat(&self) -> bool {
        self.low.at_bound && self.high.at_bound && self.max_rise < FLAT
    }
}

/// One side of a profile: where it crosses the threshold (`None`: it stays below it up to
/// the bound) and its points `(y_j, rise)` in the order made.
#[derive(Clone, Debug, PartialEq)]
pub struct Side {
    pub end: Option<End>,
    pub points: Vec<(f64, f64)>,
}

/// The profile interval of parameter `j` around the optimum `best` (unit coordinates), for
/// the misfit `score` whose minimum is `best_score`, in units of `unit`, at the threshold
/// `threshold`: its two sides ([`side`], which may run at the same time) joined by
/// [`interval`]. `None` if an evaluation stopped it.
pub fn profile(
    score: &(dyn Fn(&[f64]) -> Option<f64> + Sync),
    best: &[f64],
    best_score: f64,
    unit: f64,
    threshold: f64,
    j: usize,
) -> Option<Interval> {
    let low = side(score, best, best_score, unit, threshold, j, -1.0, 0.0)?;
    let high = side(score, best, best_score, unit, threshold, j, 1.0, 0.0)?;
    Some(interval(best[j], threshold, low, high))
}

/// One side of parameter `j`'s profile: followed from the optimum towards the lower bound
/// (`dir = -1`) or the upper one (`dir = 1`), the crossing of the threshold found by a
/// bracketing root-find on `sqrt(rise)` ([`next_offset`], [`crossing`]). It depends only
/// on the misfit, not on what else runs meanwhile. Each profile point re-optimises the
/// others, warm-started from a linear prediction along the profile, until their simplex's
/// misfits spread less than `0.02 * unit` or `noise` (the misfit's simulation noise, below
/// which a search follows noise), whichever is larger, or [`INNER_ITERS_PER_PARAMETER`]
/// iterations per other parameter. `None` if an evaluation stopped it.
#[allow(clippy::too_many_arguments)]
pub fn side(
    score: &(dyn Fn(&[f64]) -> Option<f64> + Sync),
    best: &[f64],
    best_score: f64,
    unit: f64,
    threshold: f64,
    j: usize,
    dir: f64,
    noise: f64,
) -> Option<Side> {
    let p = best.len();
    let others = |y: &[f64]| -> Vec<f64> { y.iter().enumerate().filter(|&(k, _)| k != j).map(|(_, &v)| v).collect() };
    let tolerance = (0.02 * unit).max(noise);
    let settings = Settings {
        step: INNER_STEP.0,
        tolerance,
        max_iters: INNER_ITERS_PER_PARAMETER * (p as u64 - 1).max(1) + 5,
        unit,
    };
    let mut points = Vec::new();
    // The rise at y_j = y, re-optimising the others from `warm`, predicted from the profile
    // point at `from`; returns (rise, others). The simplex is scaled to the step along the
    // profile, so that it can follow a valley that the prediction misses.
    let mut at = |y: f64, from: f64, warm: &[f64]| -> Option<(f64, Vec<f64>)> {
        let step = (INNER_STEP_SCALE * (y - from).abs()).clamp(INNER_STEP.0, INNER_STEP.1);
        let settings = Settings { step, ..settings };
        let held = |z: &[f64]| -> Option<f64> {
            let mut full = Vec::with_capacity(p);
            full.extend_from_slice(&z[..j]);
            full.push(y);
            full.extend_from_slice(&z[j..]);
            score(&full)
        };
        let (z, s) = minimise(&held, warm, settings)?;
        let rise = (s - best_score) / unit;
        points.push((y, rise));
        Some((rise, z))
    };
    // Offsets from the optimum towards the bound, which lies `room` away.
    let room = if dir < 0.0 { best[j] } else { 1.0 - best[j] };
    let to_y = |off: f64| (best[j] + dir * off).clamp(0.0, 1.0);
    let (mut off_in, mut d_in, mut z_in) = (0.0, 0.0, others(best));
    // The previous inner point, for a linear prediction of the others along the profile.
    let mut prev: Option<(f64, Vec<f64>)> = None;
    let mut off = FIRST_OFFSET.min(room);
    // Outwards until the rise reaches the threshold or the bound is reached below it.
    let (mut off_out, mut d_out) = loop {
        if off <= off_in {
            return Some(Side { end: None, points });
        }
        let warm = predict(&prev, to_y(off_in), &z_in, to_y(off));
        let (d, z) = at(to_y(off), to_y(off_in), &warm)?;
        if d >= threshold {
            break (off, d);
        }
        prev = Some((to_y(off_in), std::mem::replace(&mut z_in, z)));
        (off_in, d_in) = (off, d);
        if off >= room {
            return Some(Side { end: None, points });
        }
        off = next_offset(off, d, threshold).min(room);
    };
    // The bracket [off_in, off_out] narrowed by root-find steps while it is wide.
    for _ in 0..REFINEMENTS {
        if off_out - off_in <= BRACKET_WIDTH * off_out {
            break;
        }
        let w = off_out - off_in;
        let mid = crossing((off_in, d_in), (off_out, d_out), threshold).clamp(off_in + 0.1 * w, off_out - 0.1 * w);
        let warm = predict(&prev, to_y(off_in), &z_in, to_y(mid));
        let (dm, zm) = at(to_y(mid), to_y(off_in), &warm)?;
        if dm >= threshold {
            (off_out, d_out) = (mid, dm);
        } else {
            prev = Some((to_y(off_in), std::mem::replace(&mut z_in, zm)));
            (off_in, d_in) = (mid, dm);
        }
    }
    let off = crossing((off_in, d_in), (off_out, d_out), threshold);
    Some(Side { end: Some(End { y: to_y(off), at_bound: false }), points })
}

/// The first profile point's offset from the optimum (unit coordinates).
pub const FIRST_OFFSET: f64 = 0.1;
/// Growth of the offset outwards, at least and at most, per step.
pub const GROWTH: (f64, f64) = (1.5, 4.0);
/// The predicted crossing is overshot by this factor, so that one step brackets it.
pub const OVERSHOOT: f64 = 1.15;
/// Root-find steps that narrow a bracket of the crossing, at most.
pub const REFINEMENTS: usize = 2;
/// A bracket narrower than this fraction of its outer offset is not narrowed further.
pub const BRACKET_WIDTH: f64 = 0.2;
/// Iterations of a profile point's re-optimisation per other free parameter (plus five).
pub const INNER_ITERS_PER_PARAMETER: u64 = 10;
/// The initial simplex of a profile point's re-optimisation: this fraction of the step
/// along the profile from the point its start was predicted from ...
pub const INNER_STEP_SCALE: f64 = 0.5;
/// ... kept within these sizes (unit coordinates).
pub const INNER_STEP: (f64, f64) = (0.03, 0.1);

/// The next offset outwards after a point at offset `off` with rise `d` below the
/// threshold: where a profile rising as the square of the offset from the optimum would
/// cross it, `off sqrt(threshold / d)`, overshot by [`OVERSHOOT`] and kept within
/// [`GROWTH`] times `off`.
pub fn next_offset(off: f64, d: f64, threshold: f64) -> f64 {
    let predicted = if d > 0.0 { OVERSHOOT * off * (threshold / d).sqrt() } else { f64::INFINITY };
    predicted.clamp(GROWTH.0 * off, GROWTH.1 * off)
}

/// Where `sqrt(rise)` crosses `sqrt(threshold)` on the line through two profile points
/// `(offset, rise)` that bracket it (the first below, the second at or above): exact for a
/// profile that rises as the square of the distance from a vertex on the optimum's side
/// of both points (a rise below 0, from noise, counts as 0).
pub fn crossing(inner: (f64, f64), outer: (f64, f64), threshold: f64) -> f64 {
    let (a, b) = (inner.1.max(0.0).sqrt(), outer.1.max(0.0).sqrt());
    let frac = if b > a { ((threshold.sqrt() - a) / (b - a)).clamp(0.0, 1.0) } else { 1.0 };
    inner.0 + frac * (outer.0 - inner.0)
}

/// The interval from the two sides of a profile whose optimum is at `y_best`. A side that
/// stays below the threshold up to its bound ends at the bound, flagged. A side that
/// crosses it ends at the smoothing parabola's crossing (`parabola`) where that is
/// consistent with the side's own points (`smoothed_end`), else at its raw crossing.
pub fn interval(y_best: f64, threshold: f64, low: Side, high: Side) -> Interval {
    let smooth = parabola(low.points.iter().chain(&high.points), y_best, threshold);
    let end = |side: &Side, dir: f64| match &side.end {
        None => End { y: if dir < 0.0 { 0.0 } else { 1.0 }, at_bound: true },
        Some(raw) => smooth
            .and_then(|(vertex, half)| smoothed_end(&side.points, y_best, vertex + dir * half, dir, threshold))
            .map_or_else(|| raw.clone(), |y| End { y, at_bound: false }),
    };
    let (lo, hi) = (end(&low, -1.0), end(&high, 1.0));
    let mut points = low.points;
    points.extend(high.points);
    let max_rise = points.iter().map(|p| p.1).fold(0.0, f64::max);
    let min_rise = points.iter().map(|p| p.1).fold(0.0, f64::min);
    Interval { low: lo, high: hi, profile: points, max_rise, min_rise }
}

/// The parabola's crossing `e` as the end of the side towards `dir` (`points` its profile
/// points `(y, rise)`), kept in the box, if it agrees with them: on that side of the
/// optimum, beyond every point whose rise is below the threshold (the profile has shown
/// those inside the interval), and not beyond any point whose rise exceeds
/// [`SMOOTH_OUTSIDE`] thresholds (far above what the misfit's noise can explain). `None`
/// otherwise: a profile that is not parabola-like over the side (flat on one side of the
/// optimum, say) is given its raw crossing.
fn smoothed_end(points: &[(f64, f64)], y_best: f64, e: f64, dir: f64, threshold: f64) -> Option<f64> {
    let off = |y: f64| dir * (y - y_best);
    let inside = points.iter().filter(|p| p.1 < threshold).map(|p| off(p.0)).fold(0.0, f64::max);
    let outside =
        points.iter().filter(|p| p.1 > SMOOTH_OUTSIDE * threshold).map(|p| off(p.0)).fold(f64::INFINITY, f64::min);
    (off(e) > 0.0 && off(e) >= inside && off(e) <= outside).then(|| e.clamp(0.0, 1.0))
}

/// A profile point rising more than this many thresholds lies outside the interval, whatever
/// the smoothing parabola says.
pub const SMOOTH_OUTSIDE: f64 = 2.0;

/// The profile smoothed: a parabola `a + b d + c d^2` in `d = y - y_best` fitted by least
/// squares to the profile points with a rise below [`SMOOTH_CAP`] times the threshold and
/// the optimum itself (rise 0). Returns its vertex and the half-width `sqrt(threshold / c)`
/// at which it rises by the threshold; `None` without at least [`SMOOTH_MIN_POINTS`] such
/// points on each side, or without upward curvature.
fn parabola<'p>(points: impl Iterator<Item = &'p (f64, f64)>, y_best: f64, threshold: f64) -> Option<(f64, f64)> {
    let used: Vec<(f64, f64)> = std::iter::once((0.0, 0.0))
        .chain(points.filter(|p| p.1 <= SMOOTH_CAP * threshold).map(|&(y, d)| (y - y_best, d)))
        .collect();
    let side = |below: bool| used.iter().filter(|p| if below { p.0 < 0.0 } else { p.0 > 0.0 }).count();
    if side(true) < SMOOTH_MIN_POINTS || side(false) < SMOOTH_MIN_POINTS {
        return None;
    }
    // Normal equations of the least-squares fit, solved by Cramer's rule.
    let m = |k: i32| used.iter().map(|p| p.0.powi(k)).sum::<f64>();
    let r = |k: i32| used.iter().map(|p| p.0.powi(k) * p.1).sum::<f64>();
    let a = [[m(0), m(1), m(2)], [m(1), m(2), m(3)], [m(2), m(3), m(4)]];
    let det3 = |a: [[f64; 3]; 3]| {
        a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
    };
    let d = det3(a);
    if d.abs() < f64::MIN_POSITIVE {
        return None;
    }
    let rhs = [r(0), r(1), r(2)];
    let column = |k: usize| {
        let mut b = a;
        for (row, v) in b.iter_mut().zip(rhs) {
            row[k] = v;
        }
        det3(b) / d
    };
    let (b, c) = (column(1), column(2));
    (c > 0.0 && c.is_finite()).then(|| (y_best - b / (2.0 * c), (threshold / c).sqrt()))
}

/// Profile points used by the smoothing parabola rise at most this many thresholds.
pub const SMOOTH_CAP: f64 = 4.0;
/// Points the smoothing parabola needs on each side of the optimum.
pub const SMOOTH_MIN_POINTS: usize = 2;

/// The others' optimum at `y` predicted linearly from the last two profile points
/// `(y_prev, z_prev)` and `(y_in, z_in)` (just `z_in` without a previous one), in the box.
fn predict(prev: &Option<(f64, Vec<f64>)>, y_in: f64, z_in: &[f64], y: f64) -> Vec<f64> {
    match prev {
        Some((yp, zp)) if *yp != y_in => {
            let t = (y - y_in) / (y_in - yp);
            z_in.iter().zip(zp).map(|(a, b)| (a + t * (a - b)).clamp(0.0, 1.0)).collect()
        }
        _ => z_in.to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quadratic_misfit_gives_its_exact_interval() {
        // chi2 = ((y0 - 0.5) / 0.05)^2 + ((y1 - 0.4) / 0.1)^2 + correlation-free: the 95 %
        // profile interval of y0 is 0.5 +- 0.05 sqrt(3.84).
        let f = |y: &[f64]| Some(((y[0] - 0.5) / 0.05).powi(2) + ((y[1] - 0.4) / 0.1).powi(2));
        let t = 3.841458820694124;
        let iv = profile(&f, &[0.5, 0.4], 0.0, 1.0, t, 0).unwrap();
        let half = 0.05 * t.sqrt();
        assert!((iv.low.y - (0.5 - half)).abs() < 0.01 && (iv.high.y - (0.5 + half)).abs() < 0.01, "{iv:?}");
        assert!(iv.determined() && !iv.flat());
        // A parameter with no effect: both ends at the bounds, flat.
        let g = |y: &[f64]| Some(((y[0] - 0.5) / 0.05).powi(2));
        let iv = profile(&g, &[0.5, 0.4], 0.0, 1.0, t, 1).unwrap();
        assert!(iv.low.at_bound && iv.high.at_bound && iv.flat() && !iv.determined(), "{iv:?}");
        assert_eq!((iv.low.y, iv.high.y), (0.0, 1.0));
        // One side open: reaches the upper bound.
        let h = |y: &[f64]| Some(if y[0] < 0.5 { ((y[0] - 0.5) / 0.05).powi(2) } else { 0.0 });
        let iv = profile(&h, &[0.5], 0.0, 1.0, t, 0).unwrap();
        assert!(!iv.low.at_bound && iv.high.at_bound && iv.determined(), "{iv:?}");
    }

    /// A side as [`side`] leaves it, from points `(offset, rise)` in the order of their
    /// offsets: cut after the first point at or above the threshold, whose bracket gives
    /// the raw crossing; without one, the side reaches its bound.
    fn made_side(y_best: f64, dir: f64, pts: &[(f64, f64)], t: f64) -> Side {
        let to_y = |off: f64| (y_best + dir * off).clamp(0.0, 1.0);
        let (mut points, mut inner, mut end) = (Vec::new(), (0.0, 0.0), None);
        for &(off, rise) in pts {
            points.push((to_y(off), rise));
            if rise >= t {
                end = Some(End { y: to_y(crossing(inner, (off, rise), t)), at_bound: false });
                break;
            }
            inner = (off, rise);
        }
        Side { end, points }
    }

    #[test]
    fn every_interval_agrees_with_its_own_profile_points() {
        // Random profiles, noisy and lopsided (one side flat, the other steep, as a
        // parameter near a bound gives): the end of a side that reaches its bound below the
        // threshold is that bound, flagged; a side that crosses ends beyond every point of
        // it below the threshold and short of every point above two thresholds, whatever
        // the smoothing parabola fitted through both sides says.
        use rand::RngExt;
        let t = 3.841458820694124;
        let mut rng = crate::rng::pcg(20261129);
        let (mut smoothed, mut crossed, mut bounded) = (0, 0, 0);
        for _ in 0..20_000 {
            let y_best: f64 = rng.random_range(0.05..0.95);
            let noise = rng.random_range(0.0..1.5);
            let mut sides = Vec::new();
            for dir in [-1.0, 1.0] {
                let room = if dir < 0.0 { y_best } else { 1.0 - y_best };
                let c = 10f64.powf(rng.random_range(-1.0..3.0));
                let k = rng.random_range(2..6);
                let mut offs: Vec<f64> = (0..k).map(|_| rng.random_range(0.0..1.0) * room).collect();
                offs.sort_by(f64::total_cmp);
                let pts: Vec<(f64, f64)> =
                    offs.iter().map(|&o| (o, c * o * o + noise * rng.random_range(-1.0..1.0))).collect();
                sides.push(made_side(y_best, dir, &pts, t));
            }
            let (low, high) = (sides[0].clone(), sides[1].clone());
            let iv = interval(y_best, t, low.clone(), high.clone());
            for (side, end, dir) in [(&low, &iv.low, -1.0), (&high, &iv.high, 1.0)] {
                let off = |y: f64| dir * (y - y_best);
                match &side.end {
                    None => {
                        bounded += 1;
                        assert_eq!((end.y, end.at_bound), (if dir < 0.0 { 0.0 } else { 1.0 }, true), "{side:?} {iv:?}");
                    }
                    Some(raw) => {
                        crossed += 1;
                        smoothed += usize::from(end.y != raw.y);
                        assert!(!end.at_bound && off(end.y) > 0.0, "{side:?} {iv:?}");
                        for &(y, rise) in &side.points {
                            assert!(rise >= t || off(y) <= off(end.y), "{side:?} {iv:?}");
                            assert!(rise <= SMOOTH_OUTSIDE * t || off(y) >= off(end.y), "{side:?} {iv:?}");
                        }
                    }
                }
            }
        }
        // Every case was met, and the parabola placed many ends.
        assert!(smoothed > 1000 && crossed > 5000 && bounded > 1000, "{smoothed} {crossed} {bounded}");
    }

    /// Counts the evaluations of `f`.
    fn counted(
        f: impl Fn(&[f64]) -> f64 + Sync,
    ) -> (impl Fn(&[f64]) -> Option<f64> + Sync, std::sync::Arc<std::sync::atomic::AtomicUsize>) {
        let n = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let m = n.clone();
        (
            move |y: &[f64]| {
                m.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                Some(f(y))
            },
            n,
        )
    }

    #[test]
    fn the_root_find_places_a_quadratic_profiles_crossing_exactly() {
        // sqrt(rise) is linear in the offset for a quadratic profile: the interpolation
        // between any bracket on one side of the vertex gives the crossing.
        let t = 3.841458820694124;
        let c: f64 = 250.0;
        let (a, b) = (0.07, 0.23);
        let x = crossing((a, c * a * a), (b, c * b * b), t);
        assert!((x - (t / c).sqrt()).abs() < 1e-12, "{x}");
        // Vertex offset from the optimum (a noisy optimum): still exact.
        let x = crossing((a, c * (a - 0.02f64).powi(2)), (b, c * (b - 0.02f64).powi(2)), t);
        assert!((x - (0.02 + (t / c).sqrt())).abs() < 1e-12, "{x}");
        // The step outwards: the predicted crossing overshot, within the growth limits.
        assert!((next_offset(0.1, 1.0, 4.0) - OVERSHOOT * 0.2).abs() < 1e-12);
        assert_eq!(next_offset(0.1, 0.0, 4.0), GROWTH.1 * 0.1);
        assert_eq!(next_offset(0.1, 3.9, 4.0), GROWTH.0 * 0.1);
    }

    #[test]
    fn a_correlated_quadratic_misfit_gives_its_analytic_profile_interval_in_few_points() {
        // chi2 = d' C^-1 d for d = y - m, with C = [[s0^2, r s0 s1], [r s0 s1, s1^2]]: the
        // profile of y0 is (y0 - m0)^2 / s0^2, so its 95 % interval is m0 +- s0 sqrt(t),
        // whatever the correlation (the profile follows the valley: y1 moves with y0).
        let t = 3.841458820694124;
        let (m0, m1, s0, s1, r) = (0.45, 0.55, 0.08, 0.05, 0.9);
        let det = 1.0 - r * r;
        let (f, n) = counted(move |y: &[f64]| {
            let (u, v) = ((y[0] - m0) / s0, (y[1] - m1) / s1);
            (u * u - 2.0 * r * u * v + v * v) / det
        });
        let iv = profile(&f, &[m0, m1], 0.0, 1.0, t, 0).unwrap();
        let half = s0 * t.sqrt();
        // The inner optimum is found to the inner tolerance (0.02 in chi2): the ends within
        // a rise of 0.02, i.e. 0.02 / (2 t) of the half width, plus the NM's resolution.
        assert!(
            (iv.low.y - (m0 - half)).abs() < 0.01 * half && (iv.high.y - (m0 + half)).abs() < 0.01 * half,
            "{iv:?}"
        );
        assert!(iv.profile.len() <= 8, "{} profile points", iv.profile.len());
        println!(
            "{} evaluations for {} profile points",
            n.load(std::sync::atomic::Ordering::Relaxed),
            iv.profile.len()
        );
        // A profile rising as the cube of the offset: not quadratic, so the bracket is
        // narrowed by the root-find; the raw crossings (before the smoothing parabola) are
        // at +- (t / k)^(1/3).
        let k: f64 = 2000.0;
        let g = move |y: &[f64]| Some(k * (y[0] - 0.5).abs().powi(3));
        let half = (t / k).cbrt();
        for dir in [-1.0, 1.0] {
            let s = side(&g, &[0.5], 0.0, 1.0, t, 0, dir, 0.0).unwrap();
            let end = s.end.clone().unwrap();
            assert!(((end.y - 0.5).abs() - half).abs() < 0.005 * half && s.points.len() <= 5, "{s:?}");
        }
    }
}
