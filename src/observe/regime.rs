//! Regime classification: smooth sliding or stick-slip, from the sampled plate velocity.
//!
//! Criterion (documented in `docs/engines.md`): within the averaging window, count
//! stick→slip cycles of the plate velocity `v` with hysteresis: the plate *sticks* when
//! `v < STICK * V` and *slips* when it then rises above `SLIP * V`. The run is stick-slip
//! when it completes at least `MIN_CYCLES` such cycles, smooth otherwise. A scene with
//! `V = 0` is never driven and is classified smooth. The criterion sees the output grid
//! (`output.sample_dt`), so the grid must resolve the slips.

use serde::{Deserialize, Serialize};

use super::{Observer, Sample};

/// Stick threshold as a fraction of the driving velocity.
pub const STICK: f64 = 0.25;
/// Slip threshold as a multiple of the driving velocity.
pub const SLIP: f64 = 2.0;
/// Cycles needed to call a run stick-slip.
pub const MIN_CYCLES: u64 = 2;

/// The friction regime of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Regime {
    Smooth,
    StickSlip,
}

impl Regime {
    pub fn as_str(self) -> &'static str {
        match self {
            Regime::Smooth => "smooth",
            Regime::StickSlip => "stick-slip",
        }
    }
}

/// Online stick-slip detector over samples with `t >= t_lo`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RegimeDetector {
    t_lo: f64,
    v_drive: f64,
    stuck: bool,
    cycles: u64,
    stuck_samples: u64,
    samples: u64,
}

impl RegimeDetector {
    pub fn new(t_lo: f64, v_drive: f64) -> Self {
        RegimeDetector { t_lo, v_drive, stuck: false, cycles: 0, stuck_samples: 0, samples: 0 }
    }
    /// Completed stick→slip cycles.
    pub fn cycles(&self) -> u64 {
        self.cycles
    }
    /// Fraction of window samples with `v < STICK * V`.
    pub fn stuck_fraction(&self) -> f64 {
        if self.samples == 0 { 0.0 } else { self.stuck_samples as f64 / self.samples as f64 }
    }
    pub fn regime(&self) -> Regime {
        if self.v_drive > 0.0 && self.cycles >= MIN_CYCLES { Regime::StickSlip } else { Regime::Smooth }
    }
    /// Feeds one velocity value.
    pub fn push(&mut self, v: f64) {
        self.samples += 1;
        if v < STICK * self.v_drive {
            self.stuck_samples += 1;
            self.stuck = true;
        } else if self.stuck && v > SLIP * self.v_drive {
            self.stuck = false;
            self.cycles += 1;
        }
    }
}

impl Observer for RegimeDetector {
    fn sample(&mut self, s: &Sample) {
        if s.t >= self.t_lo {
            self.push(s.v);
        }
    }
}

/// Classifies a velocity series taken at equal intervals.
pub fn classify(velocities: &[f64], v_drive: f64) -> Regime {
    let mut d = RegimeDetector::new(f64::NEG_INFINITY, v_drive);
    velocities.iter().for_each(|&v| d.push(v));
    d.regime()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sawtooth_velocity_is_stick_slip() {
        // Stuck (v = 0) for 9 samples, then a slip at 5 V, repeated.
        let v: Vec<f64> = (0..100).map(|i| if i % 10 == 9 { 2.5 } else { 0.0 }).collect();
        assert_eq!(classify(&v, 0.5), Regime::StickSlip);
    }

    #[test]
    fn noisy_sliding_is_smooth() {
        let v: Vec<f64> = (0..1000).map(|i| 0.5 + 0.2 * ((i as f64) * 0.7).sin()).collect();
        assert_eq!(classify(&v, 0.5), Regime::Smooth);
    }

    #[test]
    fn one_slip_is_not_enough() {
        let mut v = vec![0.5; 100];
        v[10] = 0.0;
        v[11] = 3.0;
        assert_eq!(classify(&v, 0.5), Regime::Smooth);
        assert_eq!(classify(&[0.0; 10], 0.0), Regime::Smooth);
    }
}
