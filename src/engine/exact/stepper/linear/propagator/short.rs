//! The short-step path of the propagator: the Taylor polynomial of `u = y - y0` to degree
//! [`DEGREE`], its coefficients read off the initial state with constants of the plate.
//!
//! With `u(tau) = sum_n c_n tau^n` (`c_0 = 0`, `c_1 = v0`), the equation
//! `M u'' + eta u' + k u = f0 + b tau` gives
//!
//! ```text
//!     c_2 = (f0 - eta v0) / (2 M),     c_3 = (b - 2 eta c_2 - k v0) / (6 M),
//!     c_n = -(eta c_{n-1} / n + k c_{n-2} / (n (n-1))) / M      (n >= 4),
//! ```
//!
//! so every `c_n` is linear in the state: `c_n = F_n f0 + W_n v0 + G_n b`, with `F_n`, `W_n`,
//! `G_n` obtained once per plate from the same recurrence. An evaluation is then three
//! products per coefficient (independent of each other, so short in latency) and two sums
//! in Estrin's order, with no division and no series loop.
//!
//! The truncation test is the Taylor path's own (`docs/propagator.md`): with `A = eta tau/M`,
//! `B = k tau^2/M` and `t_n = c_n tau^n`, the next two terms are bounded by
//! `e1 = A |t_D| / (D+1) + B |t_{D-1}| / ((D+1) D)` and `e2 = A e1 / (D+2) + B |t_D| / ((D+2)(D+1))`,
//! and for `rho tau <= 1` the remainder weighted by the derivative index is below
//! `4 (D + 3) (e1 + e2)`; the polynomial is used when that is at most `2^-56 (2 |t_2| + 3 |t_3|)`
//! (a part of the Taylor path's `2^-56 sum_{n>=2} n |t_n|`, so never a looser test). Divided by
//! `tau^2`:
//!
//! ```text
//!     tau^(D-1) (Q + tau (p3 Q + p4 |c_D|)) <= 2^-56 (2 |c_2| + 3 |c_3| tau),
//!     Q = p1 |c_D| + p2 |c_{D-1}|,
//! ```
//!
//! `p1 = 4 (D+3) eta / ((D+1) M)`, `p2 = 4 (D+3) k / ((D+1) D M)`, `p3 = eta / ((D+2) M)`,
//! `p4 = 4 (D+3) k / ((D+2)(D+1) M)`. When it fails (or `rho tau > 2^-8`, where it cannot
//! hold) the caller takes the Taylor loop or the closed form, as before.

use super::terms::{Integrals, RECIP, TAIL, hilbert_fixed};

/// Degree of the short polynomial: at `N = 1e6` (`rho tau ~ 1e-5`) the test holds with a
/// margin of about `1e10`, at `N = 1e5` (`rho tau ~ 1e-4`) with about `1e4`.
pub(super) const DEGREE: usize = 7;
/// Coefficients `c_0 .. c_D`.
pub(crate) const LEN: usize = DEGREE + 1;
const _: () = assert!(DEGREE == 7, "Short::state sums seven coefficients (estrin6)");
/// Largest `rho tau` tried: beyond it `(rho tau)^(D-1)` alone exceeds `2^-56` by far.
pub(super) const RHO_TAU_MAX: f64 = 1.0 / 256.0;

/// The plate's constants of the short path (`M > 0`; for `M = 0` it is never taken).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Short {
    /// `c_n = f[n] f0 + w[n] v0 + g[n] b` for `n = 2 ..= D` (entries 0 and 1 unused).
    f: [f64; LEN],
    w: [f64; LEN],
    g: [f64; LEN],
    /// `[p1, p2, p3, p4]` of the truncation test.
    p: [f64; 4],
    /// Longest step tried, `2^-8 / rho` (`-1`: never, for `M = 0`).
    h_max: f64,
}

impl Short {
    /// The constants of `M y'' + eta y' + k y` with largest root modulus `rho`.
    pub(super) fn new(mass: f64, eta: f64, k: f64, rho: f64) -> Short {
        if mass <= 0.0 {
            return Short::never();
        }
        let (em, km) = (eta / mass, k / mass);
        let (mut f, mut w, mut g) = ([0.0; LEN], [0.0; LEN], [0.0; LEN]);
        f[2] = 0.5 / mass;
        w[2] = -0.5 * em;
        f[3] = -2.0 * eta * f[2] / (6.0 * mass);
        w[3] = (-2.0 * eta * w[2] - k) / (6.0 * mass);
        g[3] = 1.0 / (6.0 * mass);
        for n in 4..LEN {
            let (a, b) = (em * RECIP[n], km * RECIP[n] * RECIP[n - 1]);
            f[n] = -(a * f[n - 1] + b * f[n - 2]);
            w[n] = -(a * w[n - 1] + b * w[n - 2]);
            g[n] = -(a * g[n - 1] + b * g[n - 2]);
        }
        let d = DEGREE as f64;
        let weight = 4.0 * (d + 3.0);
        let p = [
            weight * em / (d + 1.0),
            weight * km / ((d + 1.0) * d),
            em / (d + 2.0),
            weight * km / ((d + 2.0) * (d + 1.0)),
        ];
        Short { f, w, g, p, h_max: if rho > 0.0 { RHO_TAU_MAX / rho } else { f64::INFINITY } }
    }

    /// Constants that never take the short path.
    pub(super) fn never() -> Short {
        Short { f: [0.0; LEN], w: [0.0; LEN], g: [0.0; LEN], p: [0.0; 4], h_max: -1.0 }
    }

    /// The coefficients `c_0 .. c_D` of the trajectory from velocity `v0` under forcing
    /// `f0 + b tau` at `tau`, if the polynomial is exact to round-off there (`tau >= 0`);
    /// `None` otherwise, and for a non-finite state or `tau`.
    #[inline(always)]
    pub(super) fn coefficients(&self, tau: f64, v0: f64, f0: f64, b: f64) -> Option<[f64; LEN]> {
        // NaN is not within.
        let within = tau <= self.h_max;
        if !within {
            return None;
        }
        let mut c = [0.0; LEN];
        c[1] = v0;
        c[2] = self.f[2] * f0 + self.w[2] * v0;
        let mut n = 3;
        while n < LEN {
            c[n] = (self.f[n] * f0 + self.w[n] * v0) + self.g[n] * b;
            n += 1;
        }
        let [p1, p2, p3, p4] = self.p;
        let (cd, cd1) = (c[DEGREE].abs(), c[DEGREE - 1].abs());
        let q = p1 * cd + p2 * cd1;
        let tail = pow(tau, DEGREE - 1) * (q + tau * (p3 * q + p4 * cd));
        let scale = (2.0 * TAIL) * c[2].abs() + ((3.0 * TAIL) * c[3].abs()) * tau;
        // NaN anywhere fails the test.
        (tail <= scale).then_some(c)
    }

    /// `(u, u')` at `tau` from the coefficients, each sum in Estrin's order (pairs, then
    /// pairs of pairs: a few multiply-adds deep, where Horner's order is seven).
    #[inline(always)]
    pub(super) fn state(c: &[f64; LEN], tau: f64) -> (f64, f64) {
        let d = [c[1], 2.0 * c[2], 3.0 * c[3], 4.0 * c[4], 5.0 * c[5], 6.0 * c[6], 7.0 * c[7]];
        let u = tau * estrin6(&[c[1], c[2], c[3], c[4], c[5], c[6], c[7]], tau);
        (u, estrin6(&d, tau))
    }

    /// The integrals over `[0, h]` of the polynomial ([`Integrals`]): `i1 = h sum t_n/(n+1)`
    /// and `i2 = h sum_{i,j>=1} a_i a_j/(i+j+1)`, `t_n = c_n h^n`, `a_1 = t_1 - s h`,
    /// `a_n = t_n` (the Taylor path's forms); [`integrals_in_lanes`] with one lane.
    #[inline(always)]
    pub(super) fn integrals(c: &[f64; LEN], h: f64, s: f64) -> Integrals {
        let mut lane = [[0.0]; LEN];
        for n in 1..LEN {
            lane[n] = [c[n]];
        }
        let ([i1], [i2]) = integrals_in_lanes(&lane, &[h], s);
        Integrals { i1, i2 }
    }
}

/// [`Short::integrals`] of `L` pieces side by side: piece `l` has the coefficients `c[n][l]`
/// and the length `h[l]`. Every lane runs the same operations in the same order, so each
/// piece's integrals are the same bits as alone, and the compiler can run the lanes as one
/// vector. Returns `(i1, i2)` by lane. The square's short form ([`square_integral`]) is
/// computed in every lane; a lane whose higher terms it may not drop is recomputed in full.
#[inline(always)]
pub(crate) fn integrals_in_lanes<const L: usize>(c: &[[f64; L]; LEN], h: &[f64; L], s: f64) -> ([f64; L], [f64; L]) {
    let mut t = [[0.0; L]; LEN];
    let (mut hn, mut i1) = (*h, [0.0; L]);
    let mut n = 1;
    while n < LEN {
        for l in 0..L {
            t[n][l] = c[n][l] * hn[l];
            i1[l] += t[n][l] * RECIP[n + 1];
            hn[l] *= h[l];
        }
        n += 1;
    }
    let (mut i2, mut full) = ([0.0; L], false);
    for l in 0..L {
        t[1][l] -= s * h[l];
        i1[l] *= h[l];
        let (a, dropped) = square_low(&[t[1][l], t[2][l], t[3][l], t[4][l], t[5][l], t[6][l], t[7][l]]);
        i2[l] = (a * h[l]).max(0.0);
        full |= !dropped;
    }
    if full {
        for l in 0..L {
            let mut tl = [0.0; LEN];
            for n in 1..LEN {
                tl[n] = t[n][l];
            }
            i2[l] = square_integral(&tl, h[l]);
        }
    }
    (i1, i2)
}

/// Largest `T6 / S` for which [`square_integral`] drops the terms above degree 5.
pub(super) const HIGH_NEGLIGIBLE: f64 = 1.0 / 18_014_398_509_481_984.0; // 2^-54

/// `h sum_{i,j>=1} t_i t_j / (i + j + 1)` for `t[1..=D]` ([`hilbert_fixed`], 28 pairs), from
/// the terms up to degree 5 alone (15 pairs) when `T6 = |t_6| + |t_7|` is at most
/// `2^-54 (|t_1| + ... + |t_5|)`. Every pair dropped has `max(i, j) >= 6`, so
/// `i + j + 1 >= 8`, and the pairs are covered twice over by the products `|t_i| |t_j|` with
/// `j >= 6`: they sum to at most `(2/8) T6 S h <= 2^-56 S^2 h` (`S = sum |t_n|`), below
/// the rounding of the full sum (the natural scale of `int w^2` is `S^2 h`). At the engine's
/// steps at large N (`rho h ~ 1e-5`, `|t_6| / |t_2| ~ (rho h)^4 / 360`) the test holds by far.
#[inline(always)]
pub(super) fn square_integral(t: &[f64; LEN], h: f64) -> f64 {
    match square_low(&[t[1], t[2], t[3], t[4], t[5], t[6], t[7]]) {
        (acc, true) => (acc * h).max(0.0),
        _ => hilbert_fixed::<LEN>(t, h),
    }
}

/// `(sum_{i,j=1..5} a_i a_j / (i + j + 1), whether that is the whole square to rounding)`
/// for `a = [t_1, ..., t_7]` ([`square_integral`]'s test).
#[inline(always)]
fn square_low(a: &[f64; DEGREE]) -> (f64, bool) {
    let [a1, a2, a3, a4, a5, a6, a7] = *a;
    let high = a6.abs() + a7.abs();
    let low = (a1.abs() + a2.abs()) + (a3.abs() + a4.abs()) + a5.abs();
    let r = &RECIP;
    let acc = a1 * (a1 * r[3] + 2.0 * ((a2 * r[4] + a3 * r[5]) + (a4 * r[6] + a5 * r[7])))
        + a2 * (a2 * r[5] + 2.0 * (a3 * r[6] + (a4 * r[7] + a5 * r[8])))
        + (a3 * (a3 * r[7] + 2.0 * (a4 * r[8] + a5 * r[9])) + a4 * (a4 * r[9] + 2.0 * a5 * r[10]))
        + a5 * a5 * r[11];
    (acc, high <= HIGH_NEGLIGIBLE * low)
}

/// `sum_{j=0}^{6} a_j x^j` in Estrin's order.
#[inline(always)]
fn estrin6(a: &[f64; 7], x: f64) -> f64 {
    let x2 = x * x;
    let x4 = x2 * x2;
    let lo = (a[0] + a[1] * x) + (a[2] + a[3] * x) * x2;
    let hi = (a[4] + a[5] * x) + a[6] * x2;
    lo + hi * x4
}

/// `x^n` by repeated squaring (`n` a constant at the call site: unrolled).
#[inline(always)]
fn pow(x: f64, n: usize) -> f64 {
    let (mut acc, mut base, mut e) = (1.0, x, n);
    while e > 0 {
        if e & 1 == 1 {
            acc *= base;
        }
        base *= base;
        e >>= 1;
    }
    acc
}
