//! Uniform picks drawn ahead of use, so the memory they will touch can be prefetched.
//!
//! At large N a uniform pick from a bag is a cache miss (the bag is far larger than the
//! cache). Each channel therefore draws its *next* pick as a 64-bit number `u` right after
//! it fires; the index is `floor(u n / 2^64)` for the bag size `n` at the time of use
//! (a widening multiply: every index has probability within `n / 2^64` of `1/n`, far below
//! double-precision round-off), and the line at the index for the current size is
//! prefetched after every event, so the miss overlaps the work of the events in between.

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::rng::Pcg64;

/// A pre-drawn uniform pick.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Pick(u64);

impl Pick {
    pub fn draw(rng: &mut Pcg64) -> Pick {
        Pick(rng.next_u64())
    }
    /// The index in `0..n` (`n >= 1`).
    #[inline]
    pub fn index(self, n: usize) -> usize {
        ((u128::from(self.0) * n as u128) >> 64) as usize
    }
    /// Uses this pick for a bag of size `n` and draws the next one.
    #[inline]
    pub fn take(&mut self, n: usize, rng: &mut Pcg64) -> usize {
        let i = self.index(n);
        *self = Pick::draw(rng);
        i
    }
    /// Prefetches the element this pick would choose in `bag`.
    #[inline]
    pub fn prefetch<T>(self, bag: &[T]) {
        if !bag.is_empty() {
            prefetch(&bag[self.index(bag.len())]);
        }
    }
}

/// Hints the processor to load the cache line holding `*p`. A no-op where unsupported.
#[inline(always)]
pub fn prefetch<T>(p: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch never faults and has no architectural effect.
    #[allow(unused_unsafe)]
    unsafe {
        core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>((p as *const T).cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::pcg;

    #[test]
    fn index_covers_the_range_uniformly() {
        assert_eq!(Pick(0).index(7), 0);
        assert_eq!(Pick(u64::MAX).index(7), 6);
        let mut rng = pcg(3);
        let n = 10;
        let mut counts = [0u32; 10];
        for _ in 0..100_000 {
            counts[Pick::draw(&mut rng).index(n)] += 1;
        }
        // Chi-square with 9 degrees of freedom; 27.88 is its 0.999 quantile.
        let chi2: f64 = counts.iter().map(|&c| (c as f64 - 1e4).powi(2) / 1e4).sum();
        assert!(chi2 < 27.88, "{chi2}");
    }
}
