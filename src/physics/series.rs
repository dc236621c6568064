//! The tilted law's total bond force `S(y) = sum_i f^x(y - c_i)` (plate at `y`, junction `i`
//! anchored at `c_i`, extension `x_i = y - c_i`) as a truncated series about a base point
//! `y0`, updated in O(p) per attached or detached junction and re-based in
//! O(bins p^2), independent of the number `N` of junctions (issue 10).
//!
//! **Split.** `f^x(x) = kappa x + phi(x)`, `phi(x) = -kappa l0 x h(x)`,
//! `h(x) = (x^2 + l0^2)^(-1/2)`. The linear part is kept exactly as
//! `kappa (X0 + n d)`, `d = y - y0`, `X0 = sum (y0 - c_i)` (a double-double running sum).
//! Only `phi` (bounded, analytic, singular at `x = +-i l0`) goes into the series.
//!
//! **Taylor coefficients** (`tilted_taylor`). With `R = sqrt(x0^2 + l0^2)`, `t = -x0/R`,
//! `h(x0 + d) = R^-1 (1 - 2 t (d/R) + (d/R)^2)^(-1/2) = sum_k R^-(k+1) P_k(t) d^k`
//! (generating function of the Legendre polynomials), so `h_k = R^-(k+1) P_k(t)` by the
//! stable three-term recurrence `k P_k = (2k-1) t P_(k-1) - (k-1) P_(k-2)`, O(1) per
//! coefficient. (This is the brief's power recurrence for `u^(-1/2)`,
//! `k u0 w_k = (alpha-k+1) u1 w_(k-1) + (2 alpha-k+2) u2 w_(k-2)`, after the scaling
//! `w_k = R^-(k+1) P_k`.) Then `(x h)_k = x0 h_k + h_(k-1) = R^-k (P_(k-1)(t) - t P_k(t))`.
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
//! **Bins.** Anchors are grouped on a fixed grid of width `w` in the anchor coordinate
//! (bin `j` centred at `c_b = origin + (j + 1/2) w`); bin `b` keeps the count and the raw
//! moments `M_(b,m) = sum_(i in b) e_i^m`, `e_i = c_i - c_b`, `|e_i| <= w/2`, `m = 0..=p`.
//! With `x_b = y0 - c_b` and `y = y0 + d`, `|d| <= rho`:
//! `phi(y - c_i) = sum_j phi_j(x_b) (d - e_i)^j`, and truncating at total degree `j <= p`,
//! `A_k = sum_b sum_(m <= p-k) G_b[m][k] M_(b,m)`, `G_b[m][k] = (-1)^m C(m+k, k) phi_(m+k)(x_b)`,
//! `Phi(y) ~ sum_(k<=p) A_k d^k`. A re-base recomputes `G_b` and `A` in O(bins p^2); an add or
//! remove changes `M_b` by `+-e^m` and `A_k` by `+-sum_m G_b[m][k] e^m` (O(p^2) flops, no
//! allocation), i.e. exactly the junction's own term of the re-base formula, so the series
//! always equals the sum of the present junctions' truncated expansions (no drift from
//! mixing expansions) and a detach cancels its attach up to round-off. A bin whose count
//! reaches 0 is reset to exactly zero and its slab slot freed; the handle of a junction is
//! its bin's slot. `shift` moves `origin` and `y0` only (bins, `x_b`, `G_b`, `A`, `X0` are
//! relative quantities): O(1).
//!
//! **Truncation bound.** Per junction `|d - e_i| <= rho + w/2 = q l0`, so with the coefficient
//! bound the dropped terms `j > p` are at most `kappa l0 sum_(j>p) q^j = kappa l0 q^(p+1)/(1-q)`
//! for `S` and `kappa sum_(j>p) j q^(j-1) = kappa ((p+1) q^p/(1-q) + q^(p+1)/(1-q)^2)` for
//! `dS/dy`; `error_bound` is `n` times these plus the round-off allowance. No near field is
//! needed because `q < 1` for every bin, near or far.
//!
//! **Choice of `w`, `rho`, `p`.** `w/2 = rho = l0/8`, so `q = 1/4`; `p` is the smallest order
//! with `q^(p+1)/(1-q) <= rtol/2` (capped at `PMAX - 1 = 31`, i.e. `rtol >= ~2e-19`): the
//! truncation part of `error_bound()` is then `<= (rtol/2) kappa l0 len`, leaving the other
//! half for round-off. `rtol = 1e-10` gives `p = 17`.
//!
//! **Round-off allowance** (first order in `eps`, not a proof). Norm: `|A|_rho =
//! sum_k |A_k| rho^k`; every junction's term contributes at most `kappa l0 /(1-q)` to it.
//! `A` and the bins' moments are double-double accumulators (`TwoSum`), so adding or
//! removing a term is exact to `O(eps^2)` and an attach/detach pair with the same anchor
//! cancels exactly; what remains is the rounding of each increment (powers `e^m`, `G_b`,
//! products, sums), charged as `9 (p+2) eps kappa l0/(1-q)` per add/remove and, at a
//! re-base, `(10 p + 19) eps kappa l0/(1-q)` per present junction (which resets the
//! per-operation part). At evaluation we add `eps (2p + 4) n kappa l0/(1-q)` (Horner) and
//! `4 eps kappa (|X0| + n rho + sum_b n_b (|x_b| + w/2) + n (|y0 - origin| + |y0| + |origin|))`
//! (the linear part, and the anchors' rounding against the grid: the caller's shifted
//! anchors `fl(c - dy)` and ours, `origin + e`, differ by rounding in the absolute
//! coordinates). For `dS/dy` the coefficient allowance is multiplied by `p/rho` (a
//! perturbation with `|dA|_rho <= D` changes the derivative by at most `p D / rho`). The
//! per-operation part grows by `~ 1.5e-13 kappa l0` per operation at `p = 17`, so it
//! reaches `(rtol/2) kappa l0 n` only after `~ 3e2 n` operations without a re-base at
//! `rtol = 1e-10`; `rebase(base())` (O(bins p^2)) resets it.

use serde::{Deserialize, Serialize};

use super::force::Tilted;

/// Length of the fixed coefficient arrays: orders `p <= PMAX - 1`.
pub const PMAX: usize = 32;
/// `q = (rho + w/2) / l0`, the convergence ratio of every bin's double expansion.
const Q: f64 = 0.25;
const EPS: f64 = f64::EPSILON;

/// `(2k - 1)/k` and `(k - 1)/k`, the Legendre recurrence's factors (no division per step).
const LEGENDRE: [[f64; 2]; PMAX] = {
    let mut t = [[0.0; 2]; PMAX];
    let mut k = 1;
    while k < PMAX {
        let kf = k as f64;
        t[k] = [(2.0 * kf - 1.0) / kf, (kf - 1.0) / kf];
        k += 1;
    }
    t
};

/// Taylor coefficients of the nonlinear part `phi(x) = f^x(x) - kappa x = -kappa l0 x h(x)`
/// about `x`, `out[k] = phi_k(x)` (computed directly, without the cancellation of
/// subtracting `kappa x` from `tilted_taylor`).
pub fn phi_taylor(law: &Tilted, x: f64, out: &mut [f64]) {
    let r = x.hypot(law.l0);
    let t = -x / r;
    let inv_r = 1.0 / r;
    let a = -law.kappa * law.l0;
    let (mut p_prev, mut p) = (1.0, t); // P_(k-1), P_k
    let mut scale = 1.0; // R^-k
    for (k, o) in out.iter_mut().enumerate() {
        // (x h)_k = R^-k (P_(k-1) - t P_k); (x h)_0 = x/R = -t.
        let xh = if k == 0 {
            -t
        } else {
            if k >= 2 {
                let [a1, a2] = LEGENDRE[k];
                let next = a1 * t * p - a2 * p_prev;
                p_prev = p;
                p = next;
            }
            scale *= inv_r;
            scale * (p_prev - t * p)
        };
        *o = a * xh;
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

/// `a + b` as a double-double `(hi, lo)` (Knuth's TwoSum, exact).
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// Double-double accumulator.
#[inline]
fn dd_add(acc: &mut [f64; 2], x: f64) {
    let (s, e) = two_sum(acc[0], x);
    let (hi, lo) = two_sum(s, acc[1] + e);
    *acc = [hi, lo];
}

/// `(hi, lo) += x` elementwise, double-double.
#[inline]
fn dd_add_all(hi: &mut [f64], lo: &mut [f64], x: &[f64]) {
    for ((h, l), &v) in hi.iter_mut().zip(lo.iter_mut()).zip(x) {
        let (s, e) = two_sum(*h, v);
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

/// Serialized form of `SeriesSum`: everything but the per-bin matrices `G_b`, which are a
/// deterministic function of `(law, p, w, base_off, j)` and are recomputed on reading.
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
    bins: Vec<Bin>,
    free: Vec<u32>,
    index: Vec<(i64, u32)>,
    roff: f64,
    spread: f64,
}

/// The bond force `S(y) = sum_i f^x(y - c_i)` of a set of junctions under the tilted law,
/// kept as `kappa (X0 + n d) + sum_(k<=p) A_k d^k`, `d = y - base`, plus anchor bins for
/// O(bins) re-basing (module doc).
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
    /// Per slot, `G_b[m][k]` for `m + k <= p`, rows `m` of length `p + 1 - m`, concatenated.
    g: Vec<f64>,
    /// Accumulated coefficient round-off allowance since the last re-base, in units of
    /// `eps kappa l0 / (1 - q)`.
    roff: f64,
    /// `sum_b n_b (|x_b| + w/2)`, an upper bound on `sum |y0 - c_i|` (round-off allowance).
    spread: f64,
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
            bins: w.bins,
            free: w.free,
            index: w.index,
            g: Vec::new(),
            roff: w.roff,
            spread: w.spread,
        };
        s.g = vec![0.0; s.bins.len() * s.tri()];
        for slot in 0..s.bins.len() {
            if s.bins[slot].count > 0 {
                s.fill_g(slot);
            }
        }
        s
    }
}

impl From<SeriesSum> for Wire {
    fn from(s: SeriesSum) -> Wire {
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
            bins: s.bins,
            free: s.free,
            index: s.index,
            roff: s.roff,
            spread: s.spread,
        }
    }
}

/// Smallest order `p` with `q^(p+1) / (1 - q) <= rtol / 2`, capped at `PMAX - 1`.
fn order_for(rtol: f64) -> usize {
    let mut tail = Q / (1.0 - Q); // q^(p+1)/(1-q) at p = 0
    for p in 0..PMAX - 1 {
        if tail <= 0.5 * rtol {
            return p.max(1);
        }
        tail *= Q;
    }
    PMAX - 1
}

impl SeriesSum {
    /// Empty set of anchors, base point 0, bins of width `w = l0/4`, radius `rho = l0/8`
    /// (`q = 1/4`) and the smallest order `p` with `q^(p+1)/(1-q) <= rtol/2`: the truncation
    /// part of `error_bound()` is then at most `(rtol/2) kappa l0 len()` (for `rtol >= ~2e-19`;
    /// smaller, non-positive or NaN `rtol` give the cap `p = 31`). The round-off part is
    /// separate (module doc); it stays below the other half for `N` and operations since the
    /// last re-base well below `rtol / eps`. `law.l0 > 0` is assumed (validated by the scene).
    pub fn new(law: Tilted, rtol: f64) -> SeriesSum {
        SeriesSum {
            law,
            p: order_for(rtol),
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
            g: Vec::new(),
            roff: 0.0,
            spread: 0.0,
        }
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
    /// `radius = l0/8`. Outside it, nothing is guaranteed.
    pub fn radius(&self) -> f64 {
        0.125 * self.law.l0
    }

    /// Bin width `w = l0/4`.
    #[inline]
    fn width(&self) -> f64 {
        0.25 * self.law.l0
    }

    /// Entries of one bin's triangular matrix `G_b`.
    #[inline]
    fn tri(&self) -> usize {
        (self.p + 1) * (self.p + 2) / 2
    }

    /// `x_b = y0 - c_b` of grid index `j`.
    #[inline]
    fn x_of(&self, j: i64) -> f64 {
        self.base_off - (j as f64 + 0.5) * self.width()
    }

    /// `G_b[m][k] = (-1)^m C(m+k, k) phi_(m+k)(x_b)` for the bin in `slot`. O(p^2).
    fn fill_g(&mut self, slot: usize) {
        let p = self.p;
        let mut phi = [0.0; PMAX];
        phi_taylor(&self.law, self.x_of(self.bins[slot].j), &mut phi[..=p]);
        // Pascal's triangle by rows `m`: binom[k] = C(m+k, k).
        let mut binom = [1.0; PMAX];
        let t = self.tri();
        let g = &mut self.g[slot * t..(slot + 1) * t];
        let mut off = 0;
        for m in 0..=p {
            if m > 0 {
                // C(m+k, k) = C(m-1+k, k) + C(m+k-1, k-1).
                for k in 1..=p - m {
                    binom[k] += binom[k - 1];
                }
            }
            let sign = if m % 2 == 0 { 1.0 } else { -1.0 };
            for k in 0..=p - m {
                g[off + k] = sign * binom[k] * phi[m + k];
            }
            off += p + 1 - m;
        }
    }

    /// Slot of the bin with grid index `j`, created (with its `G_b`) if absent.
    fn slot_of(&mut self, j: i64) -> usize {
        match self.index.binary_search_by_key(&j, |&(jj, _)| jj) {
            Ok(i) => self.index[i].1 as usize,
            Err(i) => {
                let bin = Bin { j, count: 0, m: [0.0; PMAX], ml: [0.0; PMAX] };
                let slot = match self.free.pop() {
                    Some(s) => {
                        self.bins[s as usize] = bin;
                        s as usize
                    }
                    None => {
                        self.bins.push(bin);
                        self.g.resize(self.bins.len() * self.tri(), 0.0);
                        self.bins.len() - 1
                    }
                };
                self.index.insert(i, (j, slot as u32));
                self.fill_g(slot);
                slot
            }
        }
    }

    /// Adds `sign * (junction with offset e in slot)` to the moments and the series. O(p^2).
    #[inline]
    fn apply(&mut self, slot: usize, e: f64, sign: f64) {
        let p = self.p;
        // Powers `sign e^m` by two interleaved chains (half the latency of one).
        let mut pw = [0.0; PMAX];
        pw[0] = sign;
        pw[1] = sign * e;
        let e2 = e * e;
        for m in 2..=p {
            pw[m] = pw[m - 2] * e2;
        }
        let bin = &mut self.bins[slot];
        dd_add_all(&mut bin.m[..=p], &mut bin.ml[..=p], &pw[..=p]);
        let t = self.tri();
        let g = &self.g[slot * t..(slot + 1) * t];
        // dt_k = sum_m G[m][k] e^m, four rows per pass (a quarter of the stores and reloads
        // of dt; rows m..m+3 have lengths len, len-1, len-2, len-3), then single rows.
        let mut dt = [0.0; PMAX];
        let mut off = 0;
        let mut m = 0;
        while m + 3 <= p {
            let len = p + 1 - m;
            let (o1, o2, o3) = (off + len, off + 2 * len - 1, off + 3 * len - 3);
            let (r0, r1, r2, r3) = (&g[off..o1], &g[o1..o1 + len - 1], &g[o2..o2 + len - 2], &g[o3..o3 + len - 3]);
            let (e0, e1, e2, e3) = (pw[m], pw[m + 1], pw[m + 2], pw[m + 3]);
            for ((((d, a), b), c), f) in dt[..len - 3].iter_mut().zip(r0).zip(r1).zip(r2).zip(r3) {
                *d += (a * e0 + b * e1) + (c * e2 + f * e3);
            }
            dt[len - 3] += (r0[len - 3] * e0 + r1[len - 3] * e1) + r2[len - 3] * e2;
            dt[len - 2] += r0[len - 2] * e0 + r1[len - 2] * e1;
            dt[len - 1] += r0[len - 1] * e0;
            off = o3 + len - 3;
            m += 4;
        }
        while m <= p {
            let len = p + 1 - m;
            for (d, gv) in dt[..len].iter_mut().zip(&g[off..off + len]) {
                *d += gv * pw[m];
            }
            off += len;
            m += 1;
        }
        dd_add_all(&mut self.a[..=p], &mut self.al[..=p], &dt[..=p]);
        self.roff += self.op_roundoff();
    }

    /// Round-off of one junction's increment `sum_m G_b[m][k] e^m` (powers, `G_b`, products
    /// and sums), in units of `eps kappa l0 / (1 - q)`; the double-double accumulation adds
    /// only `O(eps^2)`.
    #[inline]
    fn op_roundoff(&self) -> f64 {
        9.0 * (self.p as f64 + 2.0)
    }

    /// A junction with anchor `c` attached. O(p^2) flops (plus a binary search over the
    /// bins, and O(p^2 + bins) when it opens a new bin). Returns a handle to pass to `remove`.
    pub fn add(&mut self, c: f64) -> u32 {
        let w = self.width();
        let t = c - self.origin;
        let j = (t / w).floor() as i64;
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
    /// detached. O(p^2) flops (O(bins) when its bin empties and is freed).
    pub fn remove(&mut self, c: f64, h: u32) {
        let slot = h as usize;
        let w = self.width();
        let j = self.bins[slot].j;
        assert!(self.bins[slot].count > 0, "SeriesSum::remove: handle {h} has no junction");
        let e = (c - self.origin) - (j as f64 + 0.5) * w;
        self.n -= 1;
        self.bins[slot].count -= 1;
        dd_add(&mut self.x0, c - self.base);
        self.spread = (self.spread - (self.x_of(j).abs() + 0.5 * w)).max(0.0);
        if self.bins[slot].count == 0 {
            // Its exact moments are zero: forget the rounded ones and free the slot.
            self.apply(slot, e, -1.0);
            let bin = &mut self.bins[slot];
            bin.m = [0.0; PMAX];
            bin.ml = [0.0; PMAX];
            if let Ok(i) = self.index.binary_search_by_key(&j, |&(jj, _)| jj) {
                self.index.remove(i);
            }
            self.free.push(h);
        } else {
            self.apply(slot, e, -1.0);
        }
        if self.n == 0 {
            self.x0 = [0.0; 2];
            self.a = [0.0; PMAX];
            self.al = [0.0; PMAX];
            self.spread = 0.0;
            self.roff = 0.0;
        }
    }

    /// New base point `y0`: the series is recomputed from the bins' moments,
    /// `A_k = sum_b sum_m G_b[m][k] M_(b,m)`. O(bins p^2), independent of `len()`.
    pub fn rebase(&mut self, y0: f64) {
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
        let t = self.tri();
        let w = self.width();
        let mut a = [0.0; PMAX];
        let mut al = [0.0; PMAX];
        let mut spread = 0.0;
        for i in 0..self.index.len() {
            let (j, slot) = self.index[i];
            let slot = slot as usize;
            self.fill_g(slot);
            let g = &self.g[slot * t..(slot + 1) * t];
            let bin = &self.bins[slot];
            let mut tb = [0.0; PMAX];
            let mut off = 0;
            for m in 0..=p {
                let len = p + 1 - m;
                let mm = bin.m[m] + bin.ml[m];
                for (tk, gv) in tb[..len].iter_mut().zip(&g[off..off + len]) {
                    *tk += gv * mm;
                }
                off += len;
            }
            dd_add_all(&mut a[..=p], &mut al[..=p], &tb[..=p]);
            spread += bin.count as f64 * (self.x_of(j).abs() + 0.5 * w);
        }
        self.a = a;
        self.al = al;
        self.spread = spread;
        // Each present junction's term, as in `apply`, plus the bin's sum over m.
        self.roff = n * (self.op_roundoff() + p as f64 + 1.0);
    }

    /// The coordinate frame moved: every anchor `c -> c - dy` and the base `-> base - dy`.
    /// Handles stay valid. O(1): bins, `x_b`, `G_b` and the series are frame-independent.
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

    /// Bound on the truncation error of one junction's expansion, in units of `kappa l0`
    /// (`S`) and `kappa` (`dS/dy`).
    fn tails(&self) -> (f64, f64) {
        let qp = Q.powi(self.p as i32);
        let p1 = self.p as f64 + 1.0;
        (qp * Q / (1.0 - Q), p1 * qp / (1.0 - Q) + qp * Q / ((1.0 - Q) * (1.0 - Q)))
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
    /// `len kappa l0 q^(p+1)/(1-q)` (rigorous), plus the first-order round-off allowance of
    /// the module doc (which grows with the operations since the last re-base).
    pub fn error_bound(&self) -> f64 {
        let (tf, _) = self.tails();
        self.n as f64 * self.law.kappa * self.law.l0 * tf + self.coeff_roundoff() + self.linear_roundoff()
    }

    /// Same for `dS/dy`: `len kappa ((p+1) q^p/(1-q) + q^(p+1)/(1-q)^2)` plus the round-off
    /// allowance (coefficient part times `p / rho`).
    pub fn stiffness_error_bound(&self) -> f64 {
        let (_, ts) = self.tails();
        let n = self.n as f64;
        n * self.law.kappa * ts + self.coeff_roundoff() * self.p as f64 / self.radius() + 4.0 * EPS * self.law.kappa * n
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

    /// Low coefficients against the closed forms `f^x`, `d f^x/dx` and a central difference
    /// of `d f^x/dx` for `f''/2`.
    #[test]
    fn taylor_low_orders_match_closed_forms() {
        let law = Tilted { kappa: 0.3, l0: 0.7 };
        for &x in &[-40.0, -2.0, -0.3, 0.0, 1e-9, 0.5, 3.0, 1e4] {
            let mut c = [0.0; 4];
            tilted_taylor(&law, x, &mut c);
            assert!((c[0] - law.force_x(x)).abs() <= 1e-15 * (1.0 + law.force_x(x).abs()), "x = {x}");
            assert!((c[1] - law.stiffness_x(x)).abs() <= 1e-15, "x = {x}: {} vs {}", c[1], law.stiffness_x(x));
            let h = 1e-5;
            let fd = (law.stiffness_x(x + h) - law.stiffness_x(x - h)) / (2.0 * h) / 2.0;
            assert!((c[2] - fd).abs() <= 1e-8, "x = {x}: {} vs {fd}", c[2]);
        }
    }

    /// `p` is the smallest order whose truncation tail meets `rtol/2`; non-finite or
    /// non-positive `rtol` give the cap.
    #[test]
    fn order_is_minimal() {
        assert_eq!(order_for(1e-10), 17);
        for rtol in [1e-1, 1e-4, 1e-10, 1e-13, 1e-18] {
            let p = order_for(rtol);
            let tail = |p: usize| Q.powi(p as i32 + 1) / (1.0 - Q);
            assert!(tail(p) <= 0.5 * rtol, "rtol {rtol}: p = {p}");
            assert!(p == 1 || tail(p - 1) > 0.5 * rtol, "rtol {rtol}: p = {p} not minimal");
        }
        for rtol in [0.0, -1.0, f64::NAN, 1e-300] {
            assert_eq!(order_for(rtol), PMAX - 1);
        }
        let s = SeriesSum::new(Tilted { kappa: 1.0, l0: 2.0 }, 1e-10);
        assert_eq!((s.order(), s.radius(), s.width()), (17, 0.25, 0.5));
    }

    /// An attach/detach pair with the same anchor leaves the series exactly as it was
    /// (double-double accumulation), and the count-0 bin is freed.
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
    }
}
