//! 95 % intervals by profile likelihood.
//!
//! For free parameter `j`, the profile `D_j(y) = min over the others of chi2 - chi2_min`
//! (re-optimising the other parameters with `y_j` held, warm-started from the previous
//! profile point) is followed from the optimum towards each bound, at unit-coordinate
//! offsets [`OFFSETS`], until it exceeds the threshold (`chi2_1(0.95) = 3.84` with sigma
//! given; `F_{1, n-p}(0.95)` with sigma estimated from the residuals); the crossing is then
//! bracketed by [`BISECTIONS`] bisections and placed by linear interpolation between the
//! bracketing profile points. A side that reaches its bound below the threshold gives the
//! bound as the interval's end, flagged. A parameter both of whose sides reach their bounds
//! is undetermined; one whose profile never rises by [`FLAT`] is flagged as having no
//! visible effect on the data (a flat profile).

use super::optimise::{Settings, minimise};

/// Offsets from the optimum, in unit coordinates, at which a profile is followed outwards.
pub const OFFSETS: [f64; 7] = [0.03, 0.08, 0.16, 0.3, 0.5, 0.75, 1.0];
/// Bisections of the bracket around a crossing.
pub const BISECTIONS: usize = 3;
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
/// (`dir = -1`) or the upper one (`dir = 1`). It depends only on the misfit, not on what
/// else runs meanwhile. Each profile point re-optimises the others until their simplex's
/// misfits spread less than `0.02 * unit` or `noise` (the misfit's simulation noise, below
/// which a search follows noise), whichever is larger. `None` if an evaluation stopped it.
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
    let settings = Settings { step: 0.03, tolerance, max_iters: 10 * (p as u64 - 1).max(1) + 5, unit };
    let mut points = Vec::new();
    // The rise at y_j = y, re-optimising the others from `warm`; returns (rise, others).
    let mut at = |y: f64, warm: &[f64]| -> Option<(f64, Vec<f64>)> {
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
    let (mut y_in, mut d_in, mut z_in) = (best[j], 0.0, others(best));
    // The previous inner point, for a linear prediction of the others along the profile.
    let mut prev: Option<(f64, Vec<f64>)> = None;
    let mut end = None;
    for off in OFFSETS {
        let y = (best[j] + dir * off).clamp(0.0, 1.0);
        if y == y_in {
            break;
        }
        let warm = predict(&prev, y_in, &z_in, y);
        let (d, z) = at(y, &warm)?;
        if d >= threshold {
            let (mut y_out, mut d_out) = (y, d);
            for _ in 0..BISECTIONS {
                let mid = 0.5 * (y_in + y_out);
                let warm = predict(&prev, y_in, &z_in, mid);
                let (dm, zm) = at(mid, &warm)?;
                if dm >= threshold {
                    (y_out, d_out) = (mid, dm);
                } else {
                    prev = Some((y_in, z_in));
                    (y_in, d_in, z_in) = (mid, dm, zm);
                }
            }
            let frac = ((threshold - d_in) / (d_out - d_in)).clamp(0.0, 1.0);
            end = Some(End { y: y_in + frac * (y_out - y_in), at_bound: false });
            break;
        }
        prev = Some((y_in, std::mem::replace(&mut z_in, z)));
        (y_in, d_in) = (y, d);
        if y == 0.0 || y == 1.0 {
            break;
        }
    }
    Some(Side { end, points })
}

/// The interval from the two sides of a profile whose optimum is at `y_best`: the raw
/// crossings, replaced by the smoothing parabola's where it can be fitted.
pub fn interval(y_best: f64, threshold: f64, low: Side, high: Side) -> Interval {
    let mut points = low.points;
    points.extend(high.points);
    let mut low = low.end.unwrap_or(End { y: 0.0, at_bound: true });
    let mut high = high.end.unwrap_or(End { y: 1.0, at_bound: true });
    if let Some((vertex, half)) = parabola(&points, y_best, threshold) {
        let (lo, hi) = (vertex - half, vertex + half);
        low = if lo <= 0.0 || low.at_bound && lo < low.y {
            End { y: 0.0, at_bound: true }
        } else {
            End { y: lo.min(y_best), at_bound: false }
        };
        high = if hi >= 1.0 || high.at_bound && hi > high.y {
            End { y: 1.0, at_bound: true }
        } else {
            End { y: hi.max(y_best), at_bound: false }
        };
    }
    let max_rise = points.iter().map(|p| p.1).fold(0.0, f64::max);
    let min_rise = points.iter().map(|p| p.1).fold(0.0, f64::min);
    Interval { low, high, profile: points, max_rise, min_rise }
}

/// The profile smoothed: a parabola `a + b d + c d^2` in `d = y - y_best` fitted by least
/// squares to the profile points with a rise below [`SMOOTH_CAP`] times the threshold and
/// the optimum itself (rise 0). Returns its vertex and the half-width `sqrt(threshold / c)`
/// at which it rises by the threshold; `None` without at least [`SMOOTH_MIN_POINTS`] such
/// points on each side, or without upward curvature.
fn parabola(points: &[(f64, f64)], y_best: f64, threshold: f64) -> Option<(f64, f64)> {
    let used: Vec<(f64, f64)> = std::iter::once((0.0, 0.0))
        .chain(points.iter().filter(|p| p.1 <= SMOOTH_CAP * threshold).map(|&(y, d)| (y - y_best, d)))
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
}
