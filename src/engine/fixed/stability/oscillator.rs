//! The plate step's linear stability: one step of a fixed-step integrator on the
//! linearised plate `M Xdd + eta Xd + k X = 0` as a 2x2 amplification matrix, its spectral
//! radius, and the largest stable step in closed form and by a numeric search (module
//! table in [`super`]; derivations in docs/stability.md).

use crate::engine::fixed::Integrator;
use crate::engine::fixed::integrator::PlateState;
use crate::physics::Plate;

/// The linearised plate `M Xdd + eta Xd + k X = 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oscillator {
    pub mass: f64,
    pub eta: f64,
    pub k: f64,
}

/// A 2x2 matrix acting on `(X, Xd)`, row-major.
pub type Matrix = [[f64; 2]; 2];

/// The amplification matrix of one step of `integrator` for the oscillator `o`, obtained by
/// applying the engine's own plate step ([`Integrator::step`]) to the unit states
/// `(1, 0)` and `(0, 1)` with no driving (`V = 0`) and all stiffness in the spring
/// (`F_b = 0`). Inertial integrators need `M > 0`, the overdamped one `eta > 0`.
pub fn amplification(integrator: Integrator, o: Oscillator, dt: f64) -> Matrix {
    let p = Plate { mass: o.mass, eta: o.eta, k: o.k, v: 0.0 };
    let column = |x: f64, v: f64| {
        let s = integrator.step(&p, dt, PlateState { t: 0.0, t_next: dt, x, v, bond_force: 0.0 }, |_| 0.0);
        (s.x, s.v)
    };
    let (x1, v1) = column(1.0, 0.0);
    let (x2, v2) = column(0.0, 1.0);
    [[x1, x2], [v1, v2]]
}

/// Spectral radius of a real 2x2 matrix: the larger modulus of the roots of
/// `z^2 - tr z + det`.
pub fn spectral_radius(a: Matrix) -> f64 {
    let half = 0.5 * (a[0][0] + a[1][1]);
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    // (tr/2)^2 - det, written as ((a - d)/2)^2 + b c: no cancellation near a double root.
    let diff = 0.5 * (a[0][0] - a[1][1]);
    let disc = diff * diff + a[0][1] * a[1][0];
    if disc >= 0.0 {
        // Real roots half +- sqrt(disc): the larger modulus has the sign of `half`.
        half.abs() + disc.sqrt()
    } else {
        // A complex pair: |z|^2 = det (> half^2 >= 0 here).
        det.sqrt()
    }
}

/// `rho(A)` of one step of `integrator` of size `dt` for `o`.
pub fn radius(integrator: Integrator, o: Oscillator, dt: f64) -> f64 {
    spectral_radius(amplification(integrator, o, dt))
}

/// The largest stable step of `integrator` for `o`, in closed form (docs/stability.md):
/// steps `dt < dt_limit` are stable, `dt = dt_limit` has an eigenvalue of modulus 1, larger
/// steps grow. `+inf` when every step is stable, `0` when none is (explicit Euler on an
/// undamped oscillator).
pub fn dt_limit(integrator: Integrator, o: Oscillator) -> f64 {
    let Oscillator { mass: m, eta, k } = o;
    // 2 sqrt(k M), without forming k M (which could overflow).
    let s = 2.0 * k.sqrt() * m.sqrt();
    match integrator {
        Integrator::SemiImplicitEuler => {
            if k == 0.0 && eta == 0.0 {
                f64::INFINITY
            } else {
                // Root of h^2 k/M + 2 h eta/M = 4, written without cancellation.
                4.0 * m / (eta + eta.hypot(s))
            }
        }
        Integrator::ExplicitEuler => {
            if k == 0.0 {
                if eta == 0.0 { f64::INFINITY } else { 2.0 * m / eta }
            } else if eta <= s {
                // Underdamped: the complex pair leaves the unit circle at det = 1.
                eta / k
            } else {
                // Overdamped: a real eigenvalue reaches -1 first.
                4.0 * m / (eta + ((eta - s) * (eta + s)).sqrt())
            }
        }
        Integrator::VelocityVerlet => {
            if k == 0.0 {
                f64::INFINITY
            } else {
                2.0 * (m.sqrt() / k.sqrt())
            }
        }
        Integrator::Overdamped => {
            if k == 0.0 {
                f64::INFINITY
            } else {
                2.0 * eta / k
            }
        }
        // No plate equation (`X = V t`): nothing to become unstable.
        Integrator::Kinematic => f64::INFINITY,
    }
}

/// Whether a 2x2 amplification matrix is stable, by the Jury (Schur–Cohn) conditions on
/// its characteristic polynomial `z^2 - tr z + det`: both roots in the closed unit disc iff
/// `det <= 1` and `|tr| <= 1 + det`, each up to `tol` (round-off at neutral eigenvalues).
/// Unlike a threshold on [`spectral_radius`] (a square root of a discriminant that vanishes at
/// double roots), these are polynomial in the entries and keep their accuracy at the boundary.
pub fn is_stable(a: Matrix, tol: f64) -> bool {
    let tr = a[0][0] + a[1][1];
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    det <= 1.0 + tol && tr.abs() <= 1.0 + det + tol
}

/// The largest stable step found numerically: the first `dt` on a geometric scan (factor
/// 2, from `1e-300` to `1e100`, beyond which `dt^2` could overflow) whose amplification matrix fails [`is_stable`], refined by
/// bisection to relative precision `1e-13`. A cross-check of [`dt_limit`] that needs only
/// the integrator's step; assumes the stable steps form an interval `(0, dt_limit)`, which
/// holds for every integrator here.
pub fn dt_limit_numeric(integrator: Integrator, o: Oscillator, tol: f64) -> f64 {
    let unstable = |dt: f64| !is_stable(amplification(integrator, o, dt), tol);
    let mut lo = 1e-300;
    if unstable(lo) {
        return 0.0;
    }
    let mut hi = lo;
    loop {
        hi *= 2.0;
        if hi > 1e100 {
            return f64::INFINITY;
        }
        if unstable(hi) {
            break;
        }
        lo = hi;
    }
    while (hi - lo) > 1e-13 * hi {
        let mid = 0.5 * (lo + hi);
        if unstable(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [Integrator; 4] =
        [Integrator::SemiImplicitEuler, Integrator::ExplicitEuler, Integrator::VelocityVerlet, Integrator::Overdamped];

    fn osc(mass: f64, eta: f64, k: f64) -> Oscillator {
        Oscillator { mass, eta, k }
    }

    /// Brute force: `||A^n||^(1/n)` tends to `rho(A)` (Gelfand), here with `n = 2^20` by
    /// repeated squaring and rescaling (no overflow).
    fn gelfand(a: Matrix) -> f64 {
        let mul = |a: Matrix, b: Matrix| -> Matrix {
            [
                [a[0][0] * b[0][0] + a[0][1] * b[1][0], a[0][0] * b[0][1] + a[0][1] * b[1][1]],
                [a[1][0] * b[0][0] + a[1][1] * b[1][0], a[1][0] * b[0][1] + a[1][1] * b[1][1]],
            ]
        };
        let norm = |a: Matrix| a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut m = a;
        // log rho = sum of the log-scales / 2^levels.
        let mut log = 0.0;
        let levels = 20;
        for level in 0..levels {
            let s = norm(m);
            if s == 0.0 {
                return 0.0;
            }
            m = m.map(|r| r.map(|v| v / s));
            log += s.ln() / f64::from(1u32 << level);
            m = mul(m, m);
        }
        let s = norm(m);
        if s == 0.0 {
            return 0.0;
        }
        (log + s.ln() / f64::from(1u32 << levels)).exp()
    }

    /// `spectral_radius` (roots of the characteristic polynomial) against Gelfand's formula
    /// on hand-picked matrices and on the integrators' amplification matrices.
    #[test]
    fn spectral_radius_matches_brute_force_powers() {
        let cases = [
            [[1.0, 0.5], [-0.3, 0.8]],
            [[0.0, 1.0], [-1.0, 0.0]],
            [[2.0, 0.0], [0.0, -3.0]],
            [[-1.2, 0.3], [0.1, -0.9]],
            [[1.0, 1.0], [0.0, 1.0]],
            [[0.5, 10.0], [-0.001, 0.2]],
        ];
        for a in cases {
            let (r, g) = (spectral_radius(a), gelfand(a));
            // Gelfand's formula converges like n^(-1/n) for a defective matrix; 2^-20 otherwise.
            assert!((r - g).abs() <= 2e-5 * r.max(1e-300), "{a:?}: {r} vs {g}");
        }
        for i in ALL {
            for (m, eta, k, dt) in [(75.0, 75.0, 180.0, 1.0), (1.0, 0.1, 3.0, 0.7), (2.0, 5.0, 1.0, 0.3)] {
                let m = if i == Integrator::Overdamped { 0.0 } else { m };
                let a = amplification(i, osc(m, eta, k), dt);
                let (r, g) = (spectral_radius(a), gelfand(a));
                assert!((r - g).abs() <= 2e-5 * r, "{i:?}: {r} vs {g}");
            }
        }
    }

    /// The closed-form trace and determinant of each amplification matrix (module docs).
    #[test]
    fn amplification_matrices_have_the_derived_invariants() {
        let (m, eta, k, h) = (2.0, 0.7, 5.0, 0.31);
        let (c, w2) = (eta / m, k / m);
        let tr_det = |a: Matrix| (a[0][0] + a[1][1], a[0][0] * a[1][1] - a[0][1] * a[1][0]);
        let close = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-14 && (a.1 - b.1).abs() < 1e-14;
        let o = osc(m, eta, k);
        let si = tr_det(amplification(Integrator::SemiImplicitEuler, o, h));
        assert!(close(si, (2.0 - h * c - h * h * w2, 1.0 - h * c)), "{si:?}");
        let ee = tr_det(amplification(Integrator::ExplicitEuler, o, h));
        assert!(close(ee, (2.0 - h * c, 1.0 - h * c + h * h * w2)), "{ee:?}");
        let g = h * c / 2.0;
        let vv = tr_det(amplification(Integrator::VelocityVerlet, o, h));
        assert!(close(vv, (2.0 * (1.0 - h * h * w2 / 2.0) / (1.0 + g), (1.0 - g) / (1.0 + g))), "{vv:?}");
        let od = tr_det(amplification(Integrator::Overdamped, osc(0.0, eta, k), h));
        assert!(close(od, (1.0 - h * k / eta, 0.0)), "{od:?}");
    }

    /// Round-off allowance of the Jury conditions (entries of the matrices are O(1)).
    const TOL: f64 = 1e-13;

    /// How far the numeric limit may sit from the closed form: a round-off `TOL` in the Jury
    /// margin that vanishes at the limit moves the numeric limit by `TOL / slope`, with the
    /// margin's slope in `dt/dt_limit` from the module table: velocity Verlet
    /// `1 + tr + det = (4 - (w dt)^2) / (1 + dt c/2)`, slope `~ 8 / (1 + dt c/2)`; explicit
    /// Euler (underdamped) `1 - det = dt c - (w dt)^2`, slope `dt c`; the others O(1).
    fn rel_tolerance(i: Integrator, o: Oscillator, dt: f64) -> f64 {
        let c = if o.mass > 0.0 { o.eta / o.mass } else { 0.0 };
        let slope = match i {
            Integrator::VelocityVerlet => 1.0 / (1.0 + dt * c / 2.0),
            Integrator::ExplicitEuler => (dt * c).min(1.0),
            _ => 1.0,
        };
        1e-9 + 100.0 * TOL / slope
    }

    /// Closed-form limits against the numeric search on the engine's own step, across
    /// under-, critically and over-damped, undamped, stiff and free plates.
    #[test]
    fn closed_form_limits_match_the_numeric_search() {
        let mut checked = 0;
        for &m in &[1e-12, 1e-3, 1.0, 75.0, 1e6] {
            for &eta in &[0.0, 1e-3, 1.0, 75.0, 1e4] {
                for &k in &[0.0, 1e-6, 1.0, 150.0, 180.0, 1e9] {
                    for i in ALL {
                        let m = if i == Integrator::Overdamped { 0.0 } else { m };
                        if i == Integrator::Overdamped && eta == 0.0 {
                            continue;
                        }
                        let o = osc(m, eta, k);
                        let closed = dt_limit(i, o);
                        if i == Integrator::ExplicitEuler && eta == 0.0 && k > 0.0 {
                            // |eig| = sqrt(1 + (w dt)^2) > 1 at every dt: no search can find 0.
                            assert_eq!(closed, 0.0);
                            let w = (k / m).sqrt();
                            for wdt in [1e-6, 1e-3, 1.0, 10.0] {
                                let r = radius(i, o, wdt / w);
                                assert!((r / (1.0 + wdt * wdt).sqrt() - 1.0).abs() < 1e-9, "{r}");
                            }
                            continue;
                        }
                        let numeric = dt_limit_numeric(i, o, TOL);
                        let ok = if closed.is_infinite() || closed == 0.0 {
                            numeric == closed
                        } else {
                            (numeric / closed - 1.0).abs() < rel_tolerance(i, o, closed)
                        };
                        assert!(ok, "{i:?} M={m} eta={eta} k={k}: closed {closed} numeric {numeric}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 500);
        // Exactly critical damping: eta^2 = 4 k M (explicit Euler's two branches meet).
        for (m, k) in [(1.0f64, 1.0f64), (0.25, 4.0), (75.0, 3.0)] {
            let eta = 2.0 * (k * m).sqrt();
            let o = osc(m, eta, k);
            for i in [Integrator::SemiImplicitEuler, Integrator::ExplicitEuler, Integrator::VelocityVerlet] {
                let (c, n) = (dt_limit(i, o), dt_limit_numeric(i, o, TOL));
                assert!((n / c - 1.0).abs() < 1e-6, "{i:?} critical: {c} vs {n}");
            }
            assert_eq!(dt_limit(Integrator::ExplicitEuler, o), eta / k);
        }
    }

    /// Just below a limit every eigenvalue is inside the unit circle, just above one is out.
    #[test]
    fn radius_crosses_one_at_the_limit() {
        for i in ALL {
            for (m, eta, k) in [(75.0, 75.0, 180.0), (1.0, 10.0, 1.0), (1.0, 0.01, 100.0)] {
                let m = if i == Integrator::Overdamped { 0.0 } else { m };
                let o = osc(m, eta, k);
                let l = dt_limit(i, o);
                assert!(radius(i, o, 0.999 * l) < 1.0, "{i:?} {o:?}");
                assert!(radius(i, o, 1.001 * l) > 1.0, "{i:?} {o:?}");
            }
        }
    }
}
