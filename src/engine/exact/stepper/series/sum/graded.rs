//! Direct mode's graded orders and its re-base.
//!
//! **Graded orders.** Direct mode's order `p` is set by the worst junction, one at `x0 = 0`
//! (`R = l0`), whose expansion converges with ratio `rho/l0 = 1/4`. A junction at
//! `R = sqrt(x0^2 + l0^2)` converges faster: by the coefficient bound of the module doc of
//! [`super`], `|phi_k(x0)| rho^k <= kappa l0 (l0/R) r^k` with `r = rho/R`, so its
//! expansion truncated at order `m` leaves at most
//!
//! - `kappa l0 (l0/R) r^(m+1)/(1-r)` in `S`, and
//! - `kappa (l0/R)^2 ((m+1) r^m/(1-r) + r^(m+1)/(1-r)^2)` in `dS/dy`
//!
//! on the disc `|d| <= rho` (at `R = l0` these are `T_d` and `T'_d` of order `m`). Each
//! junction keeps its expansion only to the smallest order `m <= p` at which both are within
//! the worst junction's `T_d(p)` and `T'_d(p)`, so the truncation bound `kappa l0 n T_d(p)`
//! (and `kappa n T'_d(p)`) of [`super::SeriesSum::error_bound`] holds unchanged, term by
//! term. At `rtol = 1e-10` (`p = 17`) a junction at `|x0| = 2 l0` is kept to order 10, at
//! `4 l0` to 8 and at `20 l0` to 4 (test `quoted_orders`); on the letter's Fig. 1 scene
//! the attached junctions are mostly a few `l0` from their anchors (docs/performance.md,
//! "Exact engine, tilted law", has what this saves).
//!
//! A junction's order is a function of its `u = x^2 + l0^2` alone ([`Grades::order`]), and
//! `x = base_off - e` is computed the same way by the re-base, `add` and `remove`, so a
//! removal subtracts exactly the coefficients that its `add` or the last re-base added: the
//! series stays `A = sum_i D_i` with no residue.
//!
//! **Re-base** ([`direct_sums`]). Eight junctions at a time (two batches of four, added in
//! order) through `phi_taylor_lanes`, each lane
//! to its own order (the four run to the highest of their orders, the terms beyond a lane's
//! own added as zeros; sorting the junctions by order first would save some of those
//! terms, but the sort cost more than it saved at a few hundred junctions). Sums per lane
//! in plain `f64` over blocks of `BLOCK` batches, folded into the double-double series
//! after each block: the round-off charge `REBUILD_ROUNDOFF` per junction holds (each
//! junction contributes fewer terms, none with more rounding).

use std::sync::OnceLock;

use super::bound::{OP_ROUNDOFF, Q_D, tails_at};
use super::coefficients::{LANES, PMAX, phi_taylor, phi_taylor_lanes};
use super::dd::{dd_add, dd_add_all, two_sum};
use crate::physics::Tilted;

/// `R/l0` beyond which no search is made (an order that needs more keeps the next one).
const FAR: f64 = 1e12;
/// Relative margin on a threshold (covers the rounding of `u = x^2 + l0^2` and `u / l0^2`).
const MARGIN: f64 = 1e-9;
/// Buckets of `u / l0^2` per octave: the top `SUB_BITS` bits of the mantissa.
const SUB_BITS: u32 = 4;
/// Buckets from `u / l0^2 = 1` to `FAR^2` (`2^80`) and one beyond for everything further.
const BUCKETS: usize = 81 << SUB_BITS;
/// The bucket index of `u / l0^2 = 1` in the bits of an `f64` shifted right by
/// `52 - SUB_BITS` (exponent bias 1023).
const FIRST: usize = 1023 << SUB_BITS;
/// Batches summed in plain `f64` (per lane and coefficient) between two folds into the
/// double-double series: each lane's block sum has at most `BLOCK` terms.
pub(super) const BLOCK: usize = 8;
/// Round-off of one present junction's term in a direct re-base, in units of
/// `eps kappa l0 / (1 - q)`: its coefficients (`OP_ROUNDOFF`, which covers `phi_taylor` at
/// `rho = l0/4`: unit test `direct_coefficients_roundoff`) plus the plain-`f64` block sums,
/// `(BLOCK - 1) u` per lane and `2 u` for adding the four lanes (`u = eps/2`; first order,
/// Higham's bound for recursive summation), the fold into the double-double series exact
/// to `O(eps^2)`.
pub(super) const REBUILD_ROUNDOFF: f64 = OP_ROUNDOFF + 0.5 * (BLOCK as f64 + 1.0);

/// Per-junction orders of direct mode at order `p`, looked up by the bucket of
/// `u / l0^2 = (x^2 + l0^2) / l0^2` (sixteen to an octave): each bucket holds the
/// smallest order that suffices at its lower edge, so it suffices for every `u` in it (the
/// tails fall as `u` grows), never above `p`. A bucket spans at most a factor 17/16 in `u`
/// (3.1 % in `R`), so an order is at most one above the least that suffices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Grades {
    table: &'static [u8; BUCKETS],
    /// `l0^2` and its inverse.
    l2: f64,
    inv_l2: f64,
    p: usize,
}

/// The bucket tables per order `p`, computed once per process and order.
static TABLES: [OnceLock<[u8; BUCKETS]>; PMAX] = [const { OnceLock::new() }; PMAX];

/// Whether order `m` meets `(T_d(p), T'_d(p))` for a junction at `R = big l0` (module doc).
fn suffices(big: f64, m: usize, budget: (f64, f64)) -> bool {
    let (s, d) = tails_at(Q_D / big, m);
    s / big <= budget.0 && d / (big * big) <= budget.1
}

/// The least `(R/l0)^2` at which each order `m < p` suffices (`+inf` where none does below
/// `R = FAR l0`), by bisection on `R/l0` in `[1, FAR]` (geometric, 80 halvings: far below
/// the margin), raised by the margin and made non-increasing in `m`.
fn unit_thresholds(p: usize) -> [f64; PMAX] {
    let budget = tails_at(Q_D, p);
    let mut th = [0.0; PMAX];
    for (m, t) in th.iter_mut().enumerate().take(p) {
        *t = if !suffices(FAR, m, budget) {
            f64::INFINITY
        } else if suffices(1.0, m, budget) {
            1.0
        } else {
            let (mut lo, mut hi) = (1.0f64, FAR);
            for _ in 0..80 {
                let mid = (lo * hi).sqrt();
                if suffices(mid, m, budget) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            hi * hi * (1.0 + MARGIN)
        };
    }
    for m in (0..p.saturating_sub(1)).rev() {
        th[m] = th[m].max(th[m + 1]);
    }
    th
}

/// The lower edge of bucket `b`, `(1 + j/16) 2^i` for `b = 16 i + j`.
fn bucket_floor(b: usize) -> f64 {
    f64::from_bits(((FIRST + b) as u64) << (52 - SUB_BITS))
}

/// The bucket table of order `p`: the smallest order whose threshold is at most the
/// bucket's lower edge.
fn table(p: usize) -> [u8; BUCKETS] {
    let th = unit_thresholds(p);
    let mut t = [0u8; BUCKETS];
    for (b, o) in t.iter_mut().enumerate() {
        let lo = bucket_floor(b);
        *o = th[..p].iter().filter(|&&v| lo < v).count() as u8;
    }
    t
}

impl Grades {
    /// The grades of order `p` for the length `l0`.
    pub(super) fn new(l0: f64, p: usize) -> Grades {
        let p = p.min(PMAX - 1);
        let l2 = l0 * l0;
        Grades { table: TABLES[p].get_or_init(|| table(p)), l2, inv_l2: 1.0 / l2, p }
    }

    /// The order of a junction with `u = x^2 + l0^2`: its bucket's (a `u / l0^2` below 1 by
    /// rounding is in the first bucket, anything beyond `2^81` in the last).
    #[inline(always)]
    pub(super) fn order(&self, u: f64) -> usize {
        let b = ((u * self.inv_l2).to_bits() >> (52 - SUB_BITS)) as usize;
        self.table[b.saturating_sub(FIRST).min(BUCKETS - 1)] as usize
    }

    /// The order of a junction at extension `x` ([`Grades::order`] of `x^2 + l0^2`).
    #[inline(always)]
    pub(super) fn order_at(&self, x: f64) -> usize {
        self.order(x * x + self.l2)
    }
}

/// Direct mode's series rebuilt from the offsets `e` at `base_off`: `A = sum_i D_i` (each
/// to its own order, double-double), `X0 = sum_i x_i` and `spread = sum_i |x_i|`,
/// `x_i = base_off - e_i`.
pub(super) struct DirectSums {
    pub a: [f64; PMAX],
    pub al: [f64; PMAX],
    pub x0: [f64; 2],
    pub spread: f64,
}

/// [`direct_sums_in`] in 256-bit vectors where the processor has AVX2 (a run-time check),
/// else in baseline x86-64's 128-bit ones: the same operations in the same order (none
/// fused), so the same sums bit for bit.
pub(super) fn direct_sums(e: &[f64], base_off: f64, g: &Grades, law: &Tilted) -> DirectSums {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2, checked just above.
        return unsafe { direct_sums_avx2(e, base_off, g, law) };
    }
    direct_sums_in(e, base_off, g, law)
}

/// [`direct_sums_in`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn direct_sums_avx2(e: &[f64], base_off: f64, g: &Grades, law: &Tilted) -> DirectSums {
    direct_sums_in(e, base_off, g, law)
}

/// Whether `phi_taylor_lanes` takes `x` (module doc of [`super`]: `max(|x|, l0)` in
/// `[1e-150, 1e150]`).
#[inline(always)]
fn in_range(x: f64, l0: f64) -> bool {
    (1e-150..=1e150).contains(&x.abs().max(l0))
}

/// The sums of [`DirectSums`] (module doc, "Re-base").
#[inline(always)]
pub(super) fn direct_sums_in(e: &[f64], base_off: f64, g: &Grades, law: &Tilted) -> DirectSums {
    let law = *law;
    let p = g.p;
    let mut a = [0.0; PMAX];
    let mut al = [0.0; PMAX];
    let mut acc = [[0.0; LANES]; PMAX];
    // Folds the block sums into the series (the four lanes pairwise, then one
    // double-double addition per coefficient) and clears them.
    let fold = |acc: &mut [[f64; LANES]; PMAX], a: &mut [f64; PMAX], al: &mut [f64; PMAX]| {
        let mut t = [0.0; PMAX];
        for k in 0..(p + 1).min(PMAX) {
            let ak = &mut acc[k];
            t[k] = (ak[0] + ak[1]) + (ak[2] + ak[3]);
            *ak = [0.0; LANES];
        }
        dd_add_all(&mut a[..=p], &mut al[..=p], &t[..=p]);
    };
    let (mut xh, mut xl) = ([0.0; LANES], [0.0; LANES]);
    let mut spread = [0.0; LANES];
    // Batch `b` of `LANES` junctions: its offsets, orders, and whether `phi_taylor_lanes`
    // takes them all.
    let batch = |e: &[f64]| -> ([f64; LANES], [usize; LANES], bool) {
        let mut x = [0.0; LANES];
        let mut n = [0; LANES];
        for l in 0..LANES {
            x[l] = base_off - e[l];
            n[l] = g.order_at(x[l]) + 1;
        }
        // Every lane tested (no early exit), so the test is a few vector operations (an
        // index loop: iterator adaptors are not inlined here in the `release` build).
        let mut ok = true;
        for &v in &x {
            ok &= in_range(v, law.l0);
        }
        (x, n, ok)
    };
    // One batch's terms, into the block sums.
    let one = |acc: &mut [[f64; LANES]; PMAX], x: [f64; LANES], n: [usize; LANES], ok: bool| {
        if ok {
            phi_taylor_lanes(&law, x, n, acc);
        } else {
            let mut c = [0.0; PMAX];
            for l in 0..LANES {
                let nl = n[l];
                phi_taylor(&law, x[l], &mut c[..nl]);
                for k in 0..nl {
                    acc[k][l] += c[k];
                }
            }
        }
    };
    let mut sums = |x: [f64; LANES]| {
        for l in 0..LANES {
            let (s, err) = two_sum(xh[l], x[l]);
            xh[l] = s;
            xl[l] += err;
            spread[l] += x[l].abs();
        }
    };
    // Two batches at a time (the terms added batch after batch, as one at a time would: the
    // same sums bit for bit), so that two junctions' chains of dependent steps share a
    // vector of each kind; `BLOCK` is even, so a pair never straddles a fold.
    const { assert!(BLOCK % 2 == 0) };
    let pairs = e.chunks_exact(2 * LANES);
    let rest = pairs.remainder();
    let mut in_block = 0;
    for e in pairs {
        let (xa, na, oka) = batch(&e[..LANES]);
        let (xb, nb, okb) = batch(&e[LANES..]);
        if oka && okb {
            let (mut x, mut n) = ([0.0; 2 * LANES], [0; 2 * LANES]);
            for l in 0..LANES {
                (x[l], x[l + LANES]) = (xa[l], xb[l]);
                (n[l], n[l + LANES]) = (na[l], nb[l]);
            }
            phi_taylor_lanes(&law, x, n, &mut acc);
        } else {
            one(&mut acc, xa, na, oka);
            one(&mut acc, xb, nb, okb);
        }
        sums(xa);
        sums(xb);
        in_block += 2;
        if in_block == BLOCK {
            fold(&mut acc, &mut a, &mut al);
            in_block = 0;
        }
    }
    // At most one batch is left over; the pairs leave `in_block` even, below `BLOCK`, so
    // it joins the last block without a fold.
    let batches = rest.chunks_exact(LANES);
    let tail = batches.remainder();
    for e in batches {
        let (x, n, ok) = batch(e);
        one(&mut acc, x, n, ok);
        sums(x);
    }
    fold(&mut acc, &mut a, &mut al);
    let mut x0 = [0.0; 2];
    for &e in tail {
        let x = base_off - e;
        let n = g.order_at(x) + 1;
        let mut c = [0.0; PMAX];
        phi_taylor(&law, x, &mut c[..n]);
        dd_add_all(&mut a[..n], &mut al[..n], &c[..n]);
        dd_add(&mut x0, x);
        spread[0] += x.abs();
    }
    for l in 0..LANES {
        dd_add(&mut x0, xh[l]);
        dd_add(&mut x0, xl[l]);
    }
    DirectSums { a, al, x0, spread: (spread[0] + spread[1]) + (spread[2] + spread[3]) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The re-base's sums in 256-bit vectors (where the processor has AVX2) are those of the
    /// baseline build bit for bit: offsets over six decades, both signs, a tail of 1-3, and
    /// values that take the scalar branch; several orders `p` (so several grades per re-base).
    #[test]
    fn direct_sums_are_the_same_in_every_vector_width() {
        let law = Tilted { kappa: 0.1, l0: 1.0 };
        for len in [0usize, 1, 7, 64, 301, 1002] {
            let e: Vec<f64> = (0..len)
                .map(|i| {
                    let r = 10f64.powf(-3.0 + 6.0 * ((i * 37) % 101) as f64 / 100.0);
                    if i % 3 == 0 { -r } else { r * (1.0 + 1e-3 * i as f64) }
                })
                .chain((len > 5).then_some(1e200))
                .collect();
            for p in [4, 17, PMAX - 1] {
                let g = Grades::new(law.l0, p);
                let (a, b) = (direct_sums(&e, 0.3, &g, &law), direct_sums_in(&e, 0.3, &g, &law));
                let bits = |s: &DirectSums| {
                    let v: Vec<u64> =
                        s.a.iter().chain(&s.al).chain(&s.x0).chain([&s.spread]).map(|v| v.to_bits()).collect();
                    v
                };
                assert_eq!(bits(&a), bits(&b), "len {len}, p {p}");
            }
        }
    }

    /// Each order's threshold is where both of its tails meet the worst junction's, to the
    /// margin: just above it the order suffices, just below it does not. The order of a
    /// junction suffices for it, never exceeds `p`, and is minimal to within its bucket
    /// (`u` within a factor 17/16, so `R` within 3.1 %).
    #[test]
    fn orders_suffice_and_are_nearly_minimal() {
        for p in [4, 9, 17, 24, PMAX - 1] {
            let budget = tails_at(Q_D, p);
            let th = unit_thresholds(p);
            for (m, &t) in th.iter().enumerate().take(p) {
                if t.is_infinite() {
                    assert!(!suffices(FAR, m, budget), "p {p}, m {m}");
                    continue;
                }
                let big = t.sqrt();
                assert!(suffices(big, m, budget), "p {p}, m {m}: not enough at the threshold");
                if t > 1.0 + 1e-6 {
                    assert!(!suffices(big * (1.0 - 1e-6), m, budget), "p {p}, m {m}: threshold too high");
                }
            }
            let g = Grades::new(1.0, p);
            let mut x = 0.0;
            while x < 1e14 {
                let o = g.order_at(x);
                assert!(o <= p);
                let big = (x * x + 1.0).sqrt();
                assert!(o == p || suffices(big * (1.0 - 1e-12), o, budget), "p {p}, x {x}: order {o} short");
                let floor = big / (17.0f64 / 16.0).sqrt() * (1.0 - 1e-6);
                assert!(o == 0 || !suffices(floor, o - 1, budget), "p {p}, x {x}: order {o} not minimal");
                x = if x == 0.0 { 1e-3 } else { x * 1.013 };
            }
            assert_eq!(g.order_at(0.0), p, "the worst junction keeps every order");
            assert_eq!(g.order_at(1e200), g.order(f64::INFINITY));
        }
    }

    /// The orders the module doc quotes (`rtol = 1e-10`, `p = 17`).
    #[test]
    fn quoted_orders() {
        let g = Grades::new(1.0, 17);
        let at = |x: f64| g.order_at(x);
        assert_eq!([at(0.0), at(2.0), at(4.0), at(20.0)], [17, 10, 8, 4]);
    }

    /// The thresholds scale with `l0^2`: the orders depend on `x / l0` only.
    #[test]
    fn orders_depend_on_x_over_l0() {
        let (g1, g7) = (Grades::new(1.0, 17), Grades::new(0.07, 17));
        for x in [0.0, 0.5, 1.3, 2.0, 4.5, 9.0, 30.0, 1e4] {
            assert_eq!(g1.order_at(x), g7.order_at(0.07 * x), "x/l0 = {x}");
        }
    }

    /// A junction truncated at its order is within the worst junction's truncation bound
    /// everywhere on the disc, measured against its expansion to order `PMAX - 1` (whose own
    /// tail is far smaller): `|D_m - D_full| <= kappa l0 T_d(p)`, and for the derivative
    /// `kappa T'_d(p)`; and the bound is not loose by more than a modest factor for the
    /// junctions nearest to a threshold.
    #[test]
    fn truncated_junctions_stay_within_the_budget() {
        let law = Tilted { kappa: 0.3, l0: 1.0 };
        let p = 17;
        let g = Grades::new(law.l0, p);
        let (bs, bd) = tails_at(Q_D, p);
        let rho = Q_D * law.l0;
        let mut worst: f64 = 0.0;
        for i in 0..400 {
            let x = 0.05 * i as f64 * if i % 2 == 0 { 1.0 } else { -1.0 };
            let m = g.order_at(x);
            let mut full = [0.0; PMAX];
            phi_taylor(&law, x, &mut full);
            for d in [-rho, -0.5 * rho, 0.5 * rho, rho] {
                let (mut s, mut ds) = (0.0, 0.0);
                for (k, &c) in full.iter().enumerate().skip(m + 1) {
                    s += c * d.powi(k as i32);
                    ds += k as f64 * c * d.powi(k as i32 - 1);
                }
                assert!(s.abs() <= law.kappa * law.l0 * bs, "x {x}, m {m}: {s:e}");
                assert!(ds.abs() <= law.kappa * bd, "x {x}, m {m}: {ds:e}");
                worst = worst.max(s.abs() / (law.kappa * law.l0 * bs));
            }
        }
        assert!(worst > 1e-3, "the budget is used: worst share {worst:e}");
    }
}
