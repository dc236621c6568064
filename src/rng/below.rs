//! A uniform index in `0..n`, the numbers of `rand`'s `random_range(0..n)` bit for bit, inlined.

use rand::Rng;

/// `rng.random_range(0..n)` for `0 < n <= u32::MAX`, the same value from the same draws
/// (Canon's method on 32-bit words, as `rand` 0.10 takes for a `usize` range that fits in
/// 32 bits): `m = r n` for a 32-bit draw `r`; the index is `m`'s high word, plus one if
/// the low word exceeds `2^32 - n` and adding the high word of a second draw's product
/// carries. Always inlined; `rand`'s own call is out of line in the `release` build, which
/// has no link-time optimisation, and costs several times this. Wider `n` takes `rand`'s.
#[inline(always)]
pub fn below<R: Rng + ?Sized>(rng: &mut R, n: usize) -> usize {
    if n == 0 || n > u32::MAX as usize {
        return rand::RngExt::random_range(rng, 0..n);
    }
    let range = n as u32;
    let m = u64::from(rng.next_u32()) * u64::from(range);
    let (mut hi, lo) = ((m >> 32) as u32, m as u32);
    if lo > range.wrapping_neg() {
        let carry_in = ((u64::from(rng.next_u32()) * u64::from(range)) >> 32) as u32;
        hi += u32::from(lo.checked_add(carry_in).is_none());
    }
    hi as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64;

    /// The same indices and the same generator state as `random_range(0..n)`, for small,
    /// large and near-`2^32` sizes (where the second draw is taken often).
    #[test]
    fn below_is_random_range_bit_for_bit() {
        let sizes = [1usize, 2, 3, 7, 300, 1 << 20, 1_000_003, (1 << 31) + 1, u32::MAX as usize - 1, u32::MAX as usize];
        for (s, &n) in sizes.iter().enumerate() {
            let (mut a, mut b) = (Pcg64::seed_from_u64(s as u64), Pcg64::seed_from_u64(s as u64));
            for _ in 0..20_000 {
                assert_eq!(below(&mut a, n), b.random_range(0..n), "n = {n}");
            }
            assert_eq!(a.next_u64(), b.next_u64(), "n = {n}: the generators drifted apart");
        }
    }
}
