//! The tilted law's total bond force `S(y) = sum_i f^x(y - c_i)` (plate at `y`, junction `i`
//! anchored at `c_i`, extension `x_i = y - c_i`) as a truncated series about a base point
//! `y0`, updated in O(p) flops per attached or detached junction. Two modes, chosen once at
//! construction ([`SeriesSum::for_junctions`]): **bins mode** re-bases in O(bins p^2) from
//! the anchors' binned moments, independent of the number `N` of junctions; **direct mode**
//! (`N < DIRECT_MAX = 8000`) keeps the junctions' offsets and re-bases in O(N p) by summing
//! their own expansions, with twice the radius (section "Direct mode" below). Measured
//! costs: docs/performance.md, "Tilted law: the bond-force series".
//!
//! **Split.** `f^x(x) = kappa x + phi(x)`, `phi(x) = -kappa l0 x h(x)`,
//! `h(x) = (x^2 + l0^2)^(-1/2)`. The linear part is kept exactly as
//! `kappa (X0 + n d)`, `d = y - y0`, `X0 = sum (y0 - c_i)` (a double-double running sum).
//! Only `phi` (bounded, analytic, singular at `x = +-i l0`) goes into the series.
//!
//! **Taylor coefficients** (`phi_taylor`). With `R = sqrt(x0^2 + l0^2)`, `t = -x0/R`,
//! `h(x0 + d) = R^-1 (1 - 2 t (d/R) + (d/R)^2)^(-1/2) = sum_k R^-(k+1) P_k(t) d^k`
//! (generating function of the Legendre polynomials), so `h_k = R^-(k+1) P_k(t)` by the
//! three-term recurrence `k P_k = (2k-1) t P_(k-1) - (k-1) P_(k-2)`, O(1) per coefficient.
//! (This is the power recurrence from `(x^2 + l0^2) h' = -x h`,
//! `k u0 h_k = -(2k-1) x0 h_(k-1) - (k-1) h_(k-2)`, after the scaling `h_k = R^-(k+1) P_k`,
//! which keeps every term in `[-1, 1]` whatever `x0/l0`: the unscaled form over- or
//! underflows like `R^-k`, the scaled one is the classical forward Legendre recurrence.) It is
//! run two steps at a time in `s = t^2` (`LEGENDRE2`), the even `P_k` and the odd `P_k/t` as
//! two independent chains, which halves the latency of the O(p) update. Then
//! `(x h)_k = x0 h_k + h_(k-1) = R^-k (P_(k-1)(t) - t P_k(t))`. This
//! difference cancels near `|t| = 1` (`|x0| >> l0`), so its error is absolute,
//! `<= 4 (k+1) eps kappa l0 R^-k` (measured `1.7 (k+1)` at worst: unit test
//! `direct_coefficients_roundoff` against a double-double evaluation of the unscaled power
//! recurrence, `|x0|/l0` in `[0, 1e6]`, all `k <= 31`); in the
//! norm `sum_k |.| rho^k` this is `O(eps kappa l0)` whatever `x0`.
//!
//! **Coefficient bound.** For every real `x0` and `k >= 0`:
//! `|phi_k(x0)| <= kappa l0 (l0/R)^(k+1) l0^-k <= kappa l0^(1-k)`.
//! Proof: `k = 0`: `|phi_0| = kappa l0 |x0|/R`. `k >= 1`: the Legendre identity
//! `(1-t^2) P_k' = k (P_(k-1) - t P_k)` gives `(x h)_k = R^-k (1-t^2) P_k'(t) / k`, and
//! Bernstein's inequality `sqrt(1-t^2) |p'(t)| <= k max_[-1,1] |p|` with `|P_k| <= 1` gives
//! `|(x h)_k| <= R^-k sqrt(1-t^2) = l0 R^-(k+1)`. (The brief's cruder bound
//! `kappa l0 (2k+1) R^-k`, from `|h_k| <= (k+1) R^-(k+1)`, also holds; the tests check both.)
//! The bound is uniform in `x0`: every junction's expansion converges with ratio `r/l0`
//! wherever it is centred.
//!
//! **Two expansions of one junction** (bins mode; the sections down to "Direct mode" are
//! about bins mode). With `|d| <= rho`:
//! - its own (direct) expansion `D_i(d) = sum_(k<=p) phi_k(y0 - c_i) d^k`, truncation error
//!   `<= kappa l0 T_d`, `T_d = sum_(k>p) (rho/l0)^k = q_d^(p+1)/(1-q_d)`, `q_d = 1/8`;
//! - the bins' double expansion `B_i(d)`: anchors are grouped on a fixed grid of width `w`
//!   (bin `j` centred at `c_b = origin + (j + 1/2) w`, `e_i = c_i - c_b`, `|e_i| <= w/2`,
//!   `x_b = y0 - c_b`), `phi(y - c_i) = sum_j phi_j(x_b) (d - e_i)^j` truncated at total
//!   degree `j <= p`: `B_i(d) = sum_k d^k sum_(m<=p-k) G_b[m][k] e_i^m`,
//!   `G_b[m][k] = (-1)^m C(m+k, k) phi_(m+k)(x_b)`. Per junction `|d - e_i| <= rho + w/2 =
//!   q l0`, so its error is `<= kappa l0 T_b`, `T_b = q^(p+1)/(1-q)`, `q = 1/4`.
//!
//! The bins hold the count and the raw moments `M_(b,m) = sum_(i in b) e_i^m` (`m <= p`),
//! so `sum_(i in b) B_i = sum_k d^k sum_m G_b[m][k] M_(b,m)` costs O(p^2) per bin, not per
//! junction.
//!
//! **Updates.** `add` puts `+e^m` into its bin's moments and `+D_i` into the series `A`;
//! `remove` puts `-e^m` and `-D_i` (both O(p): the recurrence above, the powers, two
//! double-double accumulations). `rebase(y0)` recomputes `A = sum_b sum_i B_i` from the
//! moments (O(bins p^2)) and records `n_rb = n`. So `A` is the sum over present junctions of
//! `B_i` (present at the last re-base) or `D_i` (added since), minus, for every junction
//! present at the last re-base and removed since, its `D_i`, leaving the residue
//! `B_i - D_i`, of size `<= kappa l0 (T_b + T_d)` on the disc. (This residue is why the
//! earlier version added each junction's `B_i` in O(p^2); with `D_i` an attach/detach pair
//! between re-bases still cancels exactly.) The removals carrying a residue number at most
//! `resid = min(removals since the re-base, n_rb)` (a removal cannot tell whether its
//! junction was present then, so each is charged until the cap). A bin whose count reaches 0
//! is reset to exactly zero and its slab slot freed; the handle of a junction is its bin's
//! slot, and `add` finds its bin in O(1) through a grid-index table (`Dense`, a cache of the
//! sorted bin index at most `2^20` bins wide; outside it, a binary search). `shift` moves `origin` and `y0` only (bins, `x_b`, `A`, `X0` are relative
//! quantities): O(1).
//!
//! **Truncation bound.** `|S - S_true| <= kappa l0 (n T_b + resid (T_b + T_d))` (`T_d <=
//! T_b`), and for `dS/dy` the same with `T'_q = kappa sum_(j>p) j q^(j-1) = kappa ((p+1)
//! q^p/(1-q) + q^(p+1)/(1-q)^2)`; `error_bound` is this plus the round-off allowance. No near
//! field is needed because `q < 1` for every bin, near or far.
//!
//! **Choice of `w`, `rho`, `p`.** `w/2 = rho = l0/8`, so `q = 1/4`; `p` is the smallest order
//! with `T_b + T_d <= rtol/4` (capped at `PMAX - 1 = 31`, i.e. `rtol >= ~5e-19`): the
//! truncation part of `error_bound()` is then `<= (rtol/4) kappa l0 (n + resid)`, at most
//! `(rtol/2) kappa l0 n` while `resid <= n`, leaving the other half for round-off.
//! `rtol = 1e-10` gives `p = 17`, as the O(p^2) version (criterion `T_b <= rtol/2`) did.
//!
//! **Round-off allowance** (first order in `eps`, not a proof). Norm: `|A|_rho =
//! sum_k |A_k| rho^k`; every junction's term contributes at most `kappa l0 /(1-q)` to it.
//! `A` and the bins' moments are double-double accumulators (`TwoSum`), so adding or
//! removing a term is exact to `O(eps^2)` and an attach/detach pair with the same anchor
//! cancels exactly; what remains is the rounding of each increment, charged as `OP_ROUNDOFF
//! = 5 eps kappa l0/(1-q)` per add/remove (4.5 times the worst measured, 1.12; unit test
//! `direct_coefficients_roundoff`) and, at a re-base, `(10 p + 19) eps kappa l0/(1-q)` per
//! present junction for `B_i` (powers, `G_b`, products, sums), which resets the
//! per-operation part. At evaluation we add `eps (2p + 4) n kappa l0/(1-q)` (Horner) and
//! `4 eps kappa (|X0| + n rho + sum_b n_b (|x_b| + w/2) + n (|y0 - origin| + |y0| + |origin|))`
//! (the linear part, and the anchors' rounding against the grid: the caller's shifted
//! anchors `fl(c - dy)` and ours, `origin + e`, differ by rounding in the absolute
//! coordinates). For `dS/dy` the coefficient allowance is multiplied by `p/rho` (a
//! perturbation with `|dA|_rho <= D` changes the derivative by at most `p D / rho`). The
//! per-operation part grows by `5 eps / (3/4) = 1.5e-15 kappa l0` per operation, so it reaches
//! `(rtol/2) kappa l0 n` only after `~ 3e4 n` operations without a re-base at
//! `rtol = 1e-10`; `rebase(base())` (O(bins p^2)) resets it and the residues. (Also not in
//! the bound: a computed offset `e` may exceed `w/2` by its rounding, `eps |c - origin|`, and
//! an anchor given to `remove` after a `shift` may round to a different `e` than at `add`,
//! leaving a residue of order `kappa eps |c - origin|` in the moments and in `A` until its
//! bin empties; the engine's periodic `shift` keeps `|c - origin|` small.)
//!
//! **Direct mode** ([`SeriesSum::direct`]). At small `N` the anchors fall into about as many
//! bins as there are attached junctions, so a bins re-base (O(p^2) per bin) costs more than
//! rebuilding the series junction by junction would, and the bins' radius `l0/8` (set by
//! their double expansion, `q = (rho + w/2)/l0 = 1/4`) makes the plate re-base every
//! `l0/16` of travel. Direct mode keeps no bins:
//! - *State.* The live junctions' offsets `e_i = c_i - origin` (frame-independent like the
//!   bins' offsets: `shift` moves `origin` and `y0` only) in a dense array, with stable
//!   handles through a handle -> position table and swap-remove (O(1)). `add` adds `D_i`
//!   (`phi_taylor(x_i)`, `x_i = base_off - e_i = y0 - c_i`) to `A` and `x_i` to `X0`;
//!   `remove` subtracts the same `D_i` and `x_i`, computed from the stored offset, not from
//!   the caller's `c`. So `A = sum_i D_i` at all times: no residue, and an add/remove pair
//!   cancels exactly in the double-double accumulators (the high parts' `TwoSum` is exact;
//!   only the low parts' own sums round, `O(eps^2 |A|)`).
//! - *Re-base.* `rebase(y0)` rebuilds `A = sum_i D_i(y0)`, `X0 = sum_i x_i` and the spread
//!   `sum_i |x_i|` from the offsets, O(N p): eight junctions at a time through `phi_taylor_lanes`
//!   (`phi_taylor` on a structure of arrays, one pass, each lane to its own order, compiled
//!   to packed SSE2 operations on baseline x86-64 and to AVX2 ones where the processor has
//!   it; bit for bit `phi_taylor`'s values, unit tests `phi_taylor_lanes_is_phi_taylor` and
//!   `direct_sums_are_the_same_in_every_vector_width`), in `graded.rs`.
//! - *Radius and order.* Only the junctions' own expansions are left, so `rho = l0/4`
//!   (`q_d = rho/l0 = 1/4`: twice the bins' radius, half the re-bases) and `p` is the
//!   smallest order with `T_d = q_d^(p+1)/(1-q_d) <= rtol/4` (`p = 17` at `rtol = 1e-10`,
//!   as in bins mode; capped at 31). That order is the worst junction's (`x0 = 0`); each
//!   junction keeps its own expansion only to the order its distance from its anchor needs
//!   for the same tails (*graded orders*, `graded.rs`: at `rtol = 1e-10`, order 10 at
//!   `|x0| = 2 l0`, 8 at `4 l0`), in `add`, `remove` and the re-base alike.
//! - *Truncation bound.* `|S - S_true| <= kappa l0 n T_d` and `|dS/dy - S'_true| <= kappa n
//!   T'_(q_d)` (the coefficient bound above with `|d| <= l0/4`; with graded orders each
//!   junction's tails are within these, `graded.rs`): at most `(rtol/4) kappa l0
//!   n`. A junction at `x0 = 0` with the plate at the radius attains it within a factor
//!   3 to 40 (`p = 4` to 17; test `direct_bound_is_nearly_attained`).
//! - *Round-off.* `|D_i|_rho <= kappa l0/(1 - q_d)` and `q_d = q`, so the unit `eps kappa
//!   l0/(1-q)`, the per-operation charge `OP_ROUNDOFF` (measured at `rho = l0/4` too: 1.13,
//!   `direct_coefficients_roundoff`), the Horner and the linear part's allowances are those
//!   above (the spread is `sum_i |x_i|` itself). A re-base adds the terms in plain `f64`
//!   per lane and coefficient over blocks of `BLOCK = 8` batches, adds the four lanes
//!   pairwise and the block total to the double-double `A` (`TwoSum`, exact to `O(eps^2)`).
//!   By the bound `gamma_(m-1) sum |terms|` of recursive summation (`u = eps/2`), each
//!   present junction's term carries at most `(BLOCK - 1) u + 2 u = 4.5 eps` of summation
//!   error besides its coefficients' own, so a re-base restarts the allowance at
//!   `REBUILD_ROUNDOFF = OP_ROUNDOFF + (BLOCK + 1)/2 = 9.5` per present junction (for the
//!   bins, `10 p + 19`). Summing all `N` terms in plain `f64` would charge `(N/4) u` per
//!   junction, `O(N eps)` relative; the blocks keep it independent of `N` at one
//!   double-double addition per 32 terms. `X0` is summed in double-double per lane.
//! - *Threshold.* [`SeriesSum::for_junctions`] takes direct mode for `N < DIRECT_MAX =
//!   8000`: on the scaled Fig. 1 scene direct mode is the faster below about 7000 junctions
//!   with weak bonds and about 15000 with strong bonds (a re-base costs O(N_att p) against
//!   the bins' O(bins p^2) twice as often, and the number of bins stops growing with `N`
//!   once they cover the anchors' spread); measured figures and the command:
//!   docs/performance.md, "Exact engine, tilted law".
//!
//! **Use (engine).** Keep `|y - base()| <= radius()` (call `rebase(y)` when the plate leaves
//! it); give `remove` the anchor exactly as given to `add` (or as moved by the caller's own
//! `shift` arithmetic) with the handle `add` returned; `integral(y0, y1)` is within
//! `|y1 - y0| error_bound()` plus its own evaluation rounding (a few `eps |result|`); compare
//! `error_bound()` with `rtol kappa l0 max(len, 1)` now and then and call `rebase(base())`
//! when it has used up its half (the stick phase of a long run, where the plate stays within
//! the radius for many events: the residues then grow to at most `n_rb (T_b + T_d)`, and the
//! per-operation round-off without limit; in direct mode only the latter, and the refresh
//! costs O(N p)). The state serialises (checkpoints) with the residue count; the per-bin
//! matrices `G_b` are not stored at all (a re-base forms them bin by bin). Direct mode
//! writes its offsets and handles instead of the bins (`Wire`).
//!
//! **Local cubic** (`taylor_at`, `LocalCubic`): `[S, S', S''/2, S'''/6]` at a point in one
//! Horner pass, with `r4 = sum_(k>=4) C(k,4) |A_k| rho^(k-4)` bounding `|S''''|/24` (so the
//! cubic's remainder by `r4 e^4`) against the series; the plate's steps evaluate it instead
//! of the series when their excursion is small (`engine::exact::series::motion`).

use serde::{Deserialize, Serialize};

use super::graded::{Grades, direct_sums};
use crate::physics::Tilted;

/// Length of the fixed coefficient arrays: orders `p <= PMAX - 1`.
pub const PMAX: usize = 32;
/// `q = (rho + w/2) / l0`, the convergence ratio of every bin's double expansion.
const Q: f64 = 0.25;
/// `rho / l0`, the convergence ratio of a junction's own expansion about the base (bins mode).
const Q_DIRECT: f64 = 0.125;
/// `rho / l0` in direct mode, the convergence ratio of every junction's own expansion (no
/// bins: `rho = l0/4`).
pub(super) const Q_D: f64 = 0.25;
/// Direct mode below this many junctions ([`SeriesSum::for_junctions`]); bins mode from it on.
pub const DIRECT_MAX: usize = 8000;
/// Junctions per lane of the direct re-base's batches (`LANES` at a time).
pub(super) const LANES: usize = 4;
/// Batches summed in plain `f64` (per lane and coefficient) between two folds into the
/// double-double series: each lane's block sum has at most `BLOCK` terms.
pub(super) const BLOCK: usize = 8;
/// Round-off of one present junction's term in a direct re-base, in units of
/// `eps kappa l0 / (1 - q)`: its coefficients (`OP_ROUNDOFF`, which covers `phi_taylor` at
/// `rho = l0/4`: unit test `direct_coefficients_roundoff`) plus the plain-`f64` block sums,
/// `(BLOCK - 1) u` per lane and `2 u` for adding the four lanes (`u = eps/2`; first order,
/// Higham's bound for recursive summation), the fold into the double-double series exact
/// to `O(eps^2)`.
const REBUILD_ROUNDOFF: f64 = OP_ROUNDOFF + 0.5 * (BLOCK as f64 + 1.0);
const EPS: f64 = f64::EPSILON;
/// Round-off of one junction's direct coefficients `phi_taylor` plus their double-double
/// accumulation, in the norm `sum_k |dA_k| rho^k` and units of `eps kappa l0 / (1 - q)`:
/// measured at most 1.12 over `|x|/l0` in `[0, 1e6]` and `k <= 31` (unit test
/// `direct_coefficients_roundoff`), charged with a factor of about 4.5.
const OP_ROUNDOFF: f64 = 5.0;

/// The Legendre recurrence `k P_k = (2k-1) t P_(k-1) - (k-1) P_(k-2)` taken two steps at a
/// time in `s = t^2`: `P_(k+2) = (al_k s - be_k) P_k - ga_k P_(k-2)` (`k >= 2`), with
/// `a_k = (2k-1)/k`, `b_k = (k-1)/k`: `al_k = a_(k+2) a_(k+1)`,
/// `be_k = a_(k+2) b_(k+1) / a_k + b_(k+2)`, `ga_k = a_(k+2) b_(k+1) b_k / a_k` (eliminate
/// `t P_(k+1)` and `t P_(k-1)` with the one-step rule). It holds for the even `P_k` and for
/// the odd `Q_k = P_k / t` alike: two independent chains of half the length.
const LEGENDRE2: [[f64; 3]; PMAX] = {
    const fn a(k: usize) -> f64 {
        (2.0 * k as f64 - 1.0) / k as f64
    }
    const fn b(k: usize) -> f64 {
        (k as f64 - 1.0) / k as f64
    }
    let mut t = [[0.0; 3]; PMAX];
    let mut k = 2;
    while k < PMAX {
        t[k] = [a(k + 2) * a(k + 1), a(k + 2) * b(k + 1) / a(k) + b(k + 2), a(k + 2) * b(k + 1) * b(k) / a(k)];
        k += 1;
    }
    t
};

/// Taylor coefficients of the nonlinear part `phi(x) = f^x(x) - kappa x = -kappa l0 x h(x)`
/// about `x`, `out[k] = phi_k(x)` (computed directly, without the cancellation of
/// subtracting `kappa x` from `tilted_taylor`): `phi_0 = kappa l0 x/R`,
/// `phi_k = -kappa l0 R^-k (P_(k-1)(t) - t P_k(t))`, `R = sqrt(x^2 + l0^2)`, `t = -x/R`,
/// `P_k` by the Legendre recurrence (`LEGENDRE2`: even `P_k` and odd `P_k / t` as two
/// independent chains in `s = t^2 = x^2/R^2`, half the latency of one). O(1) per coefficient.
#[inline]
pub fn phi_taylor(law: &Tilted, x: f64, out: &mut [f64]) {
    let n = out.len();
    if n == 0 {
        return;
    }
    let l0 = law.l0;
    // `1/R^2`, `1/R`, `s = x^2/R^2`, `t`; without the libm call where no square over- or
    // underflows, and `s` without waiting for the square root.
    let big = x.abs().max(l0);
    let (inv_u, inv_r, s, t) = if (1e-150..=1e150).contains(&big) {
        let u = x * x + l0 * l0;
        let inv_u = 1.0 / u;
        let inv_r = u.sqrt() * inv_u;
        (inv_u, inv_r, x * x * inv_u, -x * inv_r)
    } else {
        let inv_r = 1.0 / x.hypot(l0);
        let t = -x * inv_r;
        (inv_r * inv_r, inv_r, t * t, t)
    };
    let a = -law.kappa * l0;
    out[0] = -a * t;
    // pk[k] = P_k (even k), P_k / t (odd k), k <= n.
    let mut pk = [0.0; PMAX + 3];
    pk[0] = 1.0;
    pk[1] = 1.0;
    pk[2] = 1.5 * s - 0.5;
    pk[3] = 2.5 * s - 1.5;
    let (mut e0, mut e1, mut o0, mut o1) = (pk[0], pk[2], pk[1], pk[3]);
    let mut k = 2;
    while k + 2 < n {
        let [al, be, ga] = LEGENDRE2[k];
        let ne = (al * s - be) * e1 - ga * e0;
        let [al, be, ga] = LEGENDRE2[k + 1];
        let no = (al * s - be) * o1 - ga * o0;
        (e0, e1, o0, o1) = (e1, ne, o1, no);
        pk[k + 2] = ne;
        pk[k + 3] = no;
        k += 2;
    }
    // phi_k = a R^-k (P_(k-1) - t P_k): odd k: P_(k-1) - s Q_k; even k: t (Q_(k-1) - P_k).
    let (mut so, mut se) = (a * inv_r, a * inv_u);
    let mut k = 1;
    while k + 1 < n {
        out[k] = so * (pk[k - 1] - s * pk[k]);
        out[k + 1] = se * (t * (pk[k] - pk[k + 1]));
        so *= inv_u;
        se *= inv_u;
        k += 2;
    }
    if k < n {
        out[k] = so * (pk[k - 1] - s * pk[k]);
    }
}

/// [`phi_taylor`] on `W` points at once, a multiple of `LANES` (structure of arrays, so that
/// each step is one operation on a vector of lanes): `acc[k][l % LANES] += phi_k(x[l])` for
/// `k < n[l]`, the lanes added in order of `l` (so `W = 2 LANES` adds two batches in the
/// order two calls with `W = LANES` would, bit for bit, with twice the independent work in
/// flight to cover each lane's chain of dependent steps). Bit for bit [`phi_taylor`]'s
/// values (the same operations in the same order, none fused). Every lane runs to the
/// largest `n[l]`; a lane's terms beyond its own `n[l]` are added as `+0`, which leaves its
/// sums unchanged (they start at `+0` and never become `-0`). Every `max(|x[l]|, l0)` must
/// lie in `[1e-150, 1e150]` (the caller checks; outside, [`phi_taylor`] takes its `hypot`
/// branch).
#[inline(always)]
pub(super) fn phi_taylor_lanes<const W: usize>(
    law: &Tilted,
    x: [f64; W],
    n: [usize; W],
    acc: &mut [[f64; LANES]; PMAX],
) {
    let top = n.iter().copied().max().unwrap_or(0);
    debug_assert!(n.iter().all(|v| (1..=PMAX).contains(v)));
    // Whether coefficient `k` is kept, per lane, as a comparison of floats (one vector compare).
    let last: [f64; W] = std::array::from_fn(|l| n[l] as f64);
    let l0 = law.l0;
    let (mut inv_u, mut inv_r, mut s, mut t) = ([0.0; W], [0.0; W], [0.0; W], [0.0; W]);
    for l in 0..W {
        let u = x[l] * x[l] + l0 * l0;
        inv_u[l] = 1.0 / u;
        inv_r[l] = u.sqrt() * inv_u[l];
        s[l] = x[l] * x[l] * inv_u[l];
        t[l] = -x[l] * inv_r[l];
    }
    let a = -law.kappa * l0;
    for l in 0..W {
        acc[0][l % LANES] += -a * t[l];
    }
    // One pass, without `phi_taylor`'s array of `P_k`: at odd `k`, `phi_k` needs `P_(k-1)`
    // and `Q_k = P_k / t`, `phi_(k+1)` needs `Q_k` and `P_(k+1)`; then the two chains step
    // to `P_(k+3)` and `Q_(k+2)`. The same operations as `phi_taylor`'s two loops.
    let mut pm = [1.0; W]; // P_(k-1)
    let mut pp = [0.0; W]; // P_(k+1)
    let mut qm = [0.0; W]; // Q_(k-2)
    let mut qc = [1.0; W]; // Q_k
    let (mut so, mut se) = ([0.0; W], [0.0; W]);
    for l in 0..W {
        pp[l] = 1.5 * s[l] - 0.5;
        so[l] = a * inv_r[l];
        se[l] = a * inv_u[l];
    }
    let mut k = 1;
    while k < top {
        let kf = k as f64;
        for l in 0..W {
            let v = so[l] * (pm[l] - s[l] * qc[l]);
            acc[k][l % LANES] += if kf < last[l] { v } else { 0.0 };
        }
        if k + 1 == top {
            break;
        }
        for l in 0..W {
            let v = se[l] * (t[l] * (qc[l] - pp[l]));
            acc[k + 1][l % LANES] += if kf + 1.0 < last[l] { v } else { 0.0 };
        }
        if k + 2 >= top {
            break;
        }
        let [ae, be, ge] = LEGENDRE2[k + 1];
        let (mut pn, mut qn) = ([0.0; W], [0.0; W]);
        for l in 0..W {
            so[l] *= inv_u[l];
            se[l] *= inv_u[l];
            pn[l] = (ae * s[l] - be) * pp[l] - ge * pm[l];
        }
        if k == 1 {
            for l in 0..W {
                qn[l] = 2.5 * s[l] - 1.5;
            }
        } else {
            let [ao, bo, go] = LEGENDRE2[k];
            for l in 0..W {
                qn[l] = (ao * s[l] - bo) * qc[l] - go * qm[l];
            }
        }
        (pm, pp, qm, qc) = (pp, pn, qc, qn);
        k += 2;
    }
}

/// Taylor coefficients of the tilted law's horizontal force about `x`:
/// `out[k] = (d^k f^x/dx^k)(x) / k!` for `k = 0..out.len()`.
///
/// `f^x = kappa x + phi`, `phi_k = -kappa l0 (x h)_k`, `(x h)_k = R^-k (P_(k-1)(t) - t P_k(t))`,
/// `R = sqrt(x^2 + l0^2)`, `t = -x/R` (module doc). O(1) per coefficient.
pub fn tilted_taylor(law: &Tilted, x: f64, out: &mut [f64]) {
    phi_taylor(law, x, out);
    if let Some(o) = out.first_mut() {
        *o += law.kappa * x;
    }
    if let Some(o) = out.get_mut(1) {
        *o += law.kappa;
    }
}

/// The first `M` coefficients of `sum_(k<=p) (a_k + al_k) z^k` re-centred at `z = t0`, all
/// side by side as polynomials in `t0` ([`recentred_in`]), in 256-bit vectors where the
/// processor has AVX2 (the same operations, so the same values bit for bit; [`direct_sums`]).
#[inline]
fn recentred<const M: usize>(a: &[f64; PMAX], al: &[f64; PMAX], p: usize, t0: f64) -> [f64; M] {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2, checked just above.
        return unsafe { recentred_avx2::<M>(a, al, p, t0) };
    }
    recentred_in::<M>(a, al, p, t0)
}

/// [`recentred_in`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn recentred_avx2<const M: usize>(a: &[f64; PMAX], al: &[f64; PMAX], p: usize, t0: f64) -> [f64; M] {
    recentred_in::<M>(a, al, p, t0)
}

/// Widest re-centring asked for ([`recentred`]'s `M`).
const RECENTRED_MAX: usize = 12;

/// `C(m + j, j)` at `[m][j]` (`m < PMAX + 3`: [`recentred_in`]'s chains read up to three
/// rows past `p`; `j < RECENTRED_MAX`; exact in `f64`).
const BINOM_SHIFT: [[f64; RECENTRED_MAX]; PMAX + 3] = {
    let mut t = [[0.0; RECENTRED_MAX]; PMAX + 3];
    let mut m = 0;
    while m < PMAX + 3 {
        let mut c = 1u64;
        let mut j = 0;
        while j < RECENTRED_MAX {
            t[m][j] = c as f64;
            // C(m + j + 1, j + 1) = C(m + j, j) (m + j + 1) / (j + 1), exact in integers.
            c = c * (m + j + 1) as u64 / (j + 1) as u64;
            j += 1;
        }
        m += 1;
    }
    t
};

/// [`recentred`]: `out[j] = sum_m C(m + j, j) A_(m+j) t0^m` (`A_k = a_k + al_k`, zero above
/// `p`), all `j` side by side: a polynomial in `t0` with vector coefficients `B_m = (C(m +
/// j, j) A_(m+j))_j`, so a multiply and an add per coefficient and lane with no lane
/// crossing. It is evaluated as four Horner chains in `t0^4` (`m = 4i + r`, combined as `(c0
/// + t0 c1) + t0^2 (c2 + t0 c3)`), independent of one another, for a quarter of one chain's
/// latency. A term of degree `m` carries a relative rounding of about `(5m/4 + 6) eps`
/// (`t0^4` itself two or three roundings, two per chain step, the product and the
/// combination), within the `(2p + 4) eps` of a Horner evaluation that the round-off
/// allowance charges (module doc) for `p >= 3`. O(p M).
#[inline(always)]
fn recentred_in<const M: usize>(a: &[f64; PMAX], al: &[f64; PMAX], p: usize, t0: f64) -> [f64; M] {
    const { assert!(M <= RECENTRED_MAX) };
    // Whole arrays (vector operations): the series keeps `a_k = al_k = 0` above `p`.
    debug_assert!(a.iter().zip(al).skip(p + 1).all(|(h, l)| *h == 0.0 && *l == 0.0));
    let mut sum = [0.0; PMAX + 3 + RECENTRED_MAX];
    for k in 0..PMAX {
        sum[k] = a[k] + al[k];
    }
    let t2 = t0 * t0;
    let t4 = t2 * t2;
    let mut c = [[0.0; M]; 4];
    for i in (0..=p.min(PMAX - 1) / 4).rev() {
        for (r, cr) in c.iter_mut().enumerate() {
            let m = 4 * i + r;
            let row = &BINOM_SHIFT[m];
            let coef: &[f64; M] = sum[m..m + M].try_into().expect("M <= RECENTRED_MAX");
            for j in 0..M {
                cr[j] = cr[j] * t4 + row[j] * coef[j];
            }
        }
    }
    let mut out = [0.0; M];
    for j in 0..M {
        out[j] = (c[0][j] + t0 * c[1][j]) + t2 * (c[2][j] + t0 * c[3][j]);
    }
    out
}

/// `a + b` as a double-double `(hi, lo)` (Knuth's TwoSum, exact).
#[inline]
pub(super) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// Double-double accumulator.
#[inline]
pub(super) fn dd_add(acc: &mut [f64; 2], x: f64) {
    let (s, e) = two_sum(acc[0], x);
    let (hi, lo) = two_sum(s, acc[1] + e);
    *acc = [hi, lo];
}

/// `(hi, lo) += x` elementwise, double-double.
#[inline]
pub(super) fn dd_add_all(hi: &mut [f64], lo: &mut [f64], x: &[f64]) {
    for ((h, l), &v) in hi.iter_mut().zip(lo.iter_mut()).zip(x) {
        let (s, e) = two_sum(*h, v);
        *h = s;
        *l += e;
    }
}

/// `(hi, lo) += sign x` elementwise, double-double (`sign = +-1`, exact).
#[inline]
fn dd_add_all_signed(hi: &mut [f64], lo: &mut [f64], x: &[f64], sign: f64) {
    for ((h, l), &v) in hi.iter_mut().zip(lo.iter_mut()).zip(x) {
        let (s, e) = two_sum(*h, sign * v);
        *h = s;
        *l += e;
    }
}

/// One bin of anchors: grid index, count, raw moments about the centre.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Bin {
    /// Grid index `j`: centre `origin + (j + 1/2) w`.
    j: i64,
    /// Number of anchors; 0 marks a free slab slot.
    count: u64,
    /// `M_m = sum e_i^m`, `m = 0..=p`, double-double: high parts ...
    m: [f64; PMAX],
    /// ... and low parts.
    ml: [f64; PMAX],
}

/// No bin in a `Dense` entry.
const NONE: u32 = u32::MAX;
/// Largest span of grid indices `Dense` covers (4 MB); beyond, lookups fall back to the
/// binary search of `index`.
const DENSE_MAX: usize = 1 << 20;

/// Grid index `j` -> slot for `j` in `[j_lo, j_lo + slots.len())` (`NONE`: no bin there), a
/// cache of `index` for an O(1) lookup on `add`. Every live bin in that range is recorded,
/// so `NONE` in range means absent. Not part of the state: rebuilt on reading, ignored by `==`.
#[derive(Clone, Debug, Default)]
struct Dense {
    j_lo: i64,
    slots: Vec<u32>,
}

impl PartialEq for Dense {
    fn eq(&self, _: &Dense) -> bool {
        true
    }
}

impl Dense {
    /// `Some(slot or NONE)` when `j` is in range.
    #[inline]
    fn get(&self, j: i64) -> Option<u32> {
        self.slots.get(j.wrapping_sub(self.j_lo) as u64 as usize).copied()
    }

    /// Records `slot` (or `NONE`) at `j`; out of range, grows to cover `j` (rebuilding from
    /// `index`) unless the span would exceed `DENSE_MAX`.
    fn set(&mut self, j: i64, slot: u32, index: &[(i64, u32)]) {
        let d = j.wrapping_sub(self.j_lo) as u64 as usize;
        if let Some(s) = self.slots.get_mut(d) {
            *s = slot;
            return;
        }
        if slot == NONE {
            return;
        }
        let (lo, hi) = match (index.first(), index.last()) {
            (Some(&(a, _)), Some(&(b, _))) => (a.min(j), b.max(j)),
            _ => (j, j),
        };
        let span = hi.saturating_sub(lo).saturating_add(1);
        let margin = (span / 2).clamp(16, 1024);
        let (lo, len) = (lo.saturating_sub(margin), span.saturating_add(2 * margin));
        if len as u64 > DENSE_MAX as u64 {
            // Too sparse: keep the old range (still exact for its own bins).
            return;
        }
        self.j_lo = lo;
        self.slots.clear();
        self.slots.resize(len as usize, NONE);
        for &(jj, ss) in index {
            self.slots[(jj - lo) as usize] = ss;
        }
        self.slots[(j - lo) as usize] = slot;
    }
}

/// Direct mode's junctions: their offsets `e_i = c_i - origin` (frame-independent, like the
/// bins' offsets) in a dense array, and stable handles through a handle -> position table
/// (swap-remove: O(1) `add` and `remove`), and their graded orders.
#[derive(Clone, Debug, PartialEq)]
struct Direct {
    /// `e_i` of the live junctions, positions `0..n`.
    e: Vec<f64>,
    /// The handle of the junction at each position.
    handle: Vec<u32>,
    /// The position of each handle (`NONE`: free).
    pos: Vec<u32>,
    /// Free handles.
    free: Vec<u32>,
    /// The junctions' orders (derived from `law.l0` and `p`, not serialised).
    grades: Grades,
}

/// Serialized form of [`Direct`] (the position table is rebuilt on reading).
#[derive(Clone, Debug, Serialize, Deserialize)]
struct DirectWire {
    e: Vec<f64>,
    handle: Vec<u32>,
    free: Vec<u32>,
}

impl Direct {
    /// No junctions, orders `grades`.
    fn new(grades: Grades) -> Direct {
        Direct { e: Vec::new(), handle: Vec::new(), pos: Vec::new(), free: Vec::new(), grades }
    }

    /// The junctions read from `w` (the position table rebuilt), orders `grades`.
    fn from_wire(w: DirectWire, grades: Grades) -> Direct {
        let len = w.handle.iter().chain(&w.free).map(|&h| h as usize + 1).max().unwrap_or(0);
        let mut pos = vec![NONE; len];
        for (i, &h) in w.handle.iter().enumerate() {
            pos[h as usize] = i as u32;
        }
        Direct { e: w.e, handle: w.handle, pos, free: w.free, grades }
    }

    /// Stores a junction with offset `e`; returns its handle. O(1).
    #[inline]
    fn insert(&mut self, e: f64) -> u32 {
        let at = self.e.len() as u32;
        let h = match self.free.pop() {
            Some(h) => {
                self.pos[h as usize] = at;
                h
            }
            None => {
                self.pos.push(at);
                self.pos.len() as u32 - 1
            }
        };
        self.e.push(e);
        self.handle.push(h);
        h
    }

    /// Forgets the junction with handle `h`; returns its offset as stored. O(1).
    #[inline]
    fn take(&mut self, h: u32) -> f64 {
        let at = self.pos.get(h as usize).copied().unwrap_or(NONE);
        assert!(at != NONE, "SeriesSum::remove: handle {h} has no junction");
        let at = at as usize;
        let e = self.e.swap_remove(at);
        self.handle.swap_remove(at);
        if let Some(&moved) = self.handle.get(at) {
            self.pos[moved as usize] = at as u32;
        }
        self.pos[h as usize] = NONE;
        self.free.push(h);
        e
    }
}

/// Serialized form of `SeriesSum`. `n_rb` and `resid` are absent from checkpoints written
/// before the O(p) update: such a state is read as re-based with every present junction
/// counted through the bins (`n_rb = n`, `resid = 0`), which is what it was. Direct mode
/// writes `direct` and no `bins`, `free`, `index` (a reader that knows only the bins then
/// refuses the state instead of misreading it); bins mode writes the same bytes as before
/// direct mode existed.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Wire {
    law: Tilted,
    p: usize,
    base: f64,
    origin: f64,
    base_off: f64,
    n: u64,
    x0: [f64; 2],
    a: [f64; PMAX],
    al: [f64; PMAX],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    bins: Option<Vec<Bin>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    free: Option<Vec<u32>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    index: Option<Vec<(i64, u32)>>,
    roff: f64,
    spread: f64,
    #[serde(default)]
    n_rb: Option<u64>,
    #[serde(default)]
    resid: u64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    direct: Option<DirectWire>,
    /// Direct mode's series holds each junction to its own order (graded orders). Absent
    /// from checkpoints written before them, whose series is then rebuilt on reading.
    #[serde(default)]
    graded: bool,
}

/// The bond force `S(y) = sum_i f^x(y - c_i)` of a set of junctions under the tilted law,
/// kept as `kappa (X0 + n d) + sum_(k<=p) A_k d^k`, `d = y - base`, plus anchor bins for
/// O(bins) re-basing (bins mode) or the junctions' offsets for an O(n) one (direct mode),
/// chosen at construction (module doc).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "Wire", into = "Wire")]
pub struct SeriesSum {
    law: Tilted,
    /// Order: coefficients `A_0..=A_p`, bin moments `M_0..=M_p`.
    p: usize,
    /// Base point `y0` in the current frame.
    base: f64,
    /// Grid origin in the current frame.
    origin: f64,
    /// `y0 - origin`, frame-independent (not touched by `shift`).
    base_off: f64,
    n: u64,
    /// `X0 = sum (y0 - c_i)`, double-double.
    x0: [f64; 2],
    /// Series coefficients of `Phi(y0 + d)`, double-double: high parts ...
    a: [f64; PMAX],
    /// ... and low parts.
    al: [f64; PMAX],
    /// Slab of bins; `count == 0` slots are on `free`.
    bins: Vec<Bin>,
    free: Vec<u32>,
    /// `(j, slot)` of the live bins, sorted by `j`.
    index: Vec<(i64, u32)>,
    /// Accumulated coefficient round-off allowance since the last re-base, in units of
    /// `eps kappa l0 / (1 - q)`.
    roff: f64,
    /// `sum_b n_b (|x_b| + w/2)`, an upper bound on `sum |y0 - c_i|` (round-off allowance).
    spread: f64,
    /// Junctions present at the last re-base, i.e. counted in `A` through the bins.
    n_rb: u64,
    /// Removals since the last re-base charged with a residue, `<= n_rb` (module doc).
    resid: u64,
    /// O(1) grid index -> slot cache of `index`.
    dense: Dense,
    /// Direct mode: the junctions' offsets (no bins; `bins`, `index` stay empty).
    direct: Option<Direct>,
}

impl From<Wire> for SeriesSum {
    fn from(w: Wire) -> SeriesSum {
        let mut s = SeriesSum {
            law: w.law,
            p: w.p.min(PMAX - 1),
            base: w.base,
            origin: w.origin,
            base_off: w.base_off,
            n: w.n,
            x0: w.x0,
            a: w.a,
            al: w.al,
            bins: w.bins.unwrap_or_default(),
            free: w.free.unwrap_or_default(),
            index: w.index.unwrap_or_default(),
            roff: w.roff,
            spread: w.spread,
            n_rb: w.n_rb.unwrap_or(w.n),
            resid: w.resid,
            dense: Dense::default(),
            direct: w.direct.map(|d| Direct::from_wire(d, Grades::new(w.law.l0, w.p.min(PMAX - 1)))),
        };
        if s.direct.is_some() && !w.graded {
            // Written with every junction to order `p`: rebuilt at its base with graded
            // orders, so that a removal subtracts what the series holds.
            s.rebase_direct(s.base);
        }
        if let Some(&(j, slot)) = s.index.last() {
            let index = std::mem::take(&mut s.index);
            s.dense.set(j, slot, &index);
            s.index = index;
        }
        s
    }
}

impl From<SeriesSum> for Wire {
    fn from(s: SeriesSum) -> Wire {
        let bins_mode = s.direct.is_none();
        Wire {
            law: s.law,
            p: s.p,
            base: s.base,
            origin: s.origin,
            base_off: s.base_off,
            n: s.n,
            x0: s.x0,
            a: s.a,
            al: s.al,
            bins: bins_mode.then_some(s.bins),
            free: bins_mode.then_some(s.free),
            index: bins_mode.then_some(s.index),
            roff: s.roff,
            spread: s.spread,
            n_rb: Some(s.n_rb),
            resid: s.resid,
            direct: s.direct.map(|d| DirectWire { e: d.e, handle: d.handle, free: d.free }),
            graded: !bins_mode,
        }
    }
}

/// Truncation bounds of a truncated expansion with convergence ratio `q` at order `p`:
/// `(q^(p+1)/(1-q), (p+1) q^p/(1-q) + q^(p+1)/(1-q)^2)`, in units of `kappa l0` (`S`) and
/// `kappa` (`dS/dy`).
pub(super) fn tails_at(q: f64, p: usize) -> (f64, f64) {
    let qp = q.powi(p as i32);
    let p1 = p as f64 + 1.0;
    (qp * q / (1.0 - q), p1 * qp / (1.0 - q) + qp * q / ((1.0 - q) * (1.0 - q)))
}

/// [`tails_at`] of `Q_D`, `Q` and `Q_DIRECT` at every order `p < PMAX`, computed once per
/// process: the error bound is asked for after most events, and `powi` was half its cost.
fn tails_table() -> &'static [[(f64, f64); 3]; PMAX] {
    static TABLE: std::sync::OnceLock<[[(f64, f64); 3]; PMAX]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|p| [tails_at(Q_D, p), tails_at(Q, p), tails_at(Q_DIRECT, p)]))
}

/// Smallest order `p` whose residue bound (bin plus direct truncation) meets `rtol/4`,
/// `q^(p+1)/(1-q) + (1/8)^(p+1)/(7/8) <= rtol/4`, capped at `PMAX - 1`.
fn order_for(rtol: f64) -> usize {
    for p in 1..PMAX - 1 {
        if tails_at(Q, p).0 + tails_at(Q_DIRECT, p).0 <= 0.25 * rtol {
            return p;
        }
    }
    PMAX - 1
}

/// Smallest order `p` whose direct truncation bound meets `rtol/4`,
/// `T_d = (1/4)^(p+1)/(3/4) <= rtol/4` (direct mode, `rho = l0/4`), capped at `PMAX - 1`.
fn order_for_direct(rtol: f64) -> usize {
    for p in 1..PMAX - 1 {
        if tails_at(Q_D, p).0 <= 0.25 * rtol {
            return p;
        }
    }
    PMAX - 1
}

/// `tb_k += sum_(m <= p-k) G[m][k] M_m`, `G[m][k] = (-1)^m C(m+k, k) phi_(m+k)`: one bin's
/// double expansion about the base (`phi = phi_taylor` at the bin's `x_b`). O(p^2).
#[inline]
fn bin_terms(phi: &[f64], mom: &[f64], tb: &mut [f64]) {
    let p = phi.len() - 1;
    // Pascal's triangle by rows `m`: binom[k] = C(m+k, k).
    let mut binom = [1.0; PMAX];
    for (m, &mm) in mom.iter().enumerate().take(p + 1) {
        if m > 0 {
            // C(m+k, k) = C(m-1+k, k) + C(m+k-1, k-1).
            for k in 1..=p - m {
                binom[k] += binom[k - 1];
            }
        }
        let sm = if m % 2 == 0 { mm } else { -mm };
        for ((tk, b), ph) in tb[..=p - m].iter_mut().zip(&binom).zip(&phi[m..]) {
            *tk += b * ph * sm;
        }
    }
}

impl SeriesSum {
    /// Empty set of anchors, base point 0, bins of width `w = l0/4`, radius `rho = l0/8`
    /// (`q = 1/4`) and the smallest order `p` with `q^(p+1)/(1-q) + (1/8)^(p+1)/(7/8) <=
    /// rtol/4`: the truncation part of `error_bound()` is then at most
    /// `(rtol/4) kappa l0 (len() + removals since the last re-base, capped at the count then)`
    /// (for `rtol >= ~5e-19`; smaller, non-positive or NaN `rtol` give the cap `p = 31`). The
    /// round-off part is separate (module doc); it stays small for `N` and operations since
    /// the last re-base well below `rtol / eps`. `law.l0 > 0` is assumed (validated by the
    /// scene).
    pub fn new(law: Tilted, rtol: f64) -> SeriesSum {
        let p = order_for(rtol);
        SeriesSum {
            law,
            p,
            base: 0.0,
            origin: 0.0,
            base_off: 0.0,
            n: 0,
            x0: [0.0; 2],
            a: [0.0; PMAX],
            al: [0.0; PMAX],
            bins: Vec::new(),
            free: Vec::new(),
            index: Vec::new(),
            roff: 0.0,
            spread: 0.0,
            n_rb: 0,
            resid: 0,
            dense: Dense::default(),
            direct: None,
        }
    }

    /// Empty set of anchors in direct mode: no bins, the junctions' offsets kept in a dense
    /// array and `rebase` an O(`len()`) rebuild of the series from them; radius
    /// `rho = l0/4` (`q_d = 1/4`) and the smallest order `p` with `(1/4)^(p+1)/(3/4) <= rtol/4`
    /// (`p = 17` at `rtol = 1e-10`): the truncation part of `error_bound()` is at most
    /// `(rtol/4) kappa l0 len()` (no residue: a removal subtracts exactly what its `add`
    /// added). Cheaper than bins mode when the anchors fall into about as many bins as
    /// there are junctions (module doc, "Direct mode").
    pub fn direct(law: Tilted, rtol: f64) -> SeriesSum {
        let p = order_for_direct(rtol);
        SeriesSum { p, direct: Some(Direct::new(Grades::new(law.l0, p))), ..SeriesSum::new(law, rtol) }
    }

    /// The series for a run of `n` junctions: direct mode below [`DIRECT_MAX`]
    /// ([`SeriesSum::direct`]), bins mode from it on ([`SeriesSum::new`]).
    pub fn for_junctions(law: Tilted, rtol: f64, n: usize) -> SeriesSum {
        if n < DIRECT_MAX { SeriesSum::direct(law, rtol) } else { SeriesSum::new(law, rtol) }
    }

    /// Whether the series is in direct mode (no bins).
    pub fn is_direct(&self) -> bool {
        self.direct.is_some()
    }

    /// Removals charged as residue since the last re-base (junctions counted through the
    /// bins then and removed since). While `residue() <= len()` the truncation part of
    /// [`SeriesSum::error_bound`] is at most `(rtol/2) kappa l0 len()`, since
    /// `T_b + T_d <= rtol/4`.
    pub fn residue(&self) -> u64 {
        self.resid
    }

    /// The truncation order `p`.
    pub fn order(&self) -> usize {
        self.p
    }

    /// Number of live bins.
    pub fn bin_count(&self) -> usize {
        self.index.len()
    }

    pub fn len(&self) -> usize {
        self.n as usize
    }

    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Base point `y0` of the series.
    pub fn base(&self) -> f64 {
        self.base
    }

    /// The series is valid (error within `error_bound()`) for `|y - base| <= radius()`;
    /// `radius = l0/8` (bins mode) or `l0/4` (direct mode). Outside it, nothing is
    /// guaranteed.
    #[inline]
    pub fn radius(&self) -> f64 {
        if self.direct.is_some() { Q_D * self.law.l0 } else { 0.125 * self.law.l0 }
    }

    /// Bin width `w = l0/4`.
    #[inline]
    fn width(&self) -> f64 {
        0.25 * self.law.l0
    }

    /// `x_b = y0 - c_b` of grid index `j`.
    #[inline]
    fn x_of(&self, j: i64) -> f64 {
        self.base_off - (j as f64 + 0.5) * self.width()
    }

    /// Slot of the bin with grid index `j`, created if absent.
    #[inline]
    fn slot_of(&mut self, j: i64) -> usize {
        match self.dense.get(j) {
            Some(s) if s != NONE => s as usize,
            _ => self.slot_of_slow(j),
        }
    }

    /// `slot_of` by the binary search of `index` (a new bin, or `j` outside `dense`).
    #[cold]
    fn slot_of_slow(&mut self, j: i64) -> usize {
        match self.index.binary_search_by_key(&j, |&(jj, _)| jj) {
            Ok(i) => self.index[i].1 as usize,
            Err(i) => self.open_bin(i, j),
        }
    }

    /// A new bin with grid index `j` at position `i` of the index.
    #[cold]
    fn open_bin(&mut self, i: usize, j: i64) -> usize {
        let bin = Bin { j, count: 0, m: [0.0; PMAX], ml: [0.0; PMAX] };
        let slot = match self.free.pop() {
            Some(s) => {
                self.bins[s as usize] = bin;
                s as usize
            }
            None => {
                self.bins.push(bin);
                self.bins.len() - 1
            }
        };
        self.index.insert(i, (j, slot as u32));
        self.dense.set(j, slot as u32, &self.index);
        slot
    }

    /// [`SeriesSum::apply_in`] in 256-bit vectors where the processor has AVX2 (the same
    /// operations, so the same values bit for bit; [`direct_sums`]).
    #[inline]
    fn apply(&mut self, slot: usize, e: f64, sign: f64) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, checked just above.
            return unsafe { self.apply_avx2(slot, e, sign) };
        }
        self.apply_in(slot, e, sign)
    }

    /// [`SeriesSum::apply_in`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn apply_avx2(&mut self, slot: usize, e: f64, sign: f64) {
        self.apply_in(slot, e, sign)
    }

    /// Adds `sign * (junction with offset e in slot)`: `+- e^m` to the bin's moments and
    /// `+- phi_k(x_b - e)` (its own Taylor coefficients about the base) to the series. O(p).
    #[inline(always)]
    fn apply_in(&mut self, slot: usize, e: f64, sign: f64) {
        let p = self.p;
        let x = self.x_of(self.bins[slot].j) - e;
        let mut c = [0.0; PMAX];
        phi_taylor(&self.law, x, &mut c[..=p]);
        // Powers `sign e^m` by four chains in registers (a chain through the array would
        // add a store-to-load delay to every step).
        let mut pw = [0.0; PMAX + 4];
        let e2 = e * e;
        let e4 = e2 * e2;
        let mut quad = [sign, sign * e, sign * e2, sign * (e * e2)];
        for chunk in pw.chunks_exact_mut(4).take(p / 4 + 1) {
            chunk.copy_from_slice(&quad);
            quad = quad.map(|v| v * e4);
        }
        let bin = &mut self.bins[slot];
        dd_add_all(&mut bin.m[..=p], &mut bin.ml[..=p], &pw[..=p]);
        dd_add_all_signed(&mut self.a[..=p], &mut self.al[..=p], &c[..=p], sign);
        self.roff += OP_ROUNDOFF;
    }

    /// Direct mode: adds `sign * D_i`, the junction's own coefficients `phi_k(x)`, `k < n`
    /// (`n - 1` its graded order), about the base (`x = y0 - c_i = base_off - e_i`), to the
    /// series and `sign * x` to `X0`. O(n).
    /// In 256-bit vectors where the processor has AVX2 (a run-time check; the same
    /// operations, so the same values bit for bit, as [`SeriesSum::apply`]).
    #[inline]
    fn apply_direct(&mut self, x: f64, n: usize, sign: f64) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, checked just above.
            return unsafe { self.apply_direct_avx2(x, n, sign) };
        }
        self.apply_direct_in(x, n, sign)
    }

    /// [`SeriesSum::apply_direct_in`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn apply_direct_avx2(&mut self, x: f64, n: usize, sign: f64) {
        self.apply_direct_in(x, n, sign)
    }

    /// [`SeriesSum::apply_direct`].
    #[inline(always)]
    fn apply_direct_in(&mut self, x: f64, n: usize, sign: f64) {
        let mut c = [0.0; PMAX];
        phi_taylor(&self.law, x, &mut c[..n]);
        dd_add_all_signed(&mut self.a[..n], &mut self.al[..n], &c[..n], sign);
        dd_add(&mut self.x0, sign * x);
        self.roff += OP_ROUNDOFF;
    }

    /// A junction with anchor `c` attached. O(p) flops (plus, in bins mode, a binary search
    /// over the bins when the grid-index table misses). Returns a handle to pass to `remove`.
    pub fn add(&mut self, c: f64) -> u32 {
        if let Some(d) = &mut self.direct {
            let e = c - self.origin;
            let h = d.insert(e);
            let x = self.base_off - e;
            let n = d.grades.order_at(x) + 1;
            self.n += 1;
            self.spread += x.abs();
            self.apply_direct(x, n, 1.0);
            return h;
        }
        let w = self.width();
        let t = c - self.origin;
        // floor(t / w) without the libm call (baseline x86-64 has no rounding instruction).
        let v = t / w;
        let j = (v as i64).saturating_sub(i64::from((v as i64 as f64) > v));
        let slot = self.slot_of(j);
        let e = t - (j as f64 + 0.5) * w;
        self.n += 1;
        self.bins[slot].count += 1;
        self.apply(slot, e, 1.0);
        dd_add(&mut self.x0, self.base - c);
        self.spread += self.x_of(j).abs() + 0.5 * w;
        slot as u32
    }

    /// The junction with anchor `c` (as given to `add`, or as moved by `shift`) and handle `h`
    /// detached. O(p) flops (O(bins) when its bin empties and is freed). Direct mode uses the
    /// offset stored at `add`, not `c`: it subtracts exactly the terms `add` added.
    pub fn remove(&mut self, c: f64, h: u32) {
        if let Some(d) = &mut self.direct {
            let e = d.take(h);
            let x = self.base_off - e;
            let n = d.grades.order_at(x) + 1;
            self.n -= 1;
            self.spread = (self.spread - x.abs()).max(0.0);
            self.apply_direct(x, n, -1.0);
            if self.n == 0 {
                self.clear();
            }
            return;
        }
        let slot = h as usize;
        let w = self.width();
        let j = self.bins[slot].j;
        assert!(self.bins[slot].count > 0, "SeriesSum::remove: handle {h} has no junction");
        let e = (c - self.origin) - (j as f64 + 0.5) * w;
        self.n -= 1;
        self.bins[slot].count -= 1;
        // It may have been counted through the bins at the last re-base (module doc).
        if self.resid < self.n_rb {
            self.resid += 1;
        }
        dd_add(&mut self.x0, c - self.base);
        self.spread = (self.spread - (self.x_of(j).abs() + 0.5 * w)).max(0.0);
        self.apply(slot, e, -1.0);
        if self.bins[slot].count == 0 {
            self.free_bin(slot, j);
        }
        if self.n == 0 {
            self.clear();
        }
    }

    /// No junction left: the series is exactly zero; forget the rounding and the residues.
    fn clear(&mut self) {
        self.x0 = [0.0; 2];
        self.a = [0.0; PMAX];
        self.al = [0.0; PMAX];
        self.spread = 0.0;
        self.roff = 0.0;
        self.n_rb = 0;
        self.resid = 0;
    }

    /// An emptied bin: its exact moments are zero, so forget the rounded ones and free the slot.
    #[cold]
    fn free_bin(&mut self, slot: usize, j: i64) {
        let bin = &mut self.bins[slot];
        bin.m = [0.0; PMAX];
        bin.ml = [0.0; PMAX];
        if let Ok(i) = self.index.binary_search_by_key(&j, |&(jj, _)| jj) {
            self.index.remove(i);
        }
        self.dense.set(j, NONE, &self.index);
        self.free.push(slot as u32);
    }

    /// New base point `y0`: the series is recomputed from the bins' moments,
    /// `A_k = sum_b sum_m G_b[m][k] M_(b,m)`, O(bins p^2), independent of `len()` (bins
    /// mode); or from the junctions' offsets, `A = sum_i D_i`, O(`len()` p) (direct mode).
    pub fn rebase(&mut self, y0: f64) {
        if self.direct.is_some() {
            self.rebase_direct(y0);
            return;
        }
        let n = self.n as f64;
        // X0 += n (y0 - base), the product exactly (Dekker split via fma-free two-product).
        let delta = y0 - self.base;
        let prod = n * delta;
        let err = two_product_err(n, delta, prod);
        dd_add(&mut self.x0, prod);
        dd_add(&mut self.x0, err);
        self.base = y0;
        self.base_off = y0 - self.origin;
        let p = self.p;
        let w = self.width();
        let mut a = [0.0; PMAX];
        let mut al = [0.0; PMAX];
        let mut spread = 0.0;
        for &(j, slot) in &self.index {
            let bin = &self.bins[slot as usize];
            let x_b = self.x_of(j);
            let mut phi = [0.0; PMAX];
            phi_taylor(&self.law, x_b, &mut phi[..=p]);
            let mut mom = [0.0; PMAX];
            for (mm, (h, l)) in mom.iter_mut().zip(bin.m.iter().zip(&bin.ml)).take(p + 1) {
                *mm = h + l;
            }
            let mut tb = [0.0; PMAX];
            bin_terms(&phi[..=p], &mom[..=p], &mut tb);
            dd_add_all(&mut a[..=p], &mut al[..=p], &tb[..=p]);
            spread += bin.count as f64 * (x_b.abs() + 0.5 * w);
        }
        self.a = a;
        self.al = al;
        self.spread = spread;
        // Each present junction's term (powers, `G_b`, products, sums), as charged by the
        // O(p^2) update this replaced, plus the bin's sum over m.
        self.roff = n * (9.0 * (p as f64 + 2.0) + p as f64 + 1.0);
        self.n_rb = self.n;
        self.resid = 0;
    }

    /// Direct mode's re-base: `A`, `X0` and the spread afresh from the offsets
    /// ([`direct_sums`]). The round-off allowance restarts at `REBUILD_ROUNDOFF` per junction.
    fn rebase_direct(&mut self, y0: f64) {
        self.base = y0;
        self.base_off = y0 - self.origin;
        let d = self.direct.as_ref().expect("direct mode");
        let sums = direct_sums(&d.e, self.base_off, &d.grades, &self.law);
        self.a = sums.a;
        self.al = sums.al;
        self.x0 = sums.x0;
        self.spread = sums.spread;
        self.roff = self.n as f64 * REBUILD_ROUNDOFF;
        self.n_rb = self.n;
        self.resid = 0;
    }

    /// The coordinate frame moved: every anchor `c -> c - dy` and the base `-> base - dy`.
    /// Handles stay valid. O(1): bins, `x_b` and the series are frame-independent.
    pub fn shift(&mut self, dy: f64) {
        self.base -= dy;
        self.origin -= dy;
    }

    /// `kappa (X0 + n d)`, the linear part at `d = y - base`.
    #[inline]
    fn linear(&self, d: f64) -> f64 {
        self.law.kappa * ((self.x0[0] + self.n as f64 * d) + self.x0[1])
    }

    /// `S(y) = kappa (X0 + n d) + sum_k A_k d^k` (Horner).
    pub fn force(&self, y: f64) -> f64 {
        let d = y - self.base;
        let mut s = 0.0;
        for k in (0..=self.p).rev() {
            s = s * d + (self.a[k] + self.al[k]);
        }
        self.linear(d) + s
    }

    /// `(S(y), dS/dy(y))`, `dS/dy = kappa n + sum_k k A_k d^(k-1)` (Horner, both at once).
    pub fn force_and_stiffness(&self, y: f64) -> (f64, f64) {
        let d = y - self.base;
        let mut s = 0.0;
        let mut ds = 0.0;
        for k in (0..=self.p).rev() {
            ds = ds * d + s;
            s = s * d + (self.a[k] + self.al[k]);
        }
        (self.linear(d) + s, self.law.kappa * self.n as f64 + ds)
    }

    /// `int_{y0}^{y1} S(y) dy` (both ends within the radius)
    /// `= (y1 - y0) [kappa (X0 + n (d0 + d1)/2) + sum_k A_k s_k / (k+1)]`,
    /// `s_k = sum_(i<=k) d1^i d0^(k-i)` (`s_k = d0 s_(k-1) + d1^k`), free of cancellation.
    /// Its error is at most `|y1 - y0| error_bound()`.
    pub fn integral(&self, y0: f64, y1: f64) -> f64 {
        let d0 = y0 - self.base;
        let d1 = y1 - self.base;
        let mut sk = 1.0;
        let mut d1k = 1.0;
        let mut acc = self.a[0] + self.al[0];
        for k in 1..=self.p {
            d1k *= d1;
            sk = d0 * sk + d1k;
            acc += (self.a[k] + self.al[k]) * sk / (k as f64 + 1.0);
        }
        (y1 - y0) * (self.linear(0.5 * (d0 + d1)) + acc)
    }

    /// Truncation bound of the whole series, in units of `kappa l0` (`S`) and `kappa`
    /// (`dS/dy`): every present junction's expansion (the bins' double expansion, which
    /// dominates its own) plus each charged residue (bin expansion minus own expansion).
    fn truncation(&self) -> (f64, f64) {
        let [t_d, t_b, t_direct] = tails_table()[self.p];
        if self.direct.is_some() {
            // Every present junction's own expansion, `q_d = 1/4`; no residue.
            let (df, ds) = t_d;
            let n = self.n as f64;
            return (n * df, n * ds);
        }
        let (bf, bs) = t_b;
        let (df, ds) = t_direct;
        let (n, r) = (self.n as f64, self.resid as f64);
        (n * bf + r * (bf + df), n * bs + r * (bs + ds))
    }

    /// Round-off allowance on the coefficients, in the norm `sum_k |dA_k| rho^k`.
    fn coeff_roundoff(&self) -> f64 {
        let n = self.n as f64;
        EPS * self.law.kappa * self.law.l0 / (1.0 - Q) * (self.roff + (2.0 * self.p as f64 + 4.0) * n)
    }

    /// Round-off allowance of the linear part and of the anchors' offsets against the grid.
    fn linear_roundoff(&self) -> f64 {
        let n = self.n as f64;
        4.0 * EPS
            * self.law.kappa
            * ((self.x0[0]).abs()
                + n * self.radius()
                + self.spread
                + n * ((self.base - self.origin).abs() + self.base.abs() + self.origin.abs()))
    }

    /// Bound on `|S(y) - S_true(y)|` for `|y - base| <= radius()`: the truncation,
    /// `kappa l0 (len T_b + resid (T_b + T_d))` with `T_b = q^(p+1)/(1-q)`,
    /// `T_d = (1/8)^(p+1)/(7/8)` (rigorous), plus the first-order round-off allowance of the
    /// module doc (which grows with the operations since the last re-base).
    pub fn error_bound(&self) -> f64 {
        self.law.kappa * self.law.l0 * self.truncation().0 + self.coeff_roundoff() + self.linear_roundoff()
    }

    /// Same for `dS/dy`: `kappa (len T'_b + resid (T'_b + T'_d))`,
    /// `T'_q = (p+1) q^p/(1-q) + q^(p+1)/(1-q)^2`, plus the round-off allowance
    /// (coefficient part times `p / rho`).
    pub fn stiffness_error_bound(&self) -> f64 {
        let n = self.n as f64;
        self.law.kappa * self.truncation().1
            + self.coeff_roundoff() * self.p as f64 / self.radius()
            + 4.0 * EPS * self.law.kappa * n
    }
}

/// The cubic Taylor polynomial of the series about a point `at`,
/// `S(z) ~ c0 + c1 e + c2 e^2 + c3 e^3`, `e = z - at` ([`SeriesSum::taylor_at`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalCubic {
    pub at: f64,
    pub c: [f64; 4],
}

impl LocalCubic {
    /// `c0 + c1 e + c2 e^2 + c3 e^3`, `e = z - at`, as `(c0 + c1 e) + e^2 (c2 + c3 e)`
    /// (Estrin's scheme: the two halves and `e^2` are independent, so the value is ready
    /// two roundings sooner than by Horner's; the rounding error has the same bound,
    /// `3 eps sum |c_j| |e|^j` to first order).
    #[inline]
    pub fn force(&self, z: f64) -> f64 {
        let e = z - self.at;
        let [c0, c1, c2, c3] = self.c;
        (c0 + c1 * e) + (e * e) * (c2 + c3 * e)
    }

    /// The cubic and its derivative `c1 + 2 c2 e + 3 c3 e^2`, both by Estrin's scheme.
    #[inline]
    pub fn force_and_stiffness(&self, z: f64) -> (f64, f64) {
        let e = z - self.at;
        let e2 = e * e;
        let [c0, c1, c2, c3] = self.c;
        ((c0 + c1 * e) + e2 * (c2 + c3 * e), (c1 + 2.0 * c2 * e) + e2 * (3.0 * c3))
    }
}

impl SeriesSum {
    /// `kappa l0 max(len, 1)`: the unit of the stated tolerance (`error_bound() <= rtol` of it).
    #[inline]
    pub fn scale(&self) -> f64 {
        self.law.kappa * self.law.l0 * self.n.max(1) as f64
    }

    /// The series' cubic Taylor polynomial about `y`, `[S, S', S''/2, S'''/6](y)`, and `r4`,
    /// a bound on `|S''''|/24` over `|z - y| <= d`, so that
    /// `|S(z) - cubic(z)| <= r4 |z - y|^4` there (Lagrange remainder).
    ///
    /// With `P(t) = sum_k A_k t^k` (`t = z - base`) the series and `t0 = y - base`:
    /// `c_j = sum_k C(k, j) A_k t0^(k-j)` (`j <= 3`, [`SeriesSum::derivatives_at`]; the
    /// linear part `kappa (X0 + n t0)` adds to `c0` and `kappa n` to `c1`), and `r4 =
    /// sum_(k>=4) C(k, 4) |A_k| rho^(k-4)`, `rho = |t0| + d` (every `|z - base| <= rho` has
    /// `|P''''(z)|/24 <= r4`; the linear part has no fourth derivative), widened by `1 + 4
    /// (p+1) eps` for its own rounding (positive terms). This bounds the cubic against the
    /// series; the series' own `error_bound` (against the true force, within `radius()` of
    /// the base) applies unchanged. The rounding of the `c_j` is that of the Horner
    /// evaluation the round-off allowance charges.
    pub fn taylor_at(&self, y: f64, d: f64) -> ([f64; 4], f64) {
        let rho = (y - self.base).abs() + d;
        let mut r4 = 0.0;
        for k in (4..=self.p).rev() {
            r4 = r4 * rho + BINOM_SHIFT[k - 4][4] * (self.a[k] + self.al[k]).abs();
        }
        let r4 = r4 * (1.0 + 4.0 * (self.p as f64 + 1.0) * EPS);
        (self.derivatives_at::<4>(y), r4)
    }
}

impl SeriesSum {
    /// The series' normalised derivatives at `y`, `S^(j)(y) / j!` for `j < M`: the
    /// polynomial re-centred at `t0 = y - base` ([`recentred`]), `out[j] =
    /// sum_k C(k, j) A_k t0^(k-j)` (as [`SeriesSum::taylor_at`], to any order; 0 above `p`),
    /// O(p M) flops in whole-array steps. The linear part adds `kappa (X0 + n t0)` and
    /// `kappa n` to the first two. Within `radius()` of the base the values of the
    /// polynomial these describe carry the series' `error_bound`.
    pub fn derivatives_at<const M: usize>(&self, y: f64) -> [f64; M] {
        let t0 = y - self.base;
        let mut out = recentred::<M>(&self.a, &self.al, self.p, t0);
        if M >= 1 {
            out[0] += self.linear(t0);
        }
        if M >= 2 {
            out[1] += self.law.kappa * self.n as f64;
        }
        out
    }
}

/// The rounding error of `prod = a * b` (Dekker's TwoProduct without fma).
#[inline]
fn two_product_err(a: f64, b: f64, prod: f64) -> f64 {
    fn split(x: f64) -> (f64, f64) {
        let c = 134_217_729.0 * x; // 2^27 + 1
        let hi = c - (c - x);
        (hi, x - hi)
    }
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    ((ah * bh - prod) + ah * bl + al * bh) + al * bl
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::ForceLaw;
    use twofloat::TwoFloat as D;

    /// Low coefficients against the closed forms `f^x`, `d f^x/dx` and a central difference
    /// of `d f^x/dx` for `f''/2`.
    #[test]
    fn taylor_low_orders_match_closed_forms() {
        let law = Tilted { kappa: 0.3, l0: 0.7 };
        for &x in &[-40.0, -2.0, -0.3, 0.0, 1e-9, 0.5, 3.0, 1e4, 1e200, -1e-200] {
            let mut c = [0.0; 4];
            tilted_taylor(&law, x, &mut c);
            assert!((c[0] - law.force_x(x)).abs() <= 1e-15 * (1.0 + law.force_x(x).abs()), "x = {x}");
            assert!((c[1] - law.stiffness_x(x)).abs() <= 1e-15, "x = {x}: {} vs {}", c[1], law.stiffness_x(x));
            if x.abs() < 1e10 {
                let h = 1e-5;
                let fd = (law.stiffness_x(x + h) - law.stiffness_x(x - h)) / (2.0 * h) / 2.0;
                assert!((c[2] - fd).abs() <= 1e-8, "x = {x}: {} vs {fd}", c[2]);
            }
        }
    }

    /// `phi_k(x)`, `k <= 31`, in double-double by the power recurrence for `h = u^(-1/2)`,
    /// `u(d) = (x + d)^2 + l0^2`: `k u0 h_k = -(2k-1) x h_(k-1) - (k-1) h_(k-2)`, then
    /// `phi_k = -kappa l0 (x h_k + h_(k-1))`. Independent of the Legendre form.
    fn phi_oracle(law: &Tilted, x: f64) -> Vec<D> {
        let (x0, l0) = (D::from(x), D::from(law.l0));
        let u0 = x0 * x0 + l0 * l0;
        let mut h = vec![D::from(1.0) / u0.sqrt()];
        for k in 1..PMAX {
            let mut v = D::from(-(2.0 * k as f64 - 1.0)) * x0 * h[k - 1];
            if k >= 2 {
                v -= D::from(k as f64 - 1.0) * h[k - 2];
            }
            h.push(v / (D::from(k as f64) * u0));
        }
        let a = D::from(-law.kappa) * l0;
        (0..PMAX).map(|k| a * (x0 * h[k] + if k >= 1 { h[k - 1] } else { D::from(0.0) })).collect()
    }

    /// Stability of the Legendre recurrence in `phi_taylor`: over `|x|/l0` from 0 to 1e6
    /// (both signs, several `l0`), every `k <= 31` is within `4 (k+1) eps kappa l0 R^-k` of the
    /// double-double value (the absolute error of `P_(k-1) - t P_k`, `|P_k| <= 1`, near
    /// `|t| = 1` where the difference cancels), and the error in the norm
    /// `sum_k |d phi_k| rho^k` of one junction's increment is below `OP_ROUNDOFF / 4` in units
    /// of `eps kappa l0 / (1 - q)`, at the radius of either mode (`rho = l0/8`, bins; `l0/4`,
    /// direct; the worst of each is printed).
    #[test]
    fn direct_coefficients_roundoff() {
        let mut worst_norm: f64 = 0.0;
        let mut worst_norm_d: f64 = 0.0;
        let mut worst_k: f64 = 0.0;
        for &(kappa, l0) in &[(1.0, 1.0), (0.3, 0.07), (2.0, 9.0)] {
            let law = Tilted { kappa, l0 };
            let rho = 0.125 * l0;
            let rho_d = Q_D * l0;
            let mut ratios = vec![0.0];
            for i in 0..=240 {
                let r = 10f64.powf(-6.0 + 12.0 * i as f64 / 240.0) * (1.0 + 0.013 * i as f64);
                ratios.push(r);
                ratios.push(-r);
            }
            for &ratio in &ratios {
                let x = ratio * l0;
                let mut c = [0.0; PMAX];
                phi_taylor(&law, x, &mut c);
                let want = phi_oracle(&law, x);
                let r = x.hypot(l0);
                let (mut norm, mut norm_d) = (0.0, 0.0);
                for k in 0..PMAX {
                    let err = (D::from(c[k]) - want[k]).hi().abs();
                    let scale = kappa * l0 * r.powi(-(k as i32));
                    let rel = err / (EPS * scale);
                    assert!(rel <= 4.0 * (k as f64 + 1.0), "x/l0 = {ratio}, k = {k}: {rel} eps");
                    worst_k = worst_k.max(rel / (k as f64 + 1.0));
                    norm += err * rho.powi(k as i32);
                    norm_d += err * rho_d.powi(k as i32);
                }
                worst_norm = worst_norm.max(norm / (EPS * kappa * l0 / (1.0 - Q)));
                worst_norm_d = worst_norm_d.max(norm_d / (EPS * kappa * l0 / (1.0 - Q_D)));
            }
        }
        println!(
            "worst error: {worst_k:.3} (k+1) eps kappa l0 R^-k; norm {worst_norm:.3} (rho = l0/8), {worst_norm_d:.3} (rho = l0/4) eps kappa l0/(1-q)"
        );
        assert!(worst_norm <= OP_ROUNDOFF / 4.0, "norm {worst_norm}");
        assert!(worst_norm_d <= OP_ROUNDOFF / 4.0, "norm at l0/4 {worst_norm_d}");
    }

    /// The re-centring against the same sums in double-double arithmetic (`out[j] = sum_k
    /// C(k, j) A_k t0^(k-j)`, term by term): within `(2p + 4) eps sum_k C(k, j) |A_k|
    /// |t0|^(k-j)`, the Horner allowance of the round-off bound, for every order, every
    /// coefficient asked for, and offsets across the disc (coefficients of mixed signs and
    /// magnitudes from a fixed-seed generator).
    #[test]
    fn recentring_is_within_its_rounding_allowance() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let binom = |k: usize, j: usize| (0..j).fold(1.0, |c: f64, i| c * (k - i) as f64 / (i + 1) as f64);
        for _ in 0..2_000 {
            let p = rng.random_range(0..PMAX);
            let (mut a, mut al) = ([0.0; PMAX], [0.0; PMAX]);
            for k in 0..=p {
                a[k] = rng.random_range(-1.0..1.0) * 4f64.powi(k as i32);
                al[k] = a[k] * rng.random_range(-1.0..1.0) * 1e-17;
            }
            let t0 = rng.random_range(-0.25..0.25);
            let got = recentred::<11>(&a, &al, p, t0);
            for (j, &g) in got.iter().enumerate() {
                let (mut exact, mut size) = (D::from(0.0), 0.0);
                for k in j..=p {
                    let term =
                        D::from(binom(k, j)) * (D::from(a[k]) + D::from(al[k])) * D::from(t0).powi((k - j) as i32);
                    exact += term;
                    size += f64::from(term).abs();
                }
                let allowance = (2.0 * p as f64 + 4.0) * EPS * size;
                let err = (g - f64::from(exact)).abs();
                assert!(err <= allowance, "p {p}, j {j}, t0 {t0}: off by {err}, allowance {allowance}");
            }
        }
    }

    /// The re-centring in 256-bit vectors (where the processor has AVX2) is the baseline
    /// build's bit for bit, for every size the plate asks for.
    #[test]
    fn recentring_is_the_same_in_every_vector_width() {
        let mut a = [0.0; PMAX];
        let mut al = [0.0; PMAX];
        for k in 0..PMAX {
            a[k] = (1.7f64).powi(-(k as i32)) * if k % 3 == 1 { -1.3 } else { 0.9 + 0.01 * k as f64 };
            al[k] = a[k] * 1e-17 * (k as f64 - 7.5);
        }
        for p in [0, 3, 17, PMAX - 1] {
            // The series keeps its coefficients above `p` at zero (what `recentred` reads).
            let (mut a, mut al) = (a, al);
            a[p + 1..].fill(0.0);
            al[p + 1..].fill(0.0);
            for t0 in [0.0, -0.2, 0.123456789, 0.25] {
                assert_eq!(
                    recentred::<5>(&a, &al, p, t0).map(f64::to_bits),
                    recentred_in::<5>(&a, &al, p, t0).map(f64::to_bits)
                );
                assert_eq!(
                    recentred::<8>(&a, &al, p, t0).map(f64::to_bits),
                    recentred_in::<8>(&a, &al, p, t0).map(f64::to_bits)
                );
                assert_eq!(
                    recentred::<11>(&a, &al, p, t0).map(f64::to_bits),
                    recentred_in::<11>(&a, &al, p, t0).map(f64::to_bits)
                );
            }
        }
    }

    /// A direct-mode update in 256-bit vectors (where the processor has AVX2) leaves the
    /// series and `X0` exactly as the baseline build's does, at every graded order and at
    /// extensions over twelve decades, both signs, added and removed.
    #[test]
    fn direct_updates_are_the_same_in_every_vector_width() {
        let law = Tilted { kappa: 0.3, l0: 0.7 };
        let mut s = SeriesSum::direct(law, 1e-10);
        for i in 0..50 {
            s.add(0.093 * i as f64 - 2.0);
        }
        for i in 0..=48 {
            let x = 10f64.powf(-6.0 + 0.25 * i as f64) * if i % 2 == 0 { 1.0 } else { -1.0 };
            for n in [1, 5, 11, s.p + 1] {
                for sign in [1.0, -1.0] {
                    let (mut a, mut b) = (s.clone(), s.clone());
                    a.apply_direct(x, n, sign);
                    b.apply_direct_in(x, n, sign);
                    let bits = |t: &SeriesSum| {
                        let v: Vec<u64> = t.a.iter().chain(&t.al).chain(&t.x0).map(|v| v.to_bits()).collect();
                        v
                    };
                    assert_eq!(bits(&a), bits(&b), "x {x}, n {n}, sign {sign}");
                }
            }
        }
    }

    /// A bins-mode update in 256-bit vectors (where the processor has AVX2) leaves the
    /// series and the bin's moments exactly as the baseline build's does.
    #[test]
    fn bin_updates_are_the_same_in_every_vector_width() {
        let law = Tilted { kappa: 0.4, l0: 1.0 };
        let mut s = SeriesSum::new(law, 1e-10);
        for i in 0..200 {
            s.add(0.0137 * i as f64 - 1.1);
        }
        s.rebase(0.3);
        let slot = s.add(0.25) as usize;
        for (e, sign) in [(0.01, 1.0), (-0.0234, -1.0), (0.1, 1.0), (1e-9, -1.0)] {
            let (mut a, mut b) = (s.clone(), s.clone());
            a.apply(slot, e, sign);
            b.apply_in(slot, e, sign);
            let bits = |t: &SeriesSum| {
                let bin = &t.bins[slot];
                let v: Vec<u64> = t.a.iter().chain(&t.al).chain(&bin.m).chain(&bin.ml).map(|v| v.to_bits()).collect();
                v
            };
            assert_eq!(bits(&a), bits(&b), "e {e}");
        }
    }

    /// `phi_taylor_lanes` gives `phi_taylor`'s values bit for bit (the same operations), for
    /// every number of coefficients, the same in every lane or not, at points over twelve decades of `|x|/l0` and both
    /// signs, several laws.
    #[test]
    fn phi_taylor_lanes_is_phi_taylor() {
        let mut xs = vec![0.0, -0.0, 1e-300];
        for i in 0..=120 {
            let r = 10f64.powf(-6.0 + 12.0 * i as f64 / 120.0) * (1.0 + 0.017 * i as f64);
            xs.extend([r, -r]);
        }
        for &(kappa, l0) in &[(1.0, 1.0), (0.3, 0.07), (2.0, 9.0)] {
            let law = Tilted { kappa, l0 };
            for n in 1..=PMAX {
                for (i, chunk) in xs.chunks_exact(LANES).enumerate() {
                    let x = [chunk[0] * l0, chunk[1] * l0, chunk[2] * l0, chunk[3] * l0];
                    // Every lane to `n`, or the lanes to different counts up to `n`.
                    let ns = if i % 2 == 0 { [n; LANES] } else { [n, 1.max(n / 2), 1.max(n / 3), n.min(2)] };
                    let mut acc = [[0.0; LANES]; PMAX];
                    phi_taylor_lanes(&law, x, ns, &mut acc);
                    for (l, &xl) in x.iter().enumerate() {
                        let n = ns[l];
                        let mut c = [0.0; PMAX];
                        phi_taylor(&law, xl, &mut c[..n]);
                        for k in 0..PMAX {
                            // `0 + v` is `v` (but `-0` becomes `+0`, which `==` accepts).
                            assert!(acc[k][l] == c[k], "n = {n}, x = {xl}, k = {k}: {} vs {}", acc[k][l], c[k]);
                        }
                    }
                }
                // Eight lanes add the same sums as two calls of four, bit for bit.
                for (i, chunk) in xs.chunks_exact(2 * LANES).enumerate() {
                    let x: [f64; 2 * LANES] = std::array::from_fn(|l| chunk[l] * l0);
                    let ns: [usize; 2 * LANES] =
                        std::array::from_fn(|l| if i % 2 == 0 { n } else { 1.max(n / (l + 1)) });
                    let (mut two, mut eight) = ([[0.0; LANES]; PMAX], [[0.0; LANES]; PMAX]);
                    two[3][1] = 0.25;
                    eight[3][1] = 0.25;
                    let (xa, xb): ([f64; LANES], [f64; LANES]) =
                        (std::array::from_fn(|l| x[l]), std::array::from_fn(|l| x[l + LANES]));
                    let (na, nb): ([usize; LANES], [usize; LANES]) =
                        (std::array::from_fn(|l| ns[l]), std::array::from_fn(|l| ns[l + LANES]));
                    phi_taylor_lanes(&law, xa, na, &mut two);
                    phi_taylor_lanes(&law, xb, nb, &mut two);
                    phi_taylor_lanes(&law, x, ns, &mut eight);
                    let bits = |a: &[[f64; LANES]; PMAX]| a.map(|r| r.map(f64::to_bits));
                    assert_eq!(bits(&two), bits(&eight), "n = {n}, batch {i}");
                }
            }
        }
    }

    /// Direct mode: radius `l0/4`, the smallest order with `T_d = (1/4)^(p+1)/(3/4) <= rtol/4`
    /// (17 at `rtol = 1e-10`), no bins; `for_junctions` picks it below `DIRECT_MAX`.
    #[test]
    fn direct_mode_order_radius_and_choice() {
        let law = Tilted { kappa: 1.0, l0: 2.0 };
        let s = SeriesSum::direct(law, 1e-10);
        assert!(s.is_direct());
        assert_eq!((s.order(), s.radius()), (17, 0.5));
        for rtol in [1e-1, 1e-4, 1e-10, 1e-13, 1e-17] {
            let p = order_for_direct(rtol);
            assert!(tails_at(Q_D, p).0 <= 0.25 * rtol, "rtol {rtol}: p = {p}");
            assert!(p == 1 || tails_at(Q_D, p - 1).0 > 0.25 * rtol, "rtol {rtol}: p = {p} not minimal");
        }
        assert!(SeriesSum::for_junctions(law, 1e-10, 300).is_direct());
        assert!(SeriesSum::for_junctions(law, 1e-10, DIRECT_MAX - 1).is_direct());
        assert!(!SeriesSum::for_junctions(law, 1e-10, DIRECT_MAX).is_direct());
        assert!(!SeriesSum::new(law, 1e-10).is_direct());
    }

    /// Direct mode: an add/remove pair cancels exactly in the double-double accumulators
    /// (the same terms added and subtracted, `TwoSum` exact): right after each other, the
    /// coefficients `A_k = hi + lo` the evaluation uses, `X0` and the force are back bit for
    /// bit; interleaved with other pairs and a `shift`, and with a `c` at `remove` that
    /// rounds differently (the stored offset is used), the double-double values are back
    /// to the rounding of the low parts' sums (`O(eps^2)`). Nothing is charged as residue;
    /// handles are reused; `len() = 0` is exactly zero.
    #[test]
    fn direct_add_remove_cancels_exactly() {
        let law = Tilted { kappa: 0.4, l0: 1.0 };
        let mut s = SeriesSum::direct(law, 1e-10);
        let mut hs: Vec<(f64, u32)> = (0..50).map(|i| (-0.013 * i as f64, s.add(-0.013 * i as f64))).collect();
        s.rebase(0.05);
        let coef = |s: &SeriesSum| -> Vec<f64> { (0..=s.p).map(|k| s.a[k] + s.al[k]).collect() };
        let before = s.clone();
        for c in [7.3, -0.2, 0.05, 1e-9] {
            let h = s.add(c);
            s.remove(c, h);
            assert_eq!(coef(&s), coef(&before), "c = {c}");
            assert_eq!(s.x0[0] + s.x0[1], before.x0[0] + before.x0[1]);
            assert_eq!(s.force_and_stiffness(0.1), before.force_and_stiffness(0.1));
        }
        let h = s.add(7.3);
        let h2 = s.add(-0.2);
        s.shift(0.1);
        s.remove(-0.2 - 0.1 + 1e-15, h2);
        s.remove(7.3 - 0.1, h);
        for k in 0..=s.p {
            let diff = (s.a[k] - before.a[k]) + (s.al[k] - before.al[k]);
            assert!(diff.abs() <= 4.0 * EPS * EPS * before.a[k].abs().max(law.kappa), "k = {k}: {diff:e}");
        }
        let dx0 = (s.x0[0] - before.x0[0]) + (s.x0[1] - before.x0[1]);
        assert!(dx0.abs() <= 4.0 * EPS * EPS * before.x0[0].abs(), "X0: {dx0:e}");
        assert_eq!((s.resid, s.residue(), s.bin_count()), (0, 0, 0));
        assert!(s.roff > before.roff, "the pairs' rounding is still charged");
        let again = s.add(1.0);
        assert!(again == h || again == h2, "a freed handle is reused: {again}");
        hs.push((1.0, again));
        for (c, h) in hs.drain(..) {
            s.remove(c, h);
        }
        assert!(s.is_empty());
        assert_eq!((s.force_and_stiffness(0.3), s.error_bound()), ((0.0, 0.0), 0.0));
    }

    /// Direct mode's re-base (four junctions at a time, blocks folded into the double-double
    /// series, a tail of fewer than four, and one batch with a point outside `phi_taylor_lanes`'
    /// range) against the same series built junction by junction (`add`, double-double) at
    /// the same base: coefficients within the two round-off allowances, `X0` and the spread
    /// to a few ulps.
    #[test]
    fn direct_rebase_matches_the_incremental_series() {
        for &(kappa, l0, n) in &[(1.0, 1.0, 1003usize), (0.3, 0.07, 37), (2.0, 9.0, 3)] {
            let law = Tilted { kappa, l0 };
            let y0 = 0.3 * l0;
            let mut by_add = SeriesSum::direct(law, 1e-10);
            by_add.rebase(y0);
            let mut state = 5u64;
            for i in 0..n {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                let c = if i == 5 { -1e151 * l0 } else { l0 * 30.0 * (u - 0.9) };
                by_add.add(c);
            }
            let mut rebuilt = by_add.clone();
            rebuilt.rebase(y0);
            assert_eq!(rebuilt.base(), by_add.base());
            let tol = by_add.coeff_roundoff() + rebuilt.coeff_roundoff();
            let rho = rebuilt.radius();
            let far = if n > 5 { 1e151 } else { 0.0 };
            let norm: f64 = (0..=rebuilt.p)
                .map(|k| ((rebuilt.a[k] + rebuilt.al[k]) - (by_add.a[k] + by_add.al[k])).abs() * rho.powi(k as i32))
                .sum();
            assert!(norm <= tol, "n = {n}: |dA|_rho = {norm:e} > {tol:e}");
            let x0 = |s: &SeriesSum| s.x0[0] + s.x0[1];
            assert!((x0(&rebuilt) - x0(&by_add)).abs() <= 4.0 * EPS * rebuilt.spread, "X0");
            assert!((rebuilt.spread - by_add.spread).abs() <= 4.0 * EPS * (by_add.spread + far), "spread");
            assert_eq!(rebuilt.roff, n as f64 * REBUILD_ROUNDOFF);
        }
    }

    /// `p` is the smallest order whose residue bound meets `rtol/4`; non-finite or
    /// non-positive `rtol` give the cap.
    #[test]
    fn order_is_minimal() {
        assert_eq!(order_for(1e-10), 17);
        let tail = |p: usize| tails_at(Q, p).0 + tails_at(Q_DIRECT, p).0;
        for rtol in [1e-1, 1e-4, 1e-10, 1e-13, 1e-18] {
            let p = order_for(rtol);
            assert!(tail(p) <= 0.25 * rtol, "rtol {rtol}: p = {p}");
            assert!(p == 1 || tail(p - 1) > 0.25 * rtol, "rtol {rtol}: p = {p} not minimal");
        }
        for rtol in [0.0, -1.0, f64::NAN, 1e-300] {
            assert_eq!(order_for(rtol), PMAX - 1);
        }
        let s = SeriesSum::new(Tilted { kappa: 1.0, l0: 2.0 }, 1e-10);
        assert_eq!((s.order(), s.radius(), s.width()), (17, 0.25, 0.5));
    }

    /// An attach/detach pair with the same anchor leaves the series exactly as it was
    /// (double-double accumulation), and the count-0 bin is freed; without a re-base in
    /// between no residue is charged.
    #[test]
    fn attach_detach_cancels() {
        let law = Tilted { kappa: 0.4, l0: 1.0 };
        let mut s = SeriesSum::new(law, 1e-10);
        for i in 0..50 {
            s.add(-0.01 * i as f64);
        }
        s.rebase(0.05);
        let before = s.force_and_stiffness(0.1);
        let bins = s.bin_count();
        let h = s.add(7.3);
        assert_eq!(s.bin_count(), bins + 1);
        let h2 = s.add(-0.2);
        s.remove(-0.2, h2);
        s.remove(7.3, h);
        assert_eq!(s.bin_count(), bins);
        assert_eq!(s.force_and_stiffness(0.1), before);
        // Two removals charged (they could have been present at the re-base), at most n_rb.
        assert_eq!((s.n_rb, s.resid), (50, 2));
    }

    /// The residue count is capped by the junctions present at the last re-base and reset by
    /// the next one.
    #[test]
    fn residue_count_is_capped_and_reset() {
        let law = Tilted { kappa: 1.0, l0: 1.0 };
        let mut s = SeriesSum::new(law, 1e-10);
        let hs: Vec<(f64, u32)> = (0..10).map(|i| (0.01 * i as f64, s.add(0.01 * i as f64))).collect();
        assert_eq!((s.n_rb, s.resid), (0, 0));
        s.rebase(0.02);
        let extra: Vec<(f64, u32)> = (0..30).map(|i| (-0.03 * i as f64, s.add(-0.03 * i as f64))).collect();
        for &(c, h) in extra.iter().chain(&hs[..5]) {
            s.remove(c, h);
        }
        assert_eq!((s.n_rb, s.resid, s.len()), (10, 10, 5));
        s.rebase(0.0);
        assert_eq!((s.n_rb, s.resid), (5, 0));
    }

    /// The O(1) grid-index cache agrees with the sorted index, also when the anchors span
    /// more than `DENSE_MAX` bins (lookups outside its range fall back to the binary search),
    /// and `add` puts each anchor in bin `floor((c - origin) / w)`.
    #[test]
    fn dense_cache_matches_index() {
        let law = Tilted { kappa: 1.0, l0: 1.0 };
        let mut s = SeriesSum::new(law, 1e-6);
        let mut live: Vec<(f64, u32)> = Vec::new();
        let mut state = 12345u64;
        for step in 0..4000 {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            let scale = if step % 500 < 10 { 1e7 } else { 30.0 };
            if live.is_empty() || u < 0.55 {
                let c = scale * (2.0 * u - 1.0) - 0.125;
                let h = s.add(c);
                assert_eq!(s.bins[h as usize].j, ((c - s.origin) / s.width()).floor() as i64, "c = {c}");
                live.push((c, h));
            } else {
                let (c, h) = live.swap_remove(((state >> 20) as usize) % live.len());
                s.remove(c, h);
            }
            for &(j, slot) in &s.index {
                if let Some(d) = s.dense.get(j) {
                    assert_eq!(d, slot, "j = {j}");
                }
            }
            let recorded = s.dense.slots.iter().filter(|&&d| d != NONE).count();
            let in_range = s.index.iter().filter(|&&(j, _)| s.dense.get(j).is_some()).count();
            assert_eq!(recorded, in_range);
            assert!(s.dense.slots.len() <= DENSE_MAX);
        }
        assert!(s.dense.slots.len() > 100);
    }

    /// A series of `n` anchors spread over about `2 l0` (several bins), re-based at `y0`.
    fn cubic_fixture(law: Tilted, n: usize, y0: f64) -> (SeriesSum, Vec<f64>) {
        let mut s = SeriesSum::new(law, 1e-10);
        let mut state = 99u64;
        let anchors: Vec<f64> = (0..n)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                law.l0 * (2.0 * u - 1.2)
            })
            .collect();
        for &c in &anchors {
            s.add(c);
        }
        s.rebase(y0);
        (s, anchors)
    }

    /// `taylor_at`'s `c_j` against (a) the series' own derivatives by a direct sum
    /// `sum_k C(k, j) A_k t0^(k-j)` (no Horner; relative 1e-13 of the sum of absolute terms)
    /// and `force`, `force_and_stiffness` (bit for bit is not required: a few ulps), and
    /// (b) the law's closed forms summed over the junctions, `sum_i f^x_j(y - c_i)`
    /// (`tilted_taylor`), within the bins' truncation of the `j`-th coefficient,
    /// `n kappa l0^(1-j) sum_(k>p) C(k, j) q^(k-j)` (`|phi_k| <= kappa l0^(1-k)`,
    /// `|d - e| <= q l0`), plus the coefficients' round-off allowance seen through the `j`-th
    /// derivative, `C(p, j) rho^-j` times it.
    #[test]
    fn taylor_at_matches_the_series_and_the_law() {
        let binom = |k: usize, j: usize| (0..j).fold(1.0, |acc, i| acc * (k - i) as f64 / (i + 1) as f64);
        for &(kappa, l0) in &[(1.0, 1.0), (0.3, 0.07)] {
            let law = Tilted { kappa, l0 };
            let (s, anchors) = cubic_fixture(law, 300, 0.1 * l0);
            let (p, rho) = (s.order(), s.radius());
            let n = anchors.len() as f64;
            for frac in [-0.95, -0.5, 0.0, 0.3, 0.99] {
                let y = s.base() + frac * rho;
                let (c, _) = s.taylor_at(y, 0.0);
                let t0 = y - s.base();
                let (f, fs) = s.force_and_stiffness(y);
                assert!((c[0] - f).abs() <= 4.0 * EPS * f.abs().max(kappa * l0), "c0 {} vs {f}", c[0]);
                assert!((c[1] - fs).abs() <= 4.0 * EPS * fs.abs().max(kappa), "c1 {} vs {fs}", c[1]);
                for j in 0..4 {
                    let (mut direct, mut mag) = (0.0, 0.0);
                    for k in j..=p {
                        let term = binom(k, j) * (s.a[k] + s.al[k]) * t0.powi((k - j) as i32);
                        direct += term;
                        mag += term.abs();
                    }
                    if j == 0 {
                        direct += s.linear(t0);
                        mag += s.linear(t0).abs();
                    } else if j == 1 {
                        direct += kappa * n;
                        mag += kappa * n;
                    }
                    assert!((c[j] - direct).abs() <= 1e-13 * mag, "j = {j}: {} vs {direct}", c[j]);
                    let mut law_sum = 0.0;
                    let mut buf = [0.0; 5];
                    for &a in &anchors {
                        tilted_taylor(&law, y - a, &mut buf);
                        law_sum += buf[j];
                    }
                    let trunc: f64 = (p + 1..200).map(|k| binom(k, j) * Q.powi((k - j) as i32)).sum();
                    let mut tol = n * kappa * l0.powi(1 - j as i32) * trunc
                        + binom(p, j) * rho.powi(-(j as i32)) * s.coeff_roundoff();
                    if j <= 1 {
                        tol += if j == 0 { s.linear_roundoff() } else { 4.0 * EPS * kappa * n };
                    }
                    assert!((c[j] - law_sum).abs() <= tol, "j = {j}, y = {y}: {} vs {law_sum}, tol {tol}", c[j]);
                }
            }
        }
    }

    /// The remainder bound: for `|z - y| <= d` (`|y - base| + d <= radius`), the series
    /// `force(z)` and the cubic differ by at most `r4 |z - y|^4` plus the rounding of the two
    /// evaluations (`8 eps` of the sum of absolute terms, far below the remainder here: `d` is
    /// large); `|S''''|/24` of the law's closed forms summed over the junctions is below `r4`
    /// (plus the truncation of the 4th coefficient, as above); and the bound is not vacuous:
    /// the largest observed remainder is at least 1e-3 of it.
    #[test]
    fn taylor_at_remainder_bound_holds() {
        let binom = |k: usize, j: usize| (0..j).fold(1.0, |acc, i| acc * (k - i) as f64 / (i + 1) as f64);
        for &(kappa, l0) in &[(1.0, 1.0), (0.3, 0.07)] {
            let law = Tilted { kappa, l0 };
            let (s, anchors) = cubic_fixture(law, 300, -0.2 * l0);
            let rho = s.radius();
            let n = anchors.len() as f64;
            let mut worst: f64 = 0.0;
            for &(frac, dfrac) in &[(0.0, 1.0), (0.0, 0.5), (0.5, 0.5), (-0.25, 0.75), (0.9, 0.1)] {
                let y = s.base() + frac * rho;
                let d = dfrac * rho;
                let (c, r4) = s.taylor_at(y, d);
                let cubic = LocalCubic { at: y, c };
                assert!(r4 > 0.0 && r4.is_finite());
                for i in 0..=40 {
                    let z = y + d * (i as f64 / 20.0 - 1.0);
                    let e = z - y;
                    let mag = s.linear(z - s.base()).abs()
                        + (0..=s.order()).map(|k| (s.a[k] + s.al[k]).abs() * rho.powi(k as i32)).sum::<f64>();
                    let diff = (s.force(z) - cubic.force(z)).abs();
                    let bound = r4 * e.powi(4);
                    assert!(diff <= bound + 8.0 * EPS * mag, "y = {y}, z = {z}: {diff} > {bound}");
                    if bound > 1e6 * EPS * mag {
                        worst = worst.max(diff / bound);
                    }
                    let mut buf = [0.0; 5];
                    let mut d4 = 0.0;
                    for &a in &anchors {
                        tilted_taylor(&law, z - a, &mut buf);
                        d4 += buf[4];
                    }
                    let trunc: f64 = (s.order() + 1..200).map(|k| binom(k, 4) * Q.powi(k as i32 - 4)).sum();
                    let tol = n * kappa * l0.powi(-3) * trunc + binom(s.order(), 4) * rho.powi(-4) * s.coeff_roundoff();
                    assert!(d4.abs() <= r4 + tol, "z = {z}: |S''''|/24 = {} > r4 = {r4}", d4.abs());
                }
            }
            println!("largest remainder / bound: {worst:.3e}");
            assert!(worst >= 1e-3, "the bound is vacuous here: {worst}");
        }
    }

    /// The cubic's derivative is the derivative of its value (`force_and_stiffness` against
    /// a central difference of `force`, exact for a cubic up to rounding).
    #[test]
    fn local_cubic_stiffness_is_its_derivative() {
        let cubic = LocalCubic { at: 0.3, c: [1.5, -2.0, 0.7, 4.0] };
        for z in [0.3, 0.31, 0.25, -1.0] {
            let h = 1e-4;
            let fd = (cubic.force(z + h) - cubic.force(z - h)) / (2.0 * h);
            // Central difference of a cubic: exact but for c3 h^2 and rounding.
            let (f, fs) = cubic.force_and_stiffness(z);
            assert_eq!(f, cubic.force(z));
            assert!((fs - fd).abs() <= 4.0 * h * h + 1e-10, "{fs} vs {fd}");
        }
    }
}
