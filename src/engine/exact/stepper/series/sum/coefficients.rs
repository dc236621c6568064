//! Taylor coefficients of the tilted law's horizontal force and of its nonlinear part `phi`
//! (the Legendre recurrence of the module doc of [`super`]), one junction at a time or on a
//! structure of arrays, and the re-centring of a series at another point.

use crate::physics::Tilted;

/// Length of the fixed coefficient arrays: orders `p <= PMAX - 1`.
pub(super) const PMAX: usize = 32;
/// Junctions per lane of the direct re-base's batches (`LANES` at a time).
pub(super) const LANES: usize = 4;

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
/// Always inlined: where `out`'s length is a constant (`COMPILED_ORDERS`) its loops unroll and
/// the recurrence stays in registers.
#[inline(always)]
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
    // Index loops (iterator adaptors and `array::from_fn` are calls here in the `release`
    // build, which has no link-time optimisation).
    let mut top = 0;
    for &v in &n {
        top = top.max(v);
    }
    debug_assert!(n.iter().all(|v| (1..=PMAX).contains(v)));
    // Whether coefficient `k` is kept, per lane, as a comparison of floats (one vector compare).
    let mut last = [0.0; W];
    for l in 0..W {
        last[l] = n[l] as f64;
    }
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

/// Series orders compiled as constants (`ORDER = p` in [`recentred_at`] and the series'
/// updates): the narrow bins' and the wide bins' (and direct mode's) at `rtol = 1e-10`, the
/// engine's default. At a constant order the loops over `0..=p` unroll and lose their bounds
/// checks; the operations and their order are those of the run-time order (`ORDER = 0`), so
/// the values are the same bit for bit.
pub(super) const COMPILED_ORDERS: [usize; 2] = [11, 17];

/// `p` itself, or the compiled `ORDER` when it is not 0 (which must then equal `p`).
#[inline(always)]
pub(super) fn order_of<const ORDER: usize>(p: usize) -> usize {
    debug_assert!(ORDER == 0 || ORDER == p, "compiled order {ORDER}, series order {p}");
    if ORDER == 0 { p } else { ORDER }
}

/// `$body` with `$order` a `const usize`: the entry of [`COMPILED_ORDERS`] equal to the
/// series order `$p`, or 0 (the order read at run time, [`order_of`]) when none is. Each arm
/// is its own copy of `$body`, compiled for its order.
macro_rules! at_compiled_order {
    ($p:expr, $order:ident => $body:expr) => {{
        use $crate::engine::exact::stepper::series::sum::coefficients::COMPILED_ORDERS;
        const P0: usize = COMPILED_ORDERS[0];
        const P1: usize = COMPILED_ORDERS[1];
        match $p {
            P0 => {
                const $order: usize = P0;
                $body
            }
            P1 => {
                const $order: usize = P1;
                $body
            }
            _ => {
                const $order: usize = 0;
                $body
            }
        }
    }};
}
pub(super) use at_compiled_order;

/// The first `M` coefficients of `sum_(k<=p) (a_k + al_k) z^k` re-centred at `z = t0`, all
/// side by side as polynomials in `t0` ([`recentred_at`], at a constant order where
/// [`COMPILED_ORDERS`] has one), in 256-bit vectors where the processor has AVX2 (the same
/// operations, so the same values bit for bit; [`direct_sums`](super::graded::direct_sums)).
#[inline]
pub(super) fn recentred<const M: usize>(a: &[f64; PMAX], al: &[f64; PMAX], p: usize, t0: f64) -> [f64; M] {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2, checked just above.
        return unsafe { recentred_avx2::<M>(a, al, p, t0) };
    }
    recentred_compiled::<M>(a, al, p, t0)
}

/// [`recentred_compiled`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn recentred_avx2<const M: usize>(a: &[f64; PMAX], al: &[f64; PMAX], p: usize, t0: f64) -> [f64; M] {
    recentred_compiled::<M>(a, al, p, t0)
}

/// [`recentred_at`] at the compiled order equal to `p`, if there is one.
#[inline(always)]
fn recentred_compiled<const M: usize>(a: &[f64; PMAX], al: &[f64; PMAX], p: usize, t0: f64) -> [f64; M] {
    at_compiled_order!(p, ORDER => recentred_at::<M, ORDER>(a, al, p, t0))
}

/// Widest re-centring asked for ([`recentred`]'s `M`).
const RECENTRED_MAX: usize = 12;

/// `C(m + j, j)` at `[m][j]` (`m < PMAX + 3`: [`recentred_at`]'s chains read up to three
/// rows past `p`; `j < RECENTRED_MAX`; exact in `f64`).
pub(super) const BINOM_SHIFT: [[f64; RECENTRED_MAX]; PMAX + 3] = {
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

/// [`BINOM_SHIFT`] transposed, `C(m + j, j)` at `[j][m]`: the four chains of
/// [`recentred_at`] read four consecutive `m` of one `j`.
const BINOM_SHIFT_T: [[f64; PMAX + 3]; RECENTRED_MAX] = {
    let mut t = [[0.0; PMAX + 3]; RECENTRED_MAX];
    let mut j = 0;
    while j < RECENTRED_MAX {
        let mut m = 0;
        while m < PMAX + 3 {
            t[j][m] = BINOM_SHIFT[m][j];
            m += 1;
        }
        j += 1;
    }
    t
};

/// [`recentred`]: `out[j] = sum_m C(m + j, j) A_(m+j) t0^m` (`A_k = a_k + al_k`, zero above
/// `p`), all `j` side by side: polynomials in `t0` with coefficients `C(m + j, j) A_(m+j)`,
/// a multiply and an add per coefficient. Each is evaluated as four Horner chains in `t0^4`
/// (`m = 4i + r`, combined as `(c0 + t0 c1) + t0^2 (c2 + t0 c3)`), independent of one
/// another, for a quarter of one chain's latency: below 8 outputs by [`by_output`], from 8
/// on by [`by_chain`] (the same operations in another order of the loops, so the same
/// values bit for bit; each the faster for its sizes). A term of degree `m` carries a
/// relative rounding of about `(5m/4 + 6) eps` (`t0^4` itself two or three roundings, two
/// per chain step, the product and the combination), within the `(2p + 4) eps` of a Horner
/// evaluation that the round-off allowance charges (module doc) for `p >= 3`. The steps
/// that would only add the zeros above `p` to a chain still at `+0` are skipped, which
/// leaves every value as it was (for a finite `t0`). O(p M). Compiled for the order when
/// `ORDER = p`, with the order read at run time when `ORDER = 0` ([`order_of`]).
#[inline(always)]
pub(super) fn recentred_at<const M: usize, const ORDER: usize>(
    a: &[f64; PMAX],
    al: &[f64; PMAX],
    p: usize,
    t0: f64,
) -> [f64; M] {
    const { assert!(M <= RECENTRED_MAX) };
    let p = order_of::<ORDER>(p);
    let sum = sums(a, al, p);
    if M >= 8 { by_chain::<M>(&sum, p, t0) } else { by_output::<M>(&sum, p, t0) }
}

/// `A_k = a_k + al_k`, zero from `PMAX` on (the chains read up to `RECENTRED_MAX + 2` past `p`).
pub(super) type Sums = [f64; PMAX + 3 + RECENTRED_MAX];

/// The sums [`recentred_at`] re-centres, as whole arrays (vector operations): the series
/// keeps `a_k = al_k = 0` above `p`.
#[inline(always)]
pub(super) fn sums(a: &[f64; PMAX], al: &[f64; PMAX], p: usize) -> Sums {
    debug_assert!(a.iter().zip(al).skip(p + 1).all(|(h, l)| *h == 0.0 && *l == 0.0));
    let mut sum = [0.0; PMAX + 3 + RECENTRED_MAX];
    for k in 0..PMAX {
        sum[k] = a[k] + al[k];
    }
    sum
}

/// [`recentred_at`] with the four chains of one output `j` stepping together, one operation
/// on four lanes (consecutive `m`, read from consecutive entries of the sums and of
/// [`BINOM_SHIFT_T`]): `c[j][r]`.
#[inline(always)]
pub(super) fn by_output<const M: usize>(sum: &Sums, p: usize, t0: f64) -> [f64; M] {
    let t2 = t0 * t0;
    let t4 = t2 * t2;
    let mut c = [[0.0; 4]; M];
    for i in (0..=p.min(PMAX - 1) / 4).rev() {
        let m = 4 * i;
        for (j, cj) in c.iter_mut().enumerate() {
            // From here on all four terms are zero (`A_k = 0` for `k > p`), and so are the
            // chains so far (a higher `m` had the same): `+0 t4 + C +0` would leave them `+0`.
            if m + j > p {
                break;
            }
            let row: &[f64; 4] = BINOM_SHIFT_T[j][m..m + 4].try_into().expect("m + 3 < PMAX + 3");
            let coef: &[f64; 4] = sum[m + j..m + j + 4].try_into().expect("m + j + 3 < the sums' length");
            for r in 0..4 {
                cj[r] = cj[r] * t4 + row[r] * coef[r];
            }
        }
    }
    let mut out = [0.0; M];
    for j in 0..M {
        out[j] = (c[j][0] + t0 * c[j][1]) + t2 * (c[j][2] + t0 * c[j][3]);
    }
    out
}

/// [`recentred_at`] with one chain `r` stepping every output at once, whole vectors of
/// outputs: `c[r][j]`.
#[inline(always)]
pub(super) fn by_chain<const M: usize>(sum: &Sums, p: usize, t0: f64) -> [f64; M] {
    let t2 = t0 * t0;
    let t4 = t2 * t2;
    let mut c = [[0.0; M]; 4];
    for i in (0..=p.min(PMAX - 1) / 4).rev() {
        for (r, cr) in c.iter_mut().enumerate() {
            let m = 4 * i + r;
            let row = &BINOM_SHIFT[m];
            let coef: &[f64; M] = sum[m..m + M].try_into().expect("M <= RECENTRED_MAX");
            // Outputs `j > p - m` take zeros (`A_k = 0` for `k > p`) into chains that are
            // still `+0` (a higher `m` had the same), which would leave them `+0`: only the
            // others are stepped, in vectors of four outputs (fixed lengths).
            for q in 0..M.div_ceil(4) {
                if m + 4 * q > p {
                    break;
                }
                for j in 4 * q..(4 * q + 4).min(M) {
                    cr[j] = cr[j] * t4 + row[j] * coef[j];
                }
            }
        }
    }
    let mut out = [0.0; M];
    for j in 0..M {
        out[j] = (c[0][j] + t0 * c[1][j]) + t2 * (c[2][j] + t0 * c[3][j]);
    }
    out
}
