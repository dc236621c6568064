//! The plate's velocity hysteresis, a supporting sign of stick-slip: stuck while
//! `v < STICK V`, a slip when, after being stuck, the plate moves faster than `SLIP V`.

use serde::{Deserialize, Serialize};

/// Stuck threshold as a fraction of the driving velocity.
pub const STICK: f64 = 0.25;
/// Slip threshold as a multiple of the driving velocity.
pub const SLIP: f64 = 2.0;

/// Where the plate is in a stick-slip cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
enum Phase {
    /// Not stuck yet since the window began.
    Free,
    /// Stuck (`v < STICK V` seen, no slip since).
    Stuck,
    /// Slipping (`v > SLIP V` seen after a stick, not stuck again yet).
    Slipping,
}

/// Counts sticks and slips online.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SlipCounter {
    v_drive: f64,
    phase: Phase,
    /// Slips begun.
    slips: u64,
    stuck_samples: u64,
    samples: u64,
}

impl SlipCounter {
    pub fn new(v_drive: f64) -> Self {
        SlipCounter { v_drive, phase: Phase::Free, slips: 0, stuck_samples: 0, samples: 0 }
    }
    /// Feeds the plate velocity of one sample.
    pub fn push(&mut self, v: f64) {
        self.samples += 1;
        let stuck = v < STICK * self.v_drive;
        self.stuck_samples += u64::from(stuck);
        self.phase = match self.phase {
            Phase::Free | Phase::Slipping if stuck => Phase::Stuck,
            Phase::Stuck if v > SLIP * self.v_drive => {
                self.slips += 1;
                Phase::Slipping
            }
            p => p,
        };
    }
    /// Slips begun (a stick followed by `v > SLIP V`).
    pub fn slips(&self) -> u64 {
        self.slips
    }
    /// Fraction of samples with `v < STICK V` (0 with no samples).
    pub fn stuck_fraction(&self) -> f64 {
        if self.samples == 0 { 0.0 } else { self.stuck_samples as f64 / self.samples as f64 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_slips_after_sticks_only() {
        let mut c = SlipCounter::new(1.0);
        // fast (free), stuck, fast = slip, medium, stuck, fast = slip, fast (same slip)
        for v in [3.0, 0.1, 2.5, 1.0, 0.0, 2.1, 3.0] {
            c.push(v);
        }
        assert_eq!(c.slips(), 2);
        assert!((c.stuck_fraction() - 2.0 / 7.0).abs() < 1e-15);
        assert_eq!(SlipCounter::new(1.0).stuck_fraction(), 0.0);
    }
}
