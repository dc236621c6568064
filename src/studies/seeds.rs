//! Seeds of the runs of a study, derived from the scene's seed so that a study is
//! reproducible and independent of the order (and the thread) in which its runs execute.
//!
//! The run for value index `i` (0-based, in the order the values are listed) and replica
//! `r` (0-based) gets
//!
//! ```text
//! h(i, r) = mix(mix(mix(s) ^ i) ^ r)        s = the scene's run.seed
//! ```
//!
//! where `mix` is SplitMix64's output function applied to `x + 0x9E3779B97F4A7C15`
//! (Steele, Lea & Flood 2014; the generator behind `rand`'s `seed_from_u64`). The seed is
//! `h >> 1` (a TOML integer, `0 ..= 2^63 - 1`), or `1 + h mod (2^31 - 2)` when the run uses
//! the Park–Miller generator (`run.engine = "fixed"`, `fixed.rng = "park-miller"`), whose
//! seeds lie in `[1, 2^31 - 2]`. Seeds are assigned in index-major order (all replicas of
//! value 0, then of value 1, ...); a seed equal to one already assigned (possible, though
//! unlikely, in the Park–Miller range) is replaced by the next `h <- mix(h)` until it is new,
//! so every run of a study has its own seed.

use std::collections::HashSet;

use crate::scene::validate::PARK_MILLER_SEED_MAX;

/// SplitMix64's increment (the golden ratio in 64-bit fixed point).
pub const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function of `x + GAMMA`: a bijection of `u64` with good avalanche.
pub fn mix(x: u64) -> u64 {
    let mut z = x.wrapping_add(GAMMA);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The range a run's seed must lie in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeedRange {
    /// `0 ..= 2^63 - 1` (any seed a scene file can hold).
    Full,
    /// `1 ..= 2^31 - 2` (the Park–Miller generator).
    ParkMiller,
}

impl SeedRange {
    fn map(self, h: u64) -> u64 {
        match self {
            SeedRange::Full => h >> 1,
            SeedRange::ParkMiller => 1 + h % PARK_MILLER_SEED_MAX,
        }
    }
}

/// `h(i, r)` before mapping into a range.
pub fn hash(scene_seed: u64, index: u64, replica: u64) -> u64 {
    mix(mix(mix(scene_seed) ^ index) ^ replica)
}

/// Seeds of all runs: `seeds[i][r]` for `values` values and `replicas` replicas, distinct.
/// `range(i)` gives the seed range of value `i`'s runs.
pub fn derive_all(
    scene_seed: u64,
    values: usize,
    replicas: usize,
    range: impl Fn(usize) -> SeedRange,
) -> Vec<Vec<u64>> {
    let mut seen = HashSet::with_capacity(values * replicas);
    (0..values)
        .map(|i| {
            let rng = range(i);
            (0..replicas)
                .map(|r| {
                    let mut h = hash(scene_seed, i as u64, r as u64);
                    let mut s = rng.map(h);
                    while !seen.insert(s) {
                        h = mix(h);
                        s = rng.map(h);
                    }
                    s
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_reference_values() {
        // SplitMix64 seeded with 0: the state advances by GAMMA and each output is mix of
        // the previous state, so mix(0), mix(GAMMA), ... are its first outputs.
        assert_eq!(mix(0), 0xE220_A839_7B1D_CDAF);
        assert_eq!(mix(GAMMA), 0x6E78_9E6A_A1B9_65F4);
    }

    #[test]
    fn seeds_are_distinct_and_in_range() {
        for range in [SeedRange::Full, SeedRange::ParkMiller] {
            let s = derive_all(1, 50, 20, |_| range);
            let flat: Vec<u64> = s.iter().flatten().copied().collect();
            let set: HashSet<u64> = flat.iter().copied().collect();
            assert_eq!(set.len(), 1000);
            for &x in &flat {
                match range {
                    SeedRange::Full => assert!(x <= i64::MAX as u64),
                    SeedRange::ParkMiller => assert!((1..=PARK_MILLER_SEED_MAX).contains(&x)),
                }
            }
        }
    }

    #[test]
    fn a_seed_depends_on_its_index_and_replica_only() {
        let a = derive_all(7, 3, 4, |_| SeedRange::Full);
        let b = derive_all(7, 5, 4, |_| SeedRange::Full);
        assert_eq!(a[..], b[..3]);
        assert_eq!(a[2][3], hash(7, 2, 3) >> 1);
        assert_ne!(derive_all(8, 1, 1, |_| SeedRange::Full), derive_all(7, 1, 1, |_| SeedRange::Full));
    }
}
