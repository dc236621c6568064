//! The Taylor terms' shared pieces: the table of reciprocals, the neglected tail, and the
//! integrals of a polynomial and of its square over a piece.

use serde::{Deserialize, Serialize};

/// Maximum number of Taylor terms (at `rho tau = 1` about 22 are used).
pub(super) const NT: usize = 40;
/// Relative size of the neglected Taylor tail.
pub(super) const TAIL: f64 = 1.0 / 72_057_594_037_927_936.0; // 2^-56
/// `1/n` for `n = 0..2 NT + 2` (entry 0 unused).
pub(super) const RECIP: [f64; 2 * NT + 3] = {
    let mut t = [0.0; 2 * NT + 3];
    let mut n = 1;
    while n < 2 * NT + 3 {
        t[n] = 1.0 / n as f64;
        n += 1;
    }
    t
};

/// Integrals over `[0, h]`: `i1 = int (y - y0)`, `i2 = int (y - y0 - s tau)^2`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Integrals {
    pub i1: f64,
    pub i2: f64,
}

/// `h * sum_{i,j} a_i a_j / (i + j + 1 + 2 off)` for `a[0..n]`:
/// `int_0^h (t/h)^(2 off) (sum a_i (t/h)^i)^2 dt`.
#[inline]
pub(super) fn hilbert_square(a: &[f64], h: f64, off: usize) -> f64 {
    let n = a.len();
    let mut acc = 0.0;
    for i in 0..n {
        let mut cross = 0.0;
        for j in (i + 1)..n {
            cross += a[j] * RECIP[i + j + 1 + 2 * off];
        }
        acc += a[i] * (a[i] * RECIP[2 * i + 1 + 2 * off] + 2.0 * cross);
    }
    (acc * h).max(0.0)
}

/// `h * sum_{i,j>=1} a_i a_j / (i + j + 1)` for Taylor terms `a[0..n]` (`a[0] = 0` is not
/// read): [`hilbert_square`] from index 1, with the common lengths unrolled (the loop
/// bounds and table indices become constants).
#[inline]
pub(super) fn hilbert_tail(a: &[f64], h: f64) -> f64 {
    match a.len() {
        6 => hilbert_fixed::<6>(a.try_into().expect("length checked"), h),
        8 => hilbert_fixed::<8>(a.try_into().expect("length checked"), h),
        10 => hilbert_fixed::<10>(a.try_into().expect("length checked"), h),
        _ => hilbert_square(&a[1..], h, 1),
    }
}

/// [`hilbert_tail`] for `L` terms (`a[0]` not read), a constant length: the loops unroll,
/// and a caller with the terms in registers keeps them there.
#[inline(always)]
pub(super) fn hilbert_fixed<const L: usize>(a: &[f64; L], h: f64) -> f64 {
    let mut acc = 0.0;
    let mut i = 1;
    while i < L {
        let mut cross = 0.0;
        let mut j = i + 1;
        while j < L {
            cross += a[j] * RECIP[i + j + 1];
            j += 1;
        }
        acc += a[i] * (a[i] * RECIP[2 * i + 1] + 2.0 * cross);
        i += 1;
    }
    (acc * h).max(0.0)
}
