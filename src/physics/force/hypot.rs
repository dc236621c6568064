//! `hypot(x, y)` of the tilted law in a form the compiler vectorises, bit for bit the C
//! library's (GNU libc 2.35 and later, the version without fused multiply-add, whose
//! `hypot` Rust's `f64::hypot` calls on Linux).
//!
//! For `ax = max(|x|, |y|)`, `ay = min(|x|, |y|)` in the common range (`ax <= 2^511`,
//! `ay >= 2^-511`): `ax + ay` when `ay <= 2^-54 ax`; otherwise `h = sqrt(ax^2 + ay^2)`
//! corrected by one Newton step on `h^2 - ax^2 - ay^2` whose residual is computed exactly
//! (Borges, "An improved algorithm for hypot(a, b)", 2019):
//!
//! - `h <= 2 ay`: `d = h - ay`, `t1 = ax (2d - ax)`, `t2 = (d - 2 (ax - ay)) d`;
//! - otherwise: `d = h - ax`, `t1 = 2d (ax - 2ay)`, `t2 = (4d - ay) ay + d^2`;
//!
//! and `hypot = h - (t1 + t2) / (2h)`. Every operation is a correctly rounded `+ - * / sqrt`
//! in the library's order, so the result is the library's bits. Outside the common range
//! (non-finite, huge or tiny arguments) [`common`] says so and the caller asks the library.
//! [`matches_library`] checks once per process that the library computes this (another C
//! library, another algorithm): if it does not, the callers use the library throughout.

use std::sync::OnceLock;

/// `2^511`: above it `ax^2` could overflow.
const LARGE: f64 = f64::from_bits(0x5FE0_0000_0000_0000);
/// `2^-511`: below it `ay^2` could underflow.
const TINY: f64 = f64::from_bits(0x2000_0000_0000_0000);
/// `2^-54`: for `ay <= EPS ax`, `hypot = ax + ay` (rounded).
const EPS: f64 = f64::from_bits(0x3C90_0000_0000_0000);

/// `(hypot(x, y), true)` when `x, y` are in the common range, `(_, false)` otherwise (the
/// first value then means nothing). Branch-free, for vectorised loops.
#[inline(always)]
pub fn common(x: f64, y: f64) -> (f64, bool) {
    let (x, y) = (x.abs(), y.abs());
    let ax = if x < y { y } else { x };
    let ay = if x < y { x } else { y };
    let in_range = x.is_finite() && y.is_finite() && ax <= LARGE && ay >= TINY;
    let h = (ax * ax + ay * ay).sqrt();
    let low = h <= 2.0 * ay;
    let delta = if low { h - ay } else { h - ax };
    let t1 = if low { ax * (2.0 * delta - ax) } else { 2.0 * delta * (ax - 2.0 * ay) };
    let t2 = if low { (delta - 2.0 * (ax - ay)) * delta } else { (4.0 * delta - ay) * ay + delta * delta };
    let corrected = h - (t1 + t2) / (2.0 * h);
    (if ay <= ax * EPS { ax + ay } else { corrected }, in_range)
}

/// [`common`] of four `x` with one `y`: the four values, and whether all four are in the
/// common range. With AVX2 (the x86-64-v3 build) in vector instructions, the same operations
/// lane by lane.
#[inline(always)]
pub fn common4(x: [f64; 4], y: f64) -> ([f64; 4], bool) {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    {
        avx2::common4(x, y)
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    {
        let mut h = [0.0; 4];
        let mut all = true;
        for i in 0..4 {
            let (hi, ok) = common(x[i], y);
            h[i] = hi;
            all &= ok;
        }
        (h, all)
    }
}

#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
mod avx2 {
    use std::arch::x86_64::*;

    use super::{EPS, LARGE, TINY};

    /// [`super::common`] lane by lane: both corrections computed and blended.
    #[inline(always)]
    pub fn common4(x: [f64; 4], y: f64) -> ([f64; 4], bool) {
        // SAFETY: compiled only when the whole build enables AVX2 (the `cfg` above), so the
        // instructions exist; the loads and stores touch the two local arrays only.
        unsafe {
            let x = _mm256_andnot_pd(_mm256_set1_pd(-0.0), _mm256_loadu_pd(x.as_ptr()));
            let y = _mm256_set1_pd(y.abs());
            let two = _mm256_set1_pd(2.0);
            let x_below = _mm256_cmp_pd::<_CMP_LT_OQ>(x, y);
            let ax = _mm256_blendv_pd(x, y, x_below);
            let ay = _mm256_blendv_pd(y, x, x_below);
            // Ordered comparisons: false for NaN.
            let finite = _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_LE_OQ>(x, _mm256_set1_pd(f64::MAX)),
                _mm256_cmp_pd::<_CMP_LE_OQ>(y, _mm256_set1_pd(f64::MAX)),
            );
            let in_range = _mm256_and_pd(
                finite,
                _mm256_and_pd(
                    _mm256_cmp_pd::<_CMP_LE_OQ>(ax, _mm256_set1_pd(LARGE)),
                    _mm256_cmp_pd::<_CMP_GE_OQ>(ay, _mm256_set1_pd(TINY)),
                ),
            );
            let h = _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(ax, ax), _mm256_mul_pd(ay, ay)));
            let low = _mm256_cmp_pd::<_CMP_LE_OQ>(h, _mm256_mul_pd(two, ay));
            let delta = _mm256_blendv_pd(_mm256_sub_pd(h, ax), _mm256_sub_pd(h, ay), low);
            let two_delta = _mm256_mul_pd(two, delta);
            // low: t1 = ax (2d - ax), t2 = (d - 2 (ax - ay)) d.
            let t1_low = _mm256_mul_pd(ax, _mm256_sub_pd(two_delta, ax));
            let t2_low = _mm256_mul_pd(_mm256_sub_pd(delta, _mm256_mul_pd(two, _mm256_sub_pd(ax, ay))), delta);
            // high: t1 = 2d (ax - 2ay), t2 = (4d - ay) ay + d^2.
            let t1_high = _mm256_mul_pd(two_delta, _mm256_sub_pd(ax, _mm256_mul_pd(two, ay)));
            let four_delta = _mm256_mul_pd(_mm256_set1_pd(4.0), delta);
            let t2_high = _mm256_add_pd(_mm256_mul_pd(_mm256_sub_pd(four_delta, ay), ay), _mm256_mul_pd(delta, delta));
            let t = _mm256_add_pd(_mm256_blendv_pd(t1_high, t1_low, low), _mm256_blendv_pd(t2_high, t2_low, low));
            let corrected = _mm256_sub_pd(h, _mm256_div_pd(t, _mm256_mul_pd(two, h)));
            let shortcut = _mm256_cmp_pd::<_CMP_LE_OQ>(ay, _mm256_mul_pd(ax, _mm256_set1_pd(EPS)));
            let result = _mm256_blendv_pd(corrected, _mm256_add_pd(ax, ay), shortcut);
            let mut out = [0.0; 4];
            _mm256_storeu_pd(out.as_mut_ptr(), result);
            (out, _mm256_movemask_pd(in_range) == 0b1111)
        }
    }
}

/// [`common`] where it applies, the library's `hypot` elsewhere.
pub fn hypot(x: f64, y: f64) -> f64 {
    match common(x, y) {
        (h, true) => h,
        _ => x.hypot(y),
    }
}

/// Whether [`common`] gives the library's bits on this machine: checked once per process
/// on a fixed set of arguments in the common range (both branches of the correction, the
/// `ax + ay` shortcut, exact and inexact square roots, the range's edges).
pub fn matches_library() -> bool {
    static MATCHES: OnceLock<bool> = OnceLock::new();
    *MATCHES.get_or_init(|| {
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let edges = [LARGE, TINY, 1.0, 3.0, 4.0, 0.5, 1e-17, 1e17, 2.0f64.powi(-27), 1.0 + f64::EPSILON];
        let mut pairs: Vec<(f64, f64)> = edges.iter().flat_map(|&a| edges.iter().map(move |&b| (a, b))).collect();
        for _ in 0..4000 {
            // Random mantissas, exponents over a range where both branches and the shortcut occur.
            let (a, b) = (next(), next());
            let x = f64::from_bits((a >> 12) | (0x3FF0_0000_0000_0000 - (30 << 52) + ((a % 61) << 52)));
            let y = f64::from_bits((b >> 12) | (0x3FF0_0000_0000_0000 - (30 << 52) + ((b % 61) << 52)));
            pairs.push((if a & 1 == 0 { x } else { -x }, y));
        }
        let scalar = pairs.iter().all(|&(x, y)| match common(x, y) {
            (h, true) => h.to_bits() == x.hypot(y).to_bits(),
            _ => true,
        });
        let four = pairs.chunks_exact(4).all(|p| {
            let (h, all) = common4([p[0].0, p[1].0, p[2].0, p[3].0], p[0].1);
            !all || p.iter().zip(h).all(|(&(x, _), h)| h.to_bits() == x.hypot(p[0].1).to_bits())
        });
        scalar && four
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The port agrees with the C library on this machine, over many arguments of every
    /// kind, and falls back to it outside the common range.
    #[test]
    fn agrees_with_the_library() {
        assert!(matches_library(), "this C library's hypot is not GNU libc 2.35+'s: the port is unused");
        let mut s = 12345u64;
        for i in 0..200_000u64 {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let x = f64::from_bits(s >> 1) * if i % 3 == 0 { -1.0 } else { 1.0 };
            let y = [1.0, 0.1, 2.5, 1e-3][(i % 4) as usize];
            let want = x.hypot(y);
            let got = hypot(x, y);
            assert!(got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()), "hypot({x:e}, {y})");
            // Scales the tilted law meets: |x| around l0.
            let x = (f64::from((s >> 40) as u32) / f64::from(1u32 << 24) - 0.5) * 8.0;
            assert_eq!(hypot(x, y).to_bits(), x.hypot(y).to_bits(), "hypot({x:e}, {y})");
        }
        for x in
            [0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, f64::MAX, f64::MIN_POSITIVE, 5e-324, LARGE, TINY]
        {
            let (got, want) = (hypot(x, 1.0), x.hypot(1.0));
            assert!(got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()), "hypot({x:e}, 1)");
        }
    }
}
