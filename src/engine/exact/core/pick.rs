//! Uniform picks drawn ahead of use, so the memory they will touch can be prefetched.
//!
//! At large N a uniform pick from a bag is a cache miss (the bag is far larger than the
//! cache). Each channel therefore keeps its next [`AHEAD`] picks as 64-bit numbers `u`,
//! drawn in order as earlier picks are used; the index is `floor(u n / 2^64)` for the bag
//! size `n` at the time of use (a widening multiply: every index has probability within
//! `n / 2^64` of `1/n`, far below double-precision round-off). After every event the lines
//! the front and the back pick can choose are prefetched, so a miss overlaps the work of
//! several events (one event is shorter than a memory access at N = 1e6). The picks are
//! independent uniforms whatever their order of drawing, so this changes no distribution.

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::rng::Pcg64;

/// Picks drawn ahead of use (a power of two: positions are taken modulo it with a mask,
/// so even a damaged `head` read from a checkpoint cannot index out of range).
pub const AHEAD: usize = 4;
const MASK: usize = AHEAD - 1;
/// How far the bag's size is allowed for to drift before the back pick is used: its index
/// `floor(u n / 2^64)` moves with `n`, by `u` elements per unit of `n`.
const DRIFT: usize = 4;

/// A queue of [`AHEAD`] pre-drawn uniform picks: the front one is used next, the back one
/// [`AHEAD`] uses later, so its memory can be prefetched several events before it is needed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Pick {
    q: [u64; AHEAD],
    head: u8,
}

/// The index in `0..n` of the 64-bit uniform `u`: `floor(u n / 2^64)` (`n >= 1`).
#[inline]
pub fn index(u: u64, n: usize) -> usize {
    ((u128::from(u) * n as u128) >> 64) as usize
}

impl Pick {
    pub fn draw(rng: &mut Pcg64) -> Pick {
        Pick { q: std::array::from_fn(|_| rng.next_u64()), head: 0 }
    }
    /// The index in `0..n` (`n >= 1`) of the next pick.
    #[inline]
    pub fn index(self, n: usize) -> usize {
        index(self.q[self.head as usize & MASK], n)
    }
    /// Uses the front pick for a bag of size `n` and draws a new one at the back.
    #[inline]
    pub fn take(&mut self, n: usize, rng: &mut Pcg64) -> usize {
        let h = self.head as usize & MASK;
        let i = index(self.q[h], n);
        self.q[h] = rng.next_u64();
        self.head = ((h + 1) & MASK) as u8;
        i
    }
    /// Prefetches the element of `bag` that the front pick would choose now (used within
    /// an event or two: the size moves by one per event, the index by at most one element),
    /// and the lines the back pick can choose at sizes `n - DRIFT ..= n + DRIFT` (their two
    /// ends and their middle: up to `2 DRIFT` elements, a line or two). The back pick is
    /// used [`AHEAD`] picks later, when the size has drifted by a few, which moves it to
    /// a neighbouring line whenever it crosses a line's edge (docs/performance.md has the
    /// A/B against prefetching at `n` alone).
    /// The addresses are formed without a bounds check (a prefetch never faults; the back
    /// pick's range reaches up to `DRIFT` elements past the end, and an empty bag
    /// prefetches its dangling base, harmlessly).
    /// By reference: the picks are read in place (by value, the queue was copied to the
    /// stack to be indexed).
    #[inline(always)]
    pub fn prefetch<T>(&self, bag: &[T]) {
        let n = bag.len();
        let h = self.head as usize & MASK;
        prefetch_ptr(bag.as_ptr().wrapping_add(index(self.q[h], n)));
        let back = self.q[(h + MASK) & MASK];
        let (lo, hi) = (index(back, n.saturating_sub(DRIFT)), index(back, n + DRIFT));
        prefetch_ptr(bag.as_ptr().wrapping_add(lo));
        prefetch_ptr(bag.as_ptr().wrapping_add((lo + hi) / 2));
        prefetch_ptr(bag.as_ptr().wrapping_add(hi));
    }
}

/// [`prefetch`] of a raw address, which need not be valid (a prefetch never faults).
#[inline(always)]
pub fn prefetch_ptr<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch never faults and has no architectural effect, whatever the address.
    #[allow(unused_unsafe)]
    unsafe {
        core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(p.cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Asks the processor to bring the cache line holding `*p` in ahead of its use (x86-64's
/// `prefetcht0`, through [`prefetch_ptr`]; a no-op elsewhere). A hint only: it never faults
/// and changes no result.
#[inline(always)]
pub fn prefetch<T>(p: &T) {
    prefetch_ptr(p as *const T)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::pcg;

    #[test]
    fn index_covers_the_range_uniformly() {
        assert_eq!(index(0, 7), 0);
        assert_eq!(index(u64::MAX, 7), 6);
        let mut rng = pcg(3);
        let n = 10;
        let mut counts = [0u32; 10];
        for _ in 0..100_000 {
            counts[index(rng.next_u64(), n)] += 1;
        }
        // Chi-square with 9 degrees of freedom; 27.88 is its 0.999 quantile.
        let chi2: f64 = counts.iter().map(|&c| (c as f64 - 1e4).powi(2) / 1e4).sum();
        assert!(chi2 < 27.88, "{chi2}");
    }
}
