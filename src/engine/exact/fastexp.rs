//! The exponential of the exact engines' hot paths, inlined: `exp(z)` for `|z| <= 708`,
//! within one unit in the last place of the exact value (the platform's `exp` is within about
//! half a unit, but it is a call through the C library, about 50 instructions with its
//! wrapper, on every re-attachment's relaxation factor `exp(-lambda (t - t_d))` and on every
//! weak-bond weight, bound and acceptance).
//!
//! The method is the usual table reduction: with `k = round(z 64 / ln 2)` and
//! `r = z - k ln2/64` (`ln2/64` split in a high part with trailing zeros, so `k ln2_hi` is
//! exact, and a low part), `|r| <= ln2/128`, and
//!
//! ```text
//!     exp(z) = 2^(k div 64) * 2^((k mod 64)/64) * exp(r),
//!     exp(r) = 1 + p(r),   p(r) = r + r^2/2 + r^3/6 + r^4/24 + r^5/120 + r^6/720,
//! ```
//!
//! the 64 values `2^(j/64)` correctly rounded in a table (computed once with 60 decimal
//! digits), the power of two added to the exponent field, and the result formed as
//! `s + s p(r)`. The truncation of `p` is below `(ln2/128)^7/5040 < 2^-64`; the table's
//! rounding, the reduction and the last two operations give the error of at most one unit
//! in the last place that the unit test checks against the platform's `exp`. Outside
//! `|z| <= 708` (where results leave the normal range) and for NaN it returns `f64::exp`.

/// `2^(j/64)`, `j = 0..64`, correctly rounded (bit patterns).
const TABLE: [u64; 64] = [
    0x3ff0000000000000,
    0x3ff02c9a3e778061,
    0x3ff059b0d3158574,
    0x3ff0874518759bc8,
    0x3ff0b5586cf9890f,
    0x3ff0e3ec32d3d1a2,
    0x3ff11301d0125b51,
    0x3ff1429aaea92de0,
    0x3ff172b83c7d517b,
    0x3ff1a35beb6fcb75,
    0x3ff1d4873168b9aa,
    0x3ff2063b88628cd6,
    0x3ff2387a6e756238,
    0x3ff26b4565e27cdd,
    0x3ff29e9df51fdee1,
    0x3ff2d285a6e4030b,
    0x3ff306fe0a31b715,
    0x3ff33c08b26416ff,
    0x3ff371a7373aa9cb,
    0x3ff3a7db34e59ff7,
    0x3ff3dea64c123422,
    0x3ff4160a21f72e2a,
    0x3ff44e086061892d,
    0x3ff486a2b5c13cd0,
    0x3ff4bfdad5362a27,
    0x3ff4f9b2769d2ca7,
    0x3ff5342b569d4f82,
    0x3ff56f4736b527da,
    0x3ff5ab07dd485429,
    0x3ff5e76f15ad2148,
    0x3ff6247eb03a5585,
    0x3ff6623882552225,
    0x3ff6a09e667f3bcd,
    0x3ff6dfb23c651a2f,
    0x3ff71f75e8ec5f74,
    0x3ff75feb564267c9,
    0x3ff7a11473eb0187,
    0x3ff7e2f336cf4e62,
    0x3ff82589994cce13,
    0x3ff868d99b4492ed,
    0x3ff8ace5422aa0db,
    0x3ff8f1ae99157736,
    0x3ff93737b0cdc5e5,
    0x3ff97d829fde4e50,
    0x3ff9c49182a3f090,
    0x3ffa0c667b5de565,
    0x3ffa5503b23e255d,
    0x3ffa9e6b5579fdbf,
    0x3ffae89f995ad3ad,
    0x3ffb33a2b84f15fb,
    0x3ffb7f76f2fb5e47,
    0x3ffbcc1e904bc1d2,
    0x3ffc199bdd85529c,
    0x3ffc67f12e57d14b,
    0x3ffcb720dcef9069,
    0x3ffd072d4a07897c,
    0x3ffd5818dcfba487,
    0x3ffda9e603db3285,
    0x3ffdfc97337b9b5f,
    0x3ffe502ee78b3ff6,
    0x3ffea4afa2a490da,
    0x3ffefa1bee615a27,
    0x3fff50765b6e4540,
    0x3fffa7c1819e90d8,
];
/// `64 / ln 2`.
const INV_LN2_64: f64 = 92.33248261689366;
/// `ln2 / 64` in two parts: the high part has 21 trailing zero bits, so `k LN2_64_HI` is
/// exact for `|k| < 2^21` (here `|k| <= 65 400`).
const LN2_64_HI: f64 = 0.01083042469326756;
const LN2_64_LO: f64 = 2.9815858269852933e-12;
/// `1.5 * 2^52`: adding it rounds to an integer (round to nearest, ties to even).
const SHIFT: f64 = 6755399441055744.0;
/// The range of the table path.
const LIMIT: f64 = 708.0;

/// `exp(z)`, within one unit in the last place (see the module documentation).
#[inline(always)]
pub fn exp(z: f64) -> f64 {
    if z.abs() <= LIMIT { table_exp(z) } else { z.exp() }
}

/// The table path of [`exp`], for `|z| <= 708`.
#[inline(always)]
fn table_exp(z: f64) -> f64 {
    let kd = z * INV_LN2_64 + SHIFT - SHIFT;
    let r = (z - kd * LN2_64_HI) - kd * LN2_64_LO;
    let k = kd as i64;
    let s = f64::from_bits(TABLE[(k & 63) as usize].wrapping_add(((k >> 6) as u64) << 52));
    let r2 = r * r;
    let p = r + r2 * (0.5 + r * (1.0 / 6.0)) + (r2 * r2) * ((1.0 / 24.0 + r * (1.0 / 120.0)) + r2 * (1.0 / 720.0));
    s + s * p
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units in the last place between two positive finite numbers.
    fn ulps(a: f64, b: f64) -> u64 {
        a.to_bits().abs_diff(b.to_bits())
    }

    /// Within one unit in the last place of the platform's `exp` (itself within about half
    /// a unit of the exact value) on a dense grid and on random arguments over the range,
    /// and exact at 0.
    #[test]
    fn within_one_ulp_of_the_platform_exp() {
        assert_eq!(exp(0.0), 1.0);
        let mut worst = 0;
        for i in -708_000..=708_000 {
            let z = i as f64 * 1e-3;
            worst = worst.max(ulps(exp(z), z.exp()));
        }
        let mut rng = crate::rng::pcg(5);
        for _ in 0..1_000_000 {
            use crate::rng::UniformSource;
            let u = rng.uniform();
            for z in [(u - 0.5) * 1416.0, (u - 0.5) * 2.0, (u - 0.5) * 1e-6] {
                worst = worst.max(ulps(exp(z), z.exp()));
            }
        }
        assert!(worst <= 1, "largest difference {worst} ulp");
    }

    #[test]
    fn outside_the_range_it_is_the_platform_exp() {
        for z in [-745.0, -709.0, 709.5, 710.0, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(exp(z).to_bits(), z.exp().to_bits(), "{z}");
        }
        assert!(exp(f64::NAN).is_nan());
    }

    /// Monotone across the table's steps (a thinning bound compares exponentials of ordered
    /// arguments).
    #[test]
    fn monotone_on_a_fine_grid() {
        let mut last = exp(-2.0);
        let mut z = -2.0;
        while z < 2.0 {
            z += 1.0 / 4096.0 + 1e-9;
            let e = exp(z);
            assert!(e >= last, "{z}");
            last = e;
        }
    }
}
