//! The tilted law's total bond force `S(y) = sum_i f^x(y - c_i)` (plate at `y`, junction `i`
//! anchored at `c_i`, extension `x_i = y - c_i`) as a truncated series about a base point
//! `y0`, updated in O(p) flops per attached or detached junction. Two modes, chosen once at
//! construction ([`SeriesSum::for_junctions`]): **bins mode** re-bases in O(bins p^2) from
//! the anchors' binned moments, independent of the number `N` of junctions; **direct mode**
//! (`N < DIRECT_MAX = 8000`) keeps the junctions' offsets and re-bases in O(N p) by summing
//! their own expansions, with twice the radius (section "Direct mode" below). Bins mode
//! has wide bins below `NARROW_FROM = 30000` junctions and narrow ones from there on
//! ("Choice of `w`, `rho`, `p`"). Measured costs: docs/performance.md, "Tilted law: the
//! bond-force series".
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
//!   `<= kappa l0 T_d`, `T_d = sum_(k>p) (rho/l0)^k = q_d^(p+1)/(1-q_d)`, `q_d = rho/l0 = q/2`;
//! - the bins' double expansion `B_i(d)`: anchors are grouped on a fixed grid of width `w`
//!   (bin `j` centred at `c_b = origin + (j + 1/2) w`, `e_i = c_i - c_b`, `|e_i| <= w/2`,
//!   `x_b = y0 - c_b`), `phi(y - c_i) = sum_j phi_j(x_b) (d - e_i)^j` truncated at total
//!   degree `j <= p`: `B_i(d) = sum_k d^k sum_(m<=p-k) G_b[m][k] e_i^m`,
//!   `G_b[m][k] = (-1)^m C(m+k, k) phi_(m+k)(x_b)`. Per junction `|d - e_i| <= rho + w/2 =
//!   q l0`, so its error is `<= kappa l0 T_b`, `T_b = q^(p+1)/(1-q)`, `q = w/l0`.
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
//! **Choice of `w`, `rho`, `p`.** `w/2 = rho`, so `q = w/l0` and `q_d = q/2`; `p` is the
//! smallest order with `T_b + T_d <= rtol/4` (capped at `PMAX - 1 = 31`, i.e. `rtol >=
//! ~5e-19`): the truncation part of `error_bound()` is then `<= (rtol/4) kappa l0 (n +
//! resid)`, at most `(rtol/2) kappa l0 n` while `resid <= n`, leaving the other half for
//! round-off. Two geometries, chosen once from `N` ([`SeriesSum::for_junctions`]):
//! - *wide bins*, `w = l0/4`, `rho = l0/8`, `q = 1/4`: `p = 17` at `rtol = 1e-10`;
//! - *narrow bins*, `w = l0/8`, `rho = l0/16`, `q = 1/8`: `p = 11` at `rtol = 1e-10`, so every
//!   add, remove and evaluation costs about two thirds as much, and the plate re-bases twice
//!   as often over the same travel, each re-base over twice as many bins at `(12/18)^2` of
//!   the work per bin. A re-base's cost is independent of `N` while the events per unit of
//!   travel grow with `N`, so narrow bins win from about `NARROW_FROM = 30000` junctions on
//!   (measured: docs/performance.md, "Exact engine, tilted law"). Narrower still (`q =
//!   1/16`, `p = 8`) saves a further 2 % of a run's instructions at `N = 1e6` and costs 41 %
//!   more at `1e4`.
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
//! rebuilding the series junction by junction would, and the wide bins' radius `l0/8` (set
//! by their double expansion, `q = (rho + w/2)/l0 = 1/4`) makes the plate re-base every
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
//!   (`q_d = rho/l0 = 1/4`: twice the wide bins' radius, half the re-bases) and `p` is the
//!   smallest order with `T_d = q_d^(p+1)/(1-q_d) <= rtol/4` (`p = 17` at `rtol = 1e-10`,
//!   as with wide bins; capped at 31). That order is the worst junction's (`x0 = 0`); each
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
//! **Compiled orders.** The work of every event, a bins-mode update (`apply`) and the
//! re-centring at a plate step's start (`derivatives_at`), is compiled for the orders of the
//! default `rtol = 1e-10` (`coefficients::COMPILED_ORDERS`: 11 for narrow bins, 17 for wide
//! bins and direct mode), and a direct-mode update for each junction order from 3 to 17:
//! at a constant order the loops unroll and lose their bounds checks. Other orders run the
//! same loops with the order read at run time. The operations and their order are the same
//! either way, so the values are the same bit for bit (unit tests compare the two forms).
//!
//! **Local cubic** (`taylor_at`, `LocalCubic`): `[S, S', S''/2, S'''/6]` at a point in one
//! Horner pass, with `r4 = sum_(k>=4) C(k,4) |A_k| rho^(k-4)` bounding `|S''''|/24` (so the
//! cubic's remainder by `r4 e^4`) against the series; the plate's steps evaluate it instead
//! of the series when their excursion is small (`engine::exact::stepper::series::motion`).

use serde::{Deserialize, Serialize};

mod bins;
mod bound;
mod coefficients;
mod cubic;
mod dd;
mod direct;
mod graded;
#[cfg(test)]
mod tests;
mod wire;

use crate::physics::Tilted;
use bins::{Bin, Dense, NONE, bin_terms};
use bound::{EPS, OP_ROUNDOFF, Q_D, Q_NARROW, Q_WIDE, order_for, order_for_direct, tails};
use coefficients::{BINOM_SHIFT, PMAX, at_compiled_order, order_of, recentred};
pub use coefficients::{phi_taylor, tilted_taylor};
pub use cubic::LocalCubic;
use dd::{dd_add, dd_add_all, dd_add_all_signed, two_product_err};
use direct::Direct;
use graded::{Grades, REBUILD_ROUNDOFF, direct_sums};

/// Direct mode below this many junctions ([`SeriesSum::for_junctions`]); bins mode from it on.
pub const DIRECT_MAX: usize = 8000;
/// Narrow bins (`q = 1/8`) from this many junctions on, wide ones (`q = 1/4`) below
/// ([`SeriesSum::for_junctions`]).
pub const NARROW_FROM: usize = 30_000;

/// The bond force `S(y) = sum_i f^x(y - c_i)` of a set of junctions under the tilted law,
/// kept as `kappa (X0 + n d) + sum_(k<=p) A_k d^k`, `d = y - base`, plus anchor bins for
/// O(bins) re-basing (bins mode) or the junctions' offsets for an O(n) one (direct mode),
/// chosen at construction (module doc).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "wire::Wire", into = "wire::Wire")]
pub struct SeriesSum {
    law: Tilted,
    /// Order: coefficients `A_0..=A_p`, bin moments `M_0..=M_p`.
    p: usize,
    /// The bins' ratio `q = w / l0` (bins mode: the radius is `q l0 / 2`), or `Q_D` (direct
    /// mode: the radius is `q l0`).
    q: f64,
    /// [`tails`] of `q` at order `p`.
    tails: [(f64, f64); 3],
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

impl SeriesSum {
    /// Empty set of anchors, base point 0, wide bins: width `w = l0/4`, radius `rho = l0/8`
    /// (`q = 1/4`), and the smallest order `p` with `q^(p+1)/(1-q) + (q/2)^(p+1)/(1-q/2) <=
    /// rtol/4`: the truncation part of `error_bound()` is then at most
    /// `(rtol/4) kappa l0 (len() + removals since the last re-base, capped at the count then)`
    /// (for `rtol >= ~5e-19`; smaller, non-positive or NaN `rtol` give the cap `p = 31`). The
    /// round-off part is separate (module doc); it stays small for `N` and operations since
    /// the last re-base well below `rtol / eps`. `law.l0 > 0` is assumed (validated by the
    /// scene).
    pub fn new(law: Tilted, rtol: f64) -> SeriesSum {
        SeriesSum::bins(law, rtol, Q_WIDE)
    }

    /// [`SeriesSum::new`] with narrow bins: `w = l0/8`, `rho = l0/16` (`q = 1/8`), so a lower
    /// order for the same bound (`p = 11` at `rtol = 1e-10`, against 17) and twice the
    /// re-bases (module doc, "Choice of `w`, `rho`, `p`").
    pub fn narrow(law: Tilted, rtol: f64) -> SeriesSum {
        SeriesSum::bins(law, rtol, Q_NARROW)
    }

    /// Bins mode with the bins' ratio `q` ([`Q_WIDE`] or [`Q_NARROW`]).
    fn bins(law: Tilted, rtol: f64, q: f64) -> SeriesSum {
        let p = order_for(q, rtol);
        SeriesSum {
            law,
            p,
            q,
            tails: tails(q, p),
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
        SeriesSum {
            p,
            q: Q_D,
            tails: tails(Q_D, p),
            direct: Some(Direct::new(Grades::new(law.l0, p))),
            ..SeriesSum::new(law, rtol)
        }
    }

    /// The series for a run of `n` junctions: direct mode below [`DIRECT_MAX`]
    /// ([`SeriesSum::direct`]), wide bins from it on ([`SeriesSum::new`]), narrow bins from
    /// [`NARROW_FROM`] on ([`SeriesSum::narrow`]).
    pub fn for_junctions(law: Tilted, rtol: f64, n: usize) -> SeriesSum {
        if n < DIRECT_MAX {
            SeriesSum::direct(law, rtol)
        } else if n < NARROW_FROM {
            SeriesSum::new(law, rtol)
        } else {
            SeriesSum::narrow(law, rtol)
        }
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
    /// `radius = q l0 / 2` (bins mode: `l0/8` wide, `l0/16` narrow) or `l0/4` (direct mode).
    /// Outside it, nothing is guaranteed.
    #[inline]
    pub fn radius(&self) -> f64 {
        if self.direct.is_some() { self.q * self.law.l0 } else { 0.5 * self.q * self.law.l0 }
    }

    /// Bin width `w = q l0` (`l0/4` wide, `l0/8` narrow).
    #[inline]
    fn width(&self) -> f64 {
        self.q * self.law.l0
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
        self.apply_compiled(slot, e, sign)
    }

    /// [`SeriesSum::apply_in`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn apply_avx2(&mut self, slot: usize, e: f64, sign: f64) {
        self.apply_compiled(slot, e, sign)
    }

    /// [`SeriesSum::apply_in`] at the compiled order equal to the series', if there is one
    /// ([`COMPILED_ORDERS`]).
    #[inline(always)]
    fn apply_compiled(&mut self, slot: usize, e: f64, sign: f64) {
        at_compiled_order!(self.p, ORDER => self.apply_in::<ORDER>(slot, e, sign))
    }

    /// Adds `sign * (junction with offset e in slot)`: `+- e^m` to the bin's moments and
    /// `+- phi_k(x_b - e)` (its own Taylor coefficients about the base) to the series, at the
    /// series' order, compiled for it when `ORDER` is not 0 ([`order_of`]). O(p).
    #[inline(always)]
    fn apply_in<const ORDER: usize>(&mut self, slot: usize, e: f64, sign: f64) {
        let p = order_of::<ORDER>(self.p);
        let x = self.x_of(self.bins[slot].j) - e;
        let mut c = [0.0; PMAX];
        phi_taylor(&self.law, x, &mut c[..=p]);
        // Powers `sign e^m` by four chains in registers (a chain through the array would
        // add a store-to-load delay to every step); written out, as the loops of `dd` are.
        let mut pw = [0.0; PMAX + 4];
        let e2 = e * e;
        let e4 = e2 * e2;
        let (mut q0, mut q1, mut q2, mut q3) = (sign, sign * e, sign * e2, sign * (e * e2));
        for i in 0..(p / 4 + 1).min(pw.len() / 4) {
            pw[4 * i] = q0;
            pw[4 * i + 1] = q1;
            pw[4 * i + 2] = q2;
            pw[4 * i + 3] = q3;
            (q0, q1, q2, q3) = (q0 * e4, q1 * e4, q2 * e4, q3 * e4);
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
        self.apply_direct_compiled(x, n, sign)
    }

    /// [`SeriesSum::apply_direct_compiled`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn apply_direct_avx2(&mut self, x: f64, n: usize, sign: f64) {
        self.apply_direct_compiled(x, n, sign)
    }

    /// [`SeriesSum::apply_direct_in`] compiled for each length `n` from 4 to 18 (direct
    /// mode's graded orders at `rtol = 1e-10` run from 17, for a junction at its anchor,
    /// down as it stretches), so that its loops unroll; any other `n` at run time. The same
    /// operations either way, so the same values bit for bit.
    #[inline(always)]
    fn apply_direct_compiled(&mut self, x: f64, n: usize, sign: f64) {
        macro_rules! compiled {
            ($($len:literal)*) => {
                match n {
                    $($len => self.apply_direct_in::<$len>(x, n, sign),)*
                    _ => self.apply_direct_in::<0>(x, n, sign),
                }
            };
        }
        compiled!(4 5 6 7 8 9 10 11 12 13 14 15 16 17 18)
    }

    /// [`SeriesSum::apply_direct`], for `n` coefficients (compiled for them when `LEN` is
    /// not 0, [`order_of`]).
    #[inline(always)]
    fn apply_direct_in<const LEN: usize>(&mut self, x: f64, n: usize, sign: f64) {
        let n = order_of::<LEN>(n);
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
        let [t_d, t_b, t_direct] = self.tails;
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
        EPS * self.law.kappa * self.law.l0 / (1.0 - self.q) * (self.roff + (2.0 * self.p as f64 + 4.0) * n)
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
    /// `T_d = (q/2)^(p+1)/(1 - q/2)` (rigorous), plus the first-order round-off allowance of the
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
    /// polynomial re-centred at `t0 = y - base` (`recentred`), `out[j] =
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
