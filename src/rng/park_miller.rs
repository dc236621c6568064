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
    fn seeds_outside_the_range_are_refused() {
        assert!(ParkMiller::new(0).is_err());
        assert!(ParkMiller::new(2_147_483_647).is_err());
        assert!(ParkMiller::new(2_147_483_646).is_ok());
    }
}
