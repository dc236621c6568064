//! Seeds of a study, derived deterministically from the scene's `run.seed`.
//!
//! Every replica of every point gets its own seed, a function of
//! `(run.seed, role, point, replica)` only, so results do not depend on the order in which
//! replicas run or on the number of threads.
//!
//! - PCG streams (the exact engine; the fixed engine with `fixed.rng = "pcg"`): the seed is
//!   the SplitMix64 hash chain of the four numbers, cut to 63 bits. `Pcg64::seed_from_u64`
//!   of distinct seeds gives unrelated 128-bit states; the reference, every point and every
//!   replica have distinct seeds.
//! - Park–Miller (the fixed engine's default): every seed lies on the generator's single
//!   cycle of length `2^31 - 2`, so seeds picked at random would give streams that overlap
//!   (at `dt = 1/256` of Fig. 1 a replica draws 11.5 million numbers, and two random starts
//!   fall that close with probability about 1 %). The replicas of one point therefore take
//!   consecutive, disjoint blocks of the cycle: the point starts at a hashed state `s_0`,
//!   replica `r` at `s_0 a^(r L) mod m` (`a = 16807`, `m = 2^31 - 1`, `L` the draws one
//!   replica can use), computed by modular exponentiation. A point whose replicas do not
//!   fit in one cycle is refused.

use crate::rng::ParkMiller;

/// Which part of a study a seed is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// The exact engine's reference replicas.
    Reference = 1,
    /// The exact engine's points (increasing replica counts).
    Exact = 2,
    /// The fixed engine's points (one per `dt`).
    Fixed = 3,
}

/// SplitMix64's output function (Steele, Lea & Flood 2014).
pub fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A 64-bit hash of `(base, role, point, replica)`.
pub fn hash(base: u64, role: Role, point: u64, replica: u64) -> u64 {
    let mut h = splitmix64(base);
    for v in [role as u64, point, replica] {
        h = splitmix64(h ^ v);
    }
    h
}

/// The PCG seed of one replica: in `[0, 2^63 - 1]`, as `run.seed` allows.
pub fn pcg_seed(base: u64, role: Role, point: u64, replica: u64) -> u64 {
    hash(base, role, point, replica) >> 1
}

/// The Park–Miller period `2^31 - 2`.
pub const PARK_MILLER_PERIOD: u64 = ParkMiller::MODULUS as u64 - 1;

/// `b^e mod m` for `m < 2^32`.
fn pow_mod(mut b: u64, mut e: u64, m: u64) -> u64 {
    let mut r = 1u64;
    b %= m;
    while e > 0 {
        if e & 1 == 1 {
            r = r * b % m;
        }
        b = b * b % m;
        e >>= 1;
    }
    r
}

/// The Park–Miller seeds of `replicas` replicas of one point, each allowed `draws` numbers:
/// disjoint consecutive blocks of the cycle starting at a hashed state. `None` if the
/// blocks do not fit in one period.
pub fn park_miller_seeds(base: u64, point: u64, replicas: usize, draws: u64) -> Option<Vec<u64>> {
    let total = (replicas as u64).checked_mul(draws)?;
    if total > PARK_MILLER_PERIOD {
        return None;
    }
    let m = u64::from(ParkMiller::MODULUS);
    let start = 1 + hash(base, Role::Fixed, point, u64::MAX) % PARK_MILLER_PERIOD;
    let jump = pow_mod(u64::from(ParkMiller::MULTIPLIER), draws % PARK_MILLER_PERIOD, m);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn park_miller_blocks_follow_each_other_on_the_cycle() {
        let draws = 1000;
        let seeds = park_miller_seeds(7, 3, 4, draws).unwrap();
        for w in seeds.windows(2) {
            let mut g = ParkMiller::new(w[0]).unwrap();
            for _ in 0..draws {
                g.next_state();
            }
            // The next replica starts where this one's block ends: no draw is shared.
            assert_eq!(u64::from(g.state()), w[1]);
        }
        assert!(seeds.iter().all(|&s| (1..=PARK_MILLER_PERIOD).contains(&s)));
    }

    #[test]
    fn too_many_draws_are_refused() {
        assert!(park_miller_seeds(1, 0, 2, PARK_MILLER_PERIOD / 2).is_some());
        assert!(park_miller_seeds(1, 0, 3, PARK_MILLER_PERIOD / 2).is_none());
    }

    #[test]
    fn seeds_differ_by_role_point_and_replica() {
        let a = pcg_seed(1, Role::Reference, 0, 0);
        assert_ne!(a, pcg_seed(1, Role::Exact, 0, 0));
        assert_ne!(a, pcg_seed(1, Role::Reference, 1, 0));
        assert_ne!(a, pcg_seed(1, Role::Reference, 0, 1));
        assert_ne!(a, pcg_seed(2, Role::Reference, 0, 0));
        assert!(a < 1 << 63);
    }
}
