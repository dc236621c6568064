//! Random numbers. Engines receive their generator by `&mut R`; only portable, named
//! generators are used (Park–Miller, `rand_pcg::Pcg64`), so a scene and a seed give the
//! same numbers on every machine and thread count.

pub mod park_miller;

pub use park_miller::ParkMiller;
pub use rand_pcg::Pcg64;

use rand::SeedableRng;

/// A source of uniform numbers in the open interval `(0, 1)`, the `xi_i` of the letter's eq. 5.
pub trait UniformSource {
    /// One uniform number in `(0, 1)`.
    fn uniform(&mut self) -> f64;
}

impl UniformSource for ParkMiller {
    /// `xi = s / (2^31 - 1)`, which lies in `(0, 1)` because `s` is in `[1, 2^31 - 2]`.
    #[inline]
    fn uniform(&mut self) -> f64 {
        f64::from(self.next_state()) / f64::from(ParkMiller::MODULUS)
    }
}

impl UniformSource for Pcg64 {
    /// `(m + 0.5) / 2^53` from the top 53 bits `m` of one output: in `(0, 1)`.
    #[inline]
    fn uniform(&mut self) -> f64 {
        use rand::Rng;
        ((self.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
    }
}

/// The PCG generator for a seed: `Pcg64::seed_from_u64(seed)`.
pub fn pcg(seed: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seed)
}

/// A standard exponential variate `-ln(xi)`, `xi` uniform in `(0, 1)`.
#[inline]
pub fn exp1<R: UniformSource + ?Sized>(rng: &mut R) -> f64 {
    -rng.uniform().ln()
}

#[cfg(test)]
mod tests {
    use super::*;

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
