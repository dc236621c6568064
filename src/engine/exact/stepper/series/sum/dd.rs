//! Double-double arithmetic: Knuth's TwoSum, the accumulators built on it, and Dekker's
//! TwoProduct error (without fma). Exact to `O(eps^2)` (module doc of [`super`], "Round-off
//! allowance").

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

/// `(hi, lo) += x` elementwise, double-double. Index loops over `x.len()` (not iterator adaptors: in the README's `release` build,
/// without link-time optimisation, `Zip` is not inlined into the AVX2 callers).
#[inline(always)]
pub(super) fn dd_add_all(hi: &mut [f64], lo: &mut [f64], x: &[f64]) {
    let n = x.len();
    let (hi, lo) = (&mut hi[..n], &mut lo[..n]);
    for i in 0..n {
        let (s, e) = two_sum(hi[i], x[i]);
        hi[i] = s;
        lo[i] += e;
    }
}

/// `(hi, lo) += sign x` elementwise, double-double (`sign = +-1`, exact); index loops, as
/// [`dd_add_all`].
#[inline(always)]
pub(super) fn dd_add_all_signed(hi: &mut [f64], lo: &mut [f64], x: &[f64], sign: f64) {
    let n = x.len();
    let (hi, lo) = (&mut hi[..n], &mut lo[..n]);
    for i in 0..n {
        let (s, e) = two_sum(hi[i], sign * x[i]);
        hi[i] = s;
        lo[i] += e;
    }
}

/// The rounding error of `prod = a * b` (Dekker's TwoProduct without fma).
#[inline]
pub(super) fn two_product_err(a: f64, b: f64, prod: f64) -> f64 {
    fn split(x: f64) -> (f64, f64) {
        let c = 134_217_729.0 * x; // 2^27 + 1
        let hi = c - (c - x);
        (hi, x - hi)
    }
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    ((ah * bh - prod) + ah * bl + al * bh) + al * bl
}
