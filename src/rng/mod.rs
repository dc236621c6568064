//! Random numbers. Engines receive their generator by `&mut R`; only portable, named
//! generators are used (Park–Miller, `rand_pcg::Pcg64`), so a scene and a seed give the
//! same numbers on every machine and thread count.

mod below;
pub mod park_miller;

pub use below::below;

pub use park_miller::{ParkMiller, PeriodExceeded};
pub use rand_pcg::Pcg64;

use rand::SeedableRng;

/// A source of uniform numbers in the open interval `(0, 1)`, the `xi_i` of the letter's eq. 5.
pub trait UniformSource {
    /// One uniform number in `(0, 1)`.
    fn uniform(&mut self) -> f64;
    /// Fills `out` with the next `out.len()` uniforms, in order: the numbers, bit for bit,
    /// that as many calls of [`UniformSource::uniform`] return.
    #[inline]
    fn uniforms(&mut self, out: &mut [f64]) {
        for u in out {
            *u = self.uniform();
        }
    }
    /// Skips the next `n` draws: the generator ends where `n` calls of
    /// [`UniformSource::uniform`] leave it. By default those calls; the named generators
    /// jump ahead in `O(log n)`.
    #[inline]
    fn skip(&mut self, n: u64) {
        for _ in 0..n {
            self.uniform();
        }
    }
    /// Whether [`UniformSource::raws`] gives the draws on a scale of their own (then
    /// [`UniformSource::to_uniform`] and [`UniformSource::raw_partition`] say how it maps).
    /// `false`: the raw draws are the uniforms.
    #[inline]
    fn has_raw_scale() -> bool
    where
        Self: Sized,
    {
        false
    }
    /// Fills `out` with the next `out.len()` draws `r` on the generator's raw scale: the
    /// uniforms that as many calls of [`UniformSource::uniform`] return are
    /// `Self::to_uniform(r)`, bit for bit. By default the uniforms themselves.
    #[inline]
    fn raws(&mut self, out: &mut [f64]) {
        self.uniforms(out);
    }
    /// The uniform of a raw draw, non-decreasing in `r`. By default `r` itself.
    #[inline]
    fn to_uniform(r: f64) -> f64
    where
        Self: Sized,
    {
        r
    }
    /// For a `keep` on uniforms that holds below some point and fails above it, the
    /// smallest raw value `c` (an integer) of the generator's range with
    /// `!keep(to_uniform(c))`: for every raw draw `r`, `keep(to_uniform(r))` iff `r < c`.
    /// Only called when [`UniformSource::has_raw_scale`]; by default NaN.
    fn raw_partition(_keep: impl Fn(f64) -> bool) -> f64
    where
        Self: Sized,
    {
        f64::NAN
    }
}

impl UniformSource for ParkMiller {
    /// `xi = s / (2^31 - 1)`, which lies in `(0, 1)` because `s` is in `[1, 2^31 - 2]`.
    #[inline]
    fn uniform(&mut self) -> f64 {
        f64::from(self.next_state()) / f64::from(ParkMiller::MODULUS)
    }
    /// The states from [`ParkMiller::fill_with`] (several lanes at once), each divided as in
    /// [`UniformSource::uniform`].
    #[inline]
    fn uniforms(&mut self, out: &mut [f64]) {
        self.raws(out);
        for u in out {
            *u = Self::to_uniform(*u);
        }
    }
    #[inline]
    fn has_raw_scale() -> bool {
        true
    }
    /// The states `s` themselves (from [`ParkMiller::fill_with`], several lanes at once),
    /// as `f64` (exact: `s < 2^31`).
    #[inline]
    fn raws(&mut self, out: &mut [f64]) {
        self.fill_with(out, f64::from);
    }
    /// `s / (2^31 - 1)`, as in [`UniformSource::uniform`]; non-decreasing in `s` because a
    /// correctly rounded division by a positive number is.
    #[inline]
    fn to_uniform(r: f64) -> f64 {
        r / f64::from(ParkMiller::MODULUS)
    }
    /// `s <- a^n s mod m` ([`ParkMiller::advance`]).
    #[inline]
    fn skip(&mut self, n: u64) {
        self.advance(n);
    }
    /// A binary search over the states `[0, 2^31 - 1]` (31 divisions).
    fn raw_partition(keep: impl Fn(f64) -> bool) -> f64 {
        let (mut lo, mut hi) = (0u32, ParkMiller::MODULUS + 1);
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if keep(Self::to_uniform(f64::from(mid))) {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        f64::from(lo)
    }
}

impl UniformSource for Pcg64 {
    /// `(m + 0.5) / 2^53` from the top 53 bits `m` of one output: in `(0, 1)`.
    #[inline]
    fn uniform(&mut self) -> f64 {
        use rand::Rng;
        ((self.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
    }
    /// One uniform is one output of the generator: the LCG's own jump ahead by `n` steps.
    #[inline]
    fn skip(&mut self, n: u64) {
        self.advance(u128::from(n));
    }
}

/// The PCG generator for a seed: `Pcg64::seed_from_u64(seed)`.
pub fn pcg(seed: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn park_miller_uniforms_are_the_single_draws() {
        for len in [0, 1, 7, 8, 9, 255, 256, 257, 1000] {
            let mut one = ParkMiller::new(42).unwrap();
            let mut many = one.clone();
            let want: Vec<u64> = (0..len).map(|_| one.uniform().to_bits()).collect();
            let mut got = vec![0.0; len];
            many.uniforms(&mut got);
            assert_eq!(got.iter().map(|u| u.to_bits()).collect::<Vec<_>>(), want, "{len} draws");
            assert_eq!(many.uniform().to_bits(), one.uniform().to_bits());
        }
    }

    /// The partition point of `u < th` on the states agrees with the division at the
    /// states around it, for thresholds at, between and beyond the uniforms.
    #[test]
    fn park_miller_partition_matches_the_division() {
        let m = f64::from(ParkMiller::MODULUS);
        let mut g = ParkMiller::new(9).unwrap();
        let mut ths: Vec<f64> = vec![0.0, -1.0, 1.0, 2.0, f64::INFINITY, 1e-300, 0.5, 1.0 / m, 2.0 / m];
        for _ in 0..200 {
            let u = g.uniform();
            ths.extend([u, f64::from_bits(u.to_bits() + 1), f64::from_bits(u.to_bits() - 1)]);
        }
        for th in ths {
            let c = ParkMiller::raw_partition(|u| u < th);
            assert_eq!(c, c.trunc());
            assert!((0.0..=m + 1.0).contains(&c), "{th}: {c}");
            if c >= 1.0 {
                assert!(ParkMiller::to_uniform(c - 1.0) < th, "{th}: {c}");
            }
            if c <= m {
                assert!(ParkMiller::to_uniform(c) >= th, "{th}: {c}");
            }
        }
        let nan = f64::NAN;
        assert_eq!(ParkMiller::raw_partition(|u| u < nan), 0.0, "no state is below NaN");
    }

    #[test]
    fn park_miller_raws_are_the_states() {
        let mut one = ParkMiller::new(5).unwrap();
        let mut many = one.clone();
        let mut got = vec![0.0; 300];
        many.raws(&mut got);
        for r in got {
            let u = one.uniform();
            assert_eq!(ParkMiller::to_uniform(r).to_bits(), u.to_bits());
        }
    }

    /// Both named generators skip ahead to where as many single draws lead.
    #[test]
    fn skipping_is_drawing() {
        fn check<R: UniformSource + Clone>(g: R) {
            for n in [0u64, 1, 2, 17, 256, 4097] {
                let (mut one, mut skipped) = (g.clone(), g.clone());
                for _ in 0..n {
                    one.uniform();
                }
                skipped.skip(n);
                assert_eq!(skipped.uniform().to_bits(), one.uniform().to_bits(), "{n} draws");
            }
        }
        check(ParkMiller::new(77).unwrap());
        check(pcg(77));
    }

    #[test]
    fn pcg_uniform_is_open_and_reproducible() {
        let mut a = pcg(42);
        let mut b = pcg(42);
        for _ in 0..10_000 {
            let u = a.uniform();
            assert!(u > 0.0 && u < 1.0);
            assert_eq!(u.to_bits(), b.uniform().to_bits());
        }
    }
}
