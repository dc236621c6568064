//! Seeds of the runs of a study, derived from the scene's seed so that a study is
//! reproducible and independent of the order (and the thread) in which its runs execute.
//!
//! One mixer, [`mix`]: SplitMix64's output function applied to `x + 0x9E3779B97F4A7C15`
//! (Steele, Lea & Flood 2014; the generator behind `rand`'s `seed_from_u64`), a bijection of
//! `u64` with good avalanche. A run's hash is the chain [`chain`]`(s, [v1, v2, ..]) =
//! mix(..mix(mix(s) ^ v1) ^ v2 ..)` of the scene's `run.seed` `s` and the numbers that name
//! the run.
//!
//! **Sweeps** (`stickslip sweep`). The run for grid point `i` (0-based, in the order the
//! points are listed; for a 1-D sweep the value index) and replica `r` (0-based) gets
//!
//! ```text
//! h(i, r) = mix(mix(mix(s) ^ i) ^ r)
//! ```
//!
//! - PCG streams (the exact engine; the fixed engine with `fixed.rng = "pcg"`): the seed is
//!   `h(i, r) >> 1` (a TOML integer, `0 ..= 2^63 - 1`). Seeds are assigned in point-major
//!   order (all replicas of point 0, then of point 1, ...); a seed equal to one already
//!   assigned is replaced by the next `h <- mix(h)` until it is new, so every run of such a
//!   sweep has its own seed.
//! - Park–Miller (`run.engine = "fixed"`, `fixed.rng = "park-miller"`): the replicas of a
//!   point take consecutive, disjoint blocks of the generator's single cycle, as in a
//!   work-precision study (below): the point starts at the state `1 + h(i, 2^64 - 1) mod
//!   (2^31 - 2)` and replica `r` `r L` draws further on, `L = N (steps + 1)` the draws one
//!   replica can use (one per junction and step, and one per junction for a stationary
//!   start; `steps` the fixed steps to `run.t_end`). A point whose replicas need more than
//!   the period `2^31 - 2` draws is refused. Different points may share states: each point
//!   is an estimate of its own, and only its replicas must be independent.
//!
//! **Work-precision studies** (`stickslip compare`). Every replica of every point gets its
//! own seed, a function of `(run.seed, role, point, replica)` only:
//!
//! - PCG streams (the exact engine; the fixed engine with `fixed.rng = "pcg"`): the seed is
//!   `chain(s, [role, point, replica]) >> 1`. `Pcg64::seed_from_u64` of distinct seeds gives
//!   unrelated 128-bit states; the reference, every point and every replica have distinct
//!   seeds.
//! - Park–Miller (the fixed engine's default): every seed lies on the generator's single
//!   cycle of length `2^31 - 2`, so seeds picked at random would give streams that overlap
//!   (at `dt = 1/256` of Fig. 1 a replica draws 11.5 million numbers, and two random starts
//!   fall that close with probability about 1 %). The replicas of one point therefore take
//!   consecutive, disjoint blocks of the cycle: the point starts at a hashed state `s_0`,
//!   replica `r` at `s_0 a^(r L) mod m` (`a = 16807`, `m = 2^31 - 1`, `L` the draws one
//!   replica can use), computed by modular exponentiation. A point whose replicas do not
//!   fit in one cycle is refused.

use std::collections::HashSet;

use crate::rng::ParkMiller;
use crate::scene::Scene;

/// SplitMix64's increment (the golden ratio in 64-bit fixed point).
pub const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function of `x + GAMMA`: a bijection of `u64` with good avalanche.
pub fn mix(x: u64) -> u64 {
    let mut z = x.wrapping_add(GAMMA);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The hash chain `mix(..mix(mix(base) ^ values[0]) ^ values[1] ..)`.
pub fn chain(base: u64, values: &[u64]) -> u64 {
    values.iter().fold(mix(base), |h, &v| mix(h ^ v))
}

// ---------------------------------------------------------------------------------------
// Sweeps

/// `h(i, r)` of a sweep's run.
pub fn hash(scene_seed: u64, index: u64, replica: u64) -> u64 {
    chain(scene_seed, &[index, replica])
}

/// Hashed seeds `seeds[i][r] = h(i, r) >> 1` for `points` grid points and `replicas`
/// replicas, distinct (a repeat is replaced by the next `h <- mix(h)`): a sweep's and a
/// calibration's ([`crate::fit`]) PCG seeds.
pub fn derive_all(scene_seed: u64, points: usize, replicas: usize) -> Vec<Vec<u64>> {
    let mut seen = HashSet::with_capacity(points * replicas);
    (0..points)
        .map(|i| {
            (0..replicas)
                .map(|r| {
                    let mut h = hash(scene_seed, i as u64, r as u64);
                    while !seen.insert(h >> 1) {
                        h = mix(h);
                    }
                    h >> 1
                })
                .collect()
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// Work-precision studies

/// Which part of a work-precision study a seed is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// The exact engine's reference replicas.
    Reference = 1,
    /// The exact engine's points (increasing replica counts).
    Exact = 2,
    /// The fixed engine's points (one per `dt`).
    Fixed = 3,
}

/// The PCG seed of one replica of a study: in `[0, 2^63 - 1]`, as `run.seed` allows.
pub fn pcg_seed(base: u64, role: Role, point: u64, replica: u64) -> u64 {
    chain(base, &[role as u64, point, replica]) >> 1
}

/// The Park–Miller period `2^31 - 2`.
pub const PARK_MILLER_PERIOD: u64 = ParkMiller::PERIOD;

/// The numbers one replica of `scene` may draw from the Park–Miller generator, the length
/// of its block of the cycle: `N (steps + 1)` for the steps to `run.t_end` (one per junction
/// and step, and one per junction for a stationary start).
pub fn replica_draws(scene: &Scene) -> u64 {
    (scene.junctions.n as u64).saturating_mul(scene.fixed.steps_for(scene.run.t_end).saturating_add(1))
}

/// Why `replicas` blocks of `draws` numbers do not fit in the Park–Miller cycle, and the
/// ways out (fewer replicas only when there are several).
pub fn blocks_do_not_fit(replicas: usize, draws: u64) -> String {
    format!(
        "the replicas need {replicas} x {draws} Park-Miller draws, more than the generator's period {}; use {}a \
         larger fixed.dt or --set fixed.rng=pcg",
        PARK_MILLER_PERIOD,
        if replicas > 1 { "fewer replicas, " } else { "" }
    )
}

/// The Park–Miller seeds of `replicas` replicas of one fixed-step point of a study, each
/// allowed `draws` numbers: disjoint consecutive blocks of the cycle starting at a hashed
/// state. `None` if the blocks do not fit in one period.
pub fn park_miller_seeds(base: u64, point: u64, replicas: usize, draws: u64) -> Option<Vec<u64>> {
    park_miller_blocks(chain(base, &[Role::Fixed as u64, point, u64::MAX]), replicas, draws)
}

/// The Park–Miller seeds of the replicas of sweep grid point `index`, each allowed `draws`
/// numbers: disjoint consecutive blocks of the cycle from the state `1 + h(index, 2^64 - 1)
/// mod (2^31 - 2)`. `None` if the blocks do not fit in one period.
pub fn sweep_park_miller_seeds(scene_seed: u64, index: u64, replicas: usize, draws: u64) -> Option<Vec<u64>> {
    park_miller_blocks(hash(scene_seed, index, u64::MAX), replicas, draws)
}

/// `replicas` states of the Park–Miller cycle, `draws` apart, from `1 + h mod (2^31 - 2)`:
/// the first states of consecutive blocks of `draws` numbers. `None` if the blocks do not
/// fit in one period.
fn park_miller_blocks(h: u64, replicas: usize, draws: u64) -> Option<Vec<u64>> {
    let total = (replicas as u64).checked_mul(draws)?;
    if total > PARK_MILLER_PERIOD {
        return None;
    }
    let m = u64::from(ParkMiller::MODULUS);
    let start = 1 + h % PARK_MILLER_PERIOD;
    let jump = u64::from(ParkMiller::jump(draws % PARK_MILLER_PERIOD));
    let mut s = start;
    Some(
        (0..replicas)
            .map(|_| {
                let seed = s;
                s = s * jump % m;
                seed
            })
            .collect(),
    )
}

/// Asserts that `seeds` are the first states of consecutive blocks of `draws` numbers of
/// the Park–Miller cycle, the first at the state of sweep point `index` of `run.seed = 1`
/// ([`sweep_park_miller_seeds`]; `None` for another start).
#[cfg(test)]
pub(crate) fn assert_consecutive_blocks(seeds: &[u64], draws: u64, index: Option<u64>) {
    if let Some(i) = index {
        assert_eq!(seeds[0], 1 + hash(1, i, u64::MAX) % PARK_MILLER_PERIOD, "point {i}");
    }
    for w in seeds.windows(2) {
        let mut g = ParkMiller::new(w[0]).unwrap();
        for _ in 0..draws {
            g.next_state();
        }
        // The next replica starts where this one's block ends: no draw is shared.
        assert_eq!(u64::from(g.state()), w[1], "{seeds:?}");
    }
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
    fn derived_seeds_are_those_of_the_documented_results() {
        // Computed with the two mixers this module replaced (the sweep's `mix` and the
        // comparison's `splitmix64`): the published sweeps and studies keep their seeds. docs/figures/fig2-sweep/sweep.json lists seeds[13][3].
        let fig2 = derive_all(1, 14, 4);
        assert_eq!(fig2[13][3], 4_231_203_880_505_546_300);
        assert_eq!(pcg_seed(7, Role::Exact, 1, 3), 3_368_791_360_226_051_095);
        assert_eq!(pcg_seed(1, Role::Reference, 0, 0), 7_256_120_447_724_176_321);
        assert_eq!(chain(1, &[Role::Fixed as u64, 2, u64::MAX]), 8_444_155_210_490_955_777);
    }

    #[test]
    fn seeds_are_distinct_and_in_range() {
        let flat: Vec<u64> = derive_all(1, 50, 20).into_iter().flatten().collect();
        let set: HashSet<u64> = flat.iter().copied().collect();
        assert_eq!(set.len(), 1000);
        assert!(flat.iter().all(|&x| x <= i64::MAX as u64));
    }

    #[test]
    fn a_seed_depends_on_its_index_and_replica_only() {
        let a = derive_all(7, 3, 4);
        let b = derive_all(7, 5, 4);
        assert_eq!(a[..], b[..3]);
        assert_eq!(a[2][3], hash(7, 2, 3) >> 1);
        assert_ne!(derive_all(8, 1, 1), derive_all(7, 1, 1));
    }

    #[test]
    fn park_miller_blocks_follow_each_other_on_the_cycle() {
        let draws = 1000;
        let seeds = park_miller_seeds(7, 3, 4, draws).unwrap();
        assert_consecutive_blocks(&seeds, draws, None);
        assert!(seeds.iter().all(|&s| (1..=PARK_MILLER_PERIOD).contains(&s)));
    }

    #[test]
    fn too_many_draws_are_refused() {
        assert!(park_miller_seeds(1, 0, 2, PARK_MILLER_PERIOD / 2).is_some());
        assert!(park_miller_seeds(1, 0, 3, PARK_MILLER_PERIOD / 2).is_none());
    }

    #[test]
    fn study_seeds_differ_by_role_point_and_replica() {
        let a = pcg_seed(1, Role::Reference, 0, 0);
        assert_ne!(a, pcg_seed(1, Role::Exact, 0, 0));
        assert_ne!(a, pcg_seed(1, Role::Reference, 1, 0));
        assert_ne!(a, pcg_seed(1, Role::Reference, 0, 1));
        assert_ne!(a, pcg_seed(2, Role::Reference, 0, 0));
        assert!(a < 1 << 63);
    }
}
