//! The series' convergence ratios, truncation tails, orders and round-off charges (module
//! doc of [`super`], "Truncation bound", "Choice of `w`, `rho`, `p`" and "Round-off
//! allowance"); [`super::SeriesSum::error_bound`] combines them with the state.

use super::coefficients::PMAX;

/// The bins' convergence ratio `q = (rho + w/2) / l0 = w / l0` (`rho = w/2`), wide bins:
/// `w = l0/4`, `rho = l0/8`, `q = 1/4` (below [`super::NARROW_FROM`] junctions, and a
/// checkpoint's series that names no ratio).
pub(super) const Q_WIDE: f64 = 0.25;
/// The same, narrow bins: `w = l0/8`, `rho = l0/16`, `q = 1/8` (a lower order for the same
/// tolerance, and twice the re-bases: the choice from [`super::NARROW_FROM`] junctions on).
pub(super) const Q_NARROW: f64 = 0.125;
/// `rho / l0` in direct mode, the convergence ratio of every junction's own expansion (no
/// bins: `rho = l0/4`).
pub(super) const Q_D: f64 = 0.25;
pub(super) const EPS: f64 = f64::EPSILON;
/// Round-off of one junction's direct coefficients `phi_taylor` plus their double-double
/// accumulation, in the norm `sum_k |dA_k| rho^k` and units of `eps kappa l0 / (1 - q)`:
/// measured at most 1.12 over `|x|/l0` in `[0, 1e6]` and `k <= 31` (unit test
/// `direct_coefficients_roundoff`), charged with a factor of about 4.5.
pub(super) const OP_ROUNDOFF: f64 = 5.0;

/// Truncation bounds of a truncated expansion with convergence ratio `q` at order `p`:
/// `(q^(p+1)/(1-q), (p+1) q^p/(1-q) + q^(p+1)/(1-q)^2)`, in units of `kappa l0` (`S`) and
/// `kappa` (`dS/dy`).
pub(super) fn tails_at(q: f64, p: usize) -> (f64, f64) {
    let qp = q.powi(p as i32);
    let p1 = p as f64 + 1.0;
    (qp * q / (1.0 - q), p1 * qp / (1.0 - q) + qp * q / ((1.0 - q) * (1.0 - q)))
}

/// The tails a series keeps for its order `p` (computed once, at construction: the error
/// bound is asked for after most events, and `powi` would be half its cost): [`tails_at`] of
/// `Q_D` (direct mode), of the bins' ratio `q` and of a junction's own expansion in bins
/// mode, `rho / l0 = q/2`.
pub(super) fn tails(q: f64, p: usize) -> [(f64, f64); 3] {
    [tails_at(Q_D, p), tails_at(q, p), tails_at(0.5 * q, p)]
}

/// Smallest order `p` whose residue bound (bin plus direct truncation) meets `rtol/4` for
/// bins of ratio `q`, `q^(p+1)/(1-q) + (q/2)^(p+1)/(1-q/2) <= rtol/4`, capped at `PMAX - 1`.
pub(super) fn order_for(q: f64, rtol: f64) -> usize {
    for p in 1..PMAX - 1 {
        if tails_at(q, p).0 + tails_at(0.5 * q, p).0 <= 0.25 * rtol {
            return p;
        }
    }
    PMAX - 1
}

/// Smallest order `p` whose direct truncation bound meets `rtol/4`,
/// `T_d = (1/4)^(p+1)/(3/4) <= rtol/4` (direct mode, `rho = l0/4`), capped at `PMAX - 1`.
pub(super) fn order_for_direct(rtol: f64) -> usize {
    for p in 1..PMAX - 1 {
        if tails_at(Q_D, p).0 <= 0.25 * rtol {
            return p;
        }
    }
    PMAX - 1
}
