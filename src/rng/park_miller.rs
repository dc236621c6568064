//! The Park–Miller "minimal standard" generator (Park & Miller, CACM 31, 1988), the
//! letter's generator: `s <- 16807 s mod (2^31 - 1)`, `xi = s / (2^31 - 1)`.

use serde::{Deserialize, Serialize};

/// Minimal-standard Lehmer generator. The state is always in `[1, 2^31 - 2]`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ParkMiller {
    state: u32,
}

/// Why a Park–Miller seed was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("Park-Miller seed {0} is outside [1, 2147483646]")]
pub struct BadSeed(pub u64);

impl ParkMiller {
    /// The modulus `2^31 - 1`.
    pub const MODULUS: u32 = 2_147_483_647;
    /// The multiplier `7^5`.
    pub const MULTIPLIER: u32 = 16_807;
    /// The period `2^31 - 2`: from any seed, draw `n + PERIOD` is draw `n` again (16807 is
    /// a primitive root modulo the prime `2^31 - 1`).
    pub const PERIOD: u64 = Self::MODULUS as u64 - 1;

    /// A generator with state `seed`, which must lie in `[1, 2^31 - 2]`.
    pub fn new(seed: u64) -> Result<Self, BadSeed> {
        if (1..=u64::from(Self::MODULUS - 1)).contains(&seed) {
            Ok(ParkMiller { state: seed as u32 })
        } else {
            Err(BadSeed(seed))
        }
    }

    /// Advances and returns the new state `s` in `[1, 2^31 - 2]`.
    #[inline]
    pub fn next_state(&mut self) -> u32 {
        // 16807 * (2^31 - 2) < 2^46: exact in u64.
        self.state = ((u64::from(self.state) * u64::from(Self::MULTIPLIER)) % u64::from(Self::MODULUS)) as u32;
        self.state
    }

    /// The current state.
    pub fn state(&self) -> u32 {
        self.state
    }

    /// `a^j mod m`, the multiplier that advances the state by `j` draws at once:
    /// `s(n + j) = a^j s(n) mod m`.
    pub const fn jump(j: u64) -> u32 {
        let (mut r, mut b, mut e) = (1u64, Self::MULTIPLIER as u64, j);
        let m = Self::MODULUS as u64;
        while e > 0 {
            if e & 1 == 1 {
                r = r * b % m;
            }
            b = b * b % m;
            e >>= 1;
        }
        r as u32
    }

    /// Skips `n` draws: the state becomes the one `n` calls of [`ParkMiller::next_state`]
    /// would leave, `s(k + n) = a^n s(k) mod m`, in `O(log n)` multiplications.
    #[inline]
    pub fn advance(&mut self, n: u64) {
        let (mut r, mut b, mut e) = (1u32, Self::MULTIPLIER, n);
        while e > 0 {
            if e & 1 == 1 {
                r = mul_mod(r, b);
            }
            b = mul_mod(b, b);
            e >>= 1;
        }
        self.state = mul_mod(self.state, r);
    }

    /// Fills `out` with the next `out.len()` states, in order: the numbers that as many
    /// calls of [`ParkMiller::next_state`] return, and the generator ends where they would
    /// leave it.
    ///
    /// [`LANES`] lanes draw the one sequence: lane `l` holds `s(n + l)` and advances by
    /// `a^LANES mod m` ([`ParkMiller::jump`]), so the lanes' multiplications are independent
    /// and run side by side (vector instructions) instead of one chain of `out.len()` steps.
    #[inline]
    pub fn fill_states(&mut self, out: &mut [u32]) {
        self.fill_with(out, |s| s);
    }

    /// [`ParkMiller::fill_states`] with each state converted by `convert` as it is written.
    #[inline(always)]
    pub fn fill_with<T: Copy>(&mut self, out: &mut [T], convert: impl Fn(u32) -> T) {
        let whole = out.len() / LANES * LANES;
        let (lanes_part, rest) = out.split_at_mut(whole);
        if whole > 0 {
            let mut lanes = [0u32; LANES];
            for lane in &mut lanes {
                *lane = self.next_state();
            }
            // Plain index loops over fixed-size arrays: they unroll into vector instructions
            // in every profile.
            let chunks = whole / LANES;
            for c in 0..chunks {
                let chunk: &mut [T; LANES] = (&mut lanes_part[c * LANES..(c + 1) * LANES]).try_into().unwrap();
                for l in 0..LANES {
                    chunk[l] = convert(lanes[l]);
                }
                // The last chunk's lanes are not advanced: the state ends at its last draw.
                if c + 1 < chunks {
                    for lane in &mut lanes {
                        *lane = mul_mod(*lane, JUMP_LANES);
                    }
                }
            }
            self.state = lanes[LANES - 1];
        }
        for s in rest {
            *s = convert(self.next_state());
        }
    }
}

/// A run that draws more numbers from a Park–Miller generator than its period
/// ([`ParkMiller::PERIOD`]): from draw `PERIOD + 1` on, the stream repeats its first draws
/// in the same order, so later steps reuse the random numbers of earlier ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PeriodExceeded {
    /// The numbers the run draws.
    pub draws: u64,
    /// The generator's period, `2^31 - 2`.
    pub period: u64,
}

impl PeriodExceeded {
    /// `Some` when `draws` exceeds the period.
    pub fn of(draws: u64) -> Option<PeriodExceeded> {
        (draws > ParkMiller::PERIOD).then_some(PeriodExceeded { draws, period: ParkMiller::PERIOD })
    }
}

impl std::fmt::Display for PeriodExceeded {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the run draws {} numbers from the Park-Miller generator, {:.3} times its period of {}: \
             the random stream repeats, and later steps reuse the numbers of earlier ones \
             (fixed.rng = \"pcg\" has no such limit)",
            self.draws,
            self.draws as f64 / self.period as f64,
            self.period
        )
    }
}

/// Lanes of [`ParkMiller::fill_states`].
pub const LANES: usize = 16;

/// `a^LANES mod m`.
const JUMP_LANES: u32 = ParkMiller::jump(LANES as u64);

/// `s b mod (2^31 - 1)` for `s, b` in `[1, 2^31 - 2]`, without a division: with
/// `p = s b = hi 2^31 + lo` (`lo < 2^31`, `hi < 2^31`), `2^31 = 1 (mod m)` gives
/// `p = hi + lo (mod m)`, and `hi + lo < 2m` needs at most one subtraction of `m`. The result
/// is never 0 (m is prime), so it lies in `[1, m - 1]`: the value of `p % m`.
#[inline(always)]
fn mul_mod(s: u32, b: u32) -> u32 {
    let m = ParkMiller::MODULUS;
    let p = u64::from(s) * u64::from(b);
    let r = (p as u32 & m) + (p >> 31) as u32;
    if r >= m { r - m } else { r }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Park & Miller's published check: from seed 1, the 10,000th value is 1043618065.
    #[test]
    fn minimal_standard_check_value() {
        let mut g = ParkMiller::new(1).unwrap();
        let mut last = 0;
        for _ in 0..10_000 {
            last = g.next_state();
        }
        assert_eq!(last, 1_043_618_065);
    }

    #[test]
    fn first_values_from_seed_one() {
        let mut g = ParkMiller::new(1).unwrap();
        assert_eq!(g.next_state(), 16_807);
        assert_eq!(g.next_state(), 282_475_249);
        assert_eq!(g.next_state(), 1_622_650_073);
    }

    #[test]
    fn jump_multipliers() {
        assert_eq!(ParkMiller::jump(0), 1);
        assert_eq!(ParkMiller::jump(1), ParkMiller::MULTIPLIER);
        // Fermat: a^(m-1) = 1 (mod m).
        assert_eq!(ParkMiller::jump(u64::from(ParkMiller::MODULUS) - 1), 1);
        let mut g = ParkMiller::new(1).unwrap();
        for _ in 0..1000 {
            g.next_state();
        }
        assert_eq!(g.state(), ParkMiller::jump(1000));
    }

    /// Skipping `n` draws lands where `n` single draws do, for every `n` up to a few
    /// hundred and for large ones (against [`ParkMiller::jump`]).
    #[test]
    fn advance_is_that_many_draws() {
        for seed in [1, 2_147_483_646, 987_654_321] {
            let mut one = ParkMiller::new(seed).unwrap();
            for n in 0..300u64 {
                let mut skipped = ParkMiller::new(seed).unwrap();
                skipped.advance(n);
                assert_eq!(skipped, one, "seed {seed}, {n} draws");
                one.next_state();
            }
            for n in [4096u64, 100_000, 1 << 40, u64::from(ParkMiller::MODULUS) - 1] {
                let mut skipped = ParkMiller::new(seed).unwrap();
                skipped.advance(n);
                let want = u64::from(seed as u32) * u64::from(ParkMiller::jump(n)) % u64::from(ParkMiller::MODULUS);
                assert_eq!(u64::from(skipped.state()), want, "seed {seed}, {n} draws");
            }
        }
    }

    #[test]
    fn mul_mod_is_the_remainder() {
        let m = u64::from(ParkMiller::MODULUS);
        let edges = [1u32, 2, 16_807, 1 << 30, (1 << 31) - 3, (1 << 31) - 2];
        let mut g = ParkMiller::new(7).unwrap();
        let mut cases: Vec<(u32, u32)> = edges.iter().flat_map(|&a| edges.iter().map(move |&b| (a, b))).collect();
        cases.extend((0..10_000).map(|_| (g.next_state(), g.next_state())));
        for (a, b) in cases {
            assert_eq!(u64::from(mul_mod(a, b)), u64::from(a) * u64::from(b) % m, "{a} * {b}");
        }
    }

    /// Every length, from every lane offset: the same states as one draw at a time, and the
    /// generator left where the single draws leave it.
    #[test]
    fn filled_states_are_the_sequence() {
        for seed in [1, 2_147_483_646, 123_456_789] {
            for len in (0..3 * LANES + 2).chain([1000, 1001]) {
                let mut one = ParkMiller::new(seed).unwrap();
                let mut many = one.clone();
                let want: Vec<u32> = (0..len).map(|_| one.next_state()).collect();
                let mut got = vec![0; len];
                many.fill_states(&mut got);
                assert_eq!(got, want, "seed {seed}, {len} draws");
                assert_eq!(many, one);
            }
        }
    }

    /// The period is `2^31 - 2`: the state comes back to the seed after exactly that many
    /// draws and not after any proper divisor of it (so no shorter cycle exists).
    #[test]
    fn period_is_two_to_the_31_minus_2() {
        assert_eq!(ParkMiller::PERIOD, 2_147_483_646);
        assert_eq!(ParkMiller::jump(ParkMiller::PERIOD), 1);
        // 2^31 - 2 = 2 3^2 7 11 31 151 331.
        for p in [2u64, 3, 7, 11, 31, 151, 331] {
            assert_ne!(ParkMiller::jump(ParkMiller::PERIOD / p), 1, "a cycle of (2^31 - 2) / {p}");
        }
        assert_eq!(PeriodExceeded::of(ParkMiller::PERIOD), None);
        let over = PeriodExceeded::of(ParkMiller::PERIOD + 1).unwrap();
        assert_eq!((over.draws, over.period), (2_147_483_647, 2_147_483_646));
    }

    #[test]
    fn seeds_outside_the_range_are_refused() {
        assert!(ParkMiller::new(0).is_err());
        assert!(ParkMiller::new(2_147_483_647).is_err());
        assert!(ParkMiller::new(2_147_483_646).is_ok());
    }
}
