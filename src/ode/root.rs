//! Crossing detection on the dense output of a step, and Brent's bracketing root finder.

use super::system::OdeError;

/// Iteration cap of [`brent`]; never reached in practice (≈ 10–60 evaluations), it only
/// bounds the work for pathological functions.
const MAX_ITER: usize = 400;

/// Brent's method (`zeroin`, R. P. Brent, *Algorithms for Minimization without Derivatives*,
/// 1973, ch. 4) for a bracket `a < b` with `g(a) = fa < 0 <= fb = g(b)`.
///
/// Returns a point `x` in `(a, b]` with `g(x) >= 0` such that some point within
/// `4 eps max(|a|, |b|)` (plus `4 eps |x|`) below it has `g < 0`: i.e. `x` is the upper end of
/// a bracket of width about `1e-15` relative to `max(|a|, |b|)`. If the bracket holds several
/// crossings, any one of them may be returned. `None` if the bracket is not as required.
///
/// The sign test is `g >= 0` (zero counts as reached), matching [`crate::ode::Dop853::locate`].
pub fn brent<G: FnMut(f64) -> f64>(mut g: G, a: f64, b: f64, fa: f64, fb: f64) -> Option<f64> {
    if !(a < b && fa < 0.0 && fb >= 0.0) {
        return None;
    }
    let pos = |v: f64| v >= 0.0;
    let xtol = 4.0 * f64::EPSILON * a.abs().max(b.abs());
    let (mut a, mut fa, mut b, mut fb) = (a, fa, b, fb);
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    for _ in 0..MAX_ITER {
        if pos(fb) == pos(fc) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        // Now b is the best estimate and the root lies between b and c.
        let tol1 = 2.0 * f64::EPSILON * b.abs() + 0.5 * xtol;
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol1 || fb == 0.0 {
            break;
        }
        if e.abs() >= tol1 && fa.abs() > fb.abs() {
            // Inverse quadratic interpolation (or secant if only two distinct points).
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * xm * q - (tol1 * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol1 { d } else { tol1.copysign(xm) };
        fb = g(b);
    }
    // Return the end of the final bracket on the `>= 0` side.
    Some(if pos(fb) {
        b
    } else if pos(fc) {
        c
    } else {
        a
    })
}

/// First upward crossing of `g` (from `< 0` to `>= 0`) in `[t0, t1]`.
///
/// `g` is sampled at `n_sub + 1` equally spaced points including both ends; the first
/// sub-interval whose left value is `< 0` and right value `>= 0` is refined with [`brent`].
/// A value `>= 0` at `t0` is not a crossing (the crossing, if any, happened earlier); a later
/// return to `< 0` and crossing again is found. Caveat: a pair of crossings (down and up, or
/// up and down) inside one sub-interval is invisible to the sampling.
pub(super) fn first_crossing<G: FnMut(f64) -> f64>(
    t0: f64,
    t1: f64,
    n_sub: u32,
    mut g: G,
) -> Result<Option<f64>, OdeError> {
    let check = |t: f64, v: f64| {
        if v.is_finite() { Ok(v) } else { Err(OdeError::NonFiniteEvent { t, value: v }) }
    };
    let n = n_sub.max(1);
    let mut a = t0;
    let mut ga = check(t0, g(t0))?;
    for j in 1..=n {
        let b = if j == n { t1 } else { t0 + (t1 - t0) * (f64::from(j) / f64::from(n)) };
        let gb = check(b, g(b))?;
        if ga < 0.0 && gb >= 0.0 {
            let mut bad: Option<(f64, f64)> = None;
            let root = brent(
                |t| {
                    let v = g(t);
                    if !v.is_finite() && bad.is_none() {
                        bad = Some((t, v));
                    }
                    v
                },
                a,
                b,
                ga,
                gb,
            );
            if let Some((t, value)) = bad {
                return Err(OdeError::NonFiniteEvent { t, value });
            }
            // `brent` accepts the bracket: a < b (distinct values of g), ga < 0 <= gb.
            return Ok(Some(root.unwrap_or(b)));
        }
        a = b;
        ga = gb;
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ulps_apart(x: f64, y: f64) -> u64 {
        (x.to_bits() as i64 - y.to_bits() as i64).unsigned_abs()
    }

    #[test]
    fn brent_finds_cube_root_to_a_few_ulps() {
        let mut evals = 0;
        let g = |x: f64| {
            evals += 1;
            x * x * x - 2.0
        };
        let r = brent(g, 0.0, 3.0, -2.0, 25.0).unwrap();
        let exact = 2f64.cbrt();
        assert!(r * r * r - 2.0 >= 0.0);
        assert!(ulps_apart(r, exact) <= 8, "r = {r:e}, exact = {exact:e}");
        assert!(evals < 60, "evals = {evals}");
    }

    #[test]
    fn brent_returns_nonnegative_side_and_handles_flat_and_steep_functions() {
        // A step function: the "root" is the jump; returned point must have g >= 0.
        let jump = 0.123456789;
        let g = |x: f64| if x < jump { -1.0 } else { 1.0 };
        let r = brent(g, 0.0, 1.0, -1.0, 1.0).unwrap();
        assert!(r >= jump && r - jump <= 1e-15, "r - jump = {:e}", r - jump);
        // A very flat function near the root (x - 0.3)^9.
        let g = |x: f64| (x - 0.3f64).powi(9);
        let r = brent(g, 0.0, 1.0, g(0.0), g(1.0)).unwrap();
        assert!((r - 0.3).abs() < 1e-6 && g(r) >= 0.0);
        // Exact zero at the right end.
        let r = brent(|x| x - 1.0, 0.0, 1.0, -1.0, 0.0).unwrap();
        assert_eq!(r, 1.0);
        // Bad brackets.
        assert!(brent(|x| x, 0.0, 1.0, 0.0, 1.0).is_none());
        assert!(brent(|x| x, 1.0, 0.0, -1.0, 1.0).is_none());
    }

    #[test]
    fn first_crossing_semantics() {
        // Crossing inside.
        let r = first_crossing(0.0, 1.0, 8, |t| t - 0.3).unwrap().unwrap();
        assert!((r - 0.3).abs() <= 1e-15);
        // Non-monotone: below at both ends, above in the middle.
        let r = first_crossing(0.0, 1.0, 8, |t| 0.01 - (t - 0.5) * (t - 0.5)).unwrap().unwrap();
        assert!((r - 0.4).abs() <= 1e-14, "r = {r}");
        // Already >= 0 at the start and stays: no crossing.
        assert_eq!(first_crossing(0.0, 1.0, 8, |t| t).unwrap(), None);
        // Starts >= 0, dips below, comes back: the return crossing is found.
        let r = first_crossing(0.0, 1.0, 8, |t| (t - 0.25) * (t - 0.75)).unwrap().unwrap();
        assert!((r - 0.75).abs() <= 1e-14, "r = {r}");
        // Exactly at the end.
        assert_eq!(first_crossing(0.0, 1.0, 8, |t| t - 1.0).unwrap(), Some(1.0));
        // Never.
        assert_eq!(first_crossing(0.0, 1.0, 8, |t| -1.0 - t).unwrap(), None);
        // NaN is an error.
        assert!(matches!(
            first_crossing(0.0, 1.0, 8, |t| if t > 0.5 { f64::NAN } else { -1.0 }),
            Err(OdeError::NonFiniteEvent { .. })
        ));
    }
}
