//! Regime classification: smooth sliding or stick-slip, from the sampled plate velocity and
//! friction force.
//!
//! Criterion (documented in `docs/model.md`, section Observables): over the output samples
//! inside the averaging window, with `V` the driving velocity,
//!
//! - the plate is *stuck* while `v < STICK * V`;
//! - a *slip* begins when, after being stuck, the plate moves faster than `SLIP * V`; it
//!   lasts until the plate is stuck again (or the window ends);
//! - a slip is *large* when the friction `F = K (V t - X)` falls during it by at least
//!   `DROP` times the friction it had reached (the largest `F` from the start of the stick
//!   to the start of the slip): `F_top - F_bottom >= DROP * F_top`, `F_bottom` the smallest
//!   `F` from the start of the slip to the next stick.
//!
//! The run is **stick-slip** when (a) it has at least `MIN_CYCLES` large slips, (b) at
//! least half of its slips are large, and (c) the plate is stuck in at least
//! `MIN_STUCK_FRACTION` of the window's samples; otherwise it is **smooth**. A scene with
//! `V = 0` is never driven and is classified smooth.
//!
//! Why three conditions: (a) alone (the velocity hysteresis of the first version) calls
//! noise stick-slip whenever the plate's velocity fluctuates by more than `V`, which at low
//! `V` it does at every `V` (below `V0` the linear-law dynamics scale with `V`). (b) asks
//! that the slips carry the friction down (a sawtooth), which a plate ringing against its
//! junctions, with the driving force nearly constant, does not. (c) asks that the plate
//! actually sticks, which noise around a stiff driving spring (large force fluctuations,
//! brief dips of `v`) does not. The criterion sees only the output grid
//! (`output.sample_dt`), which must resolve a slip.

use serde::{Deserialize, Serialize};

use super::{Observer, Sample};

/// Stick threshold as a fraction of the driving velocity.
pub const STICK: f64 = 0.25;
/// Slip threshold as a multiple of the driving velocity.
pub const SLIP: f64 = 2.0;
/// Large slips needed to call a run stick-slip.
pub const MIN_CYCLES: u64 = 2;
/// Relative friction drop that makes a slip large.
pub const DROP: f64 = 0.1;
/// Fraction of window samples the plate must be stuck in.
pub const MIN_STUCK_FRACTION: f64 = 0.1;

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

/// Where the detector is in a stick-slip cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
enum Phase {
    /// Not stuck yet since the window began.
    Free,
    /// Stuck (`v < STICK V` seen, no slip since).
    Stuck,
    /// Slipping (`v > SLIP V` seen after a stick, not stuck again yet).
    Slipping,
}

/// Online stick-slip detector over samples with `t >= t_lo`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RegimeDetector {
    t_lo: f64,
    v_drive: f64,
    phase: Phase,
    /// Largest friction since the current stick began.
    top: f64,
    /// Smallest friction since the current slip began.
    bottom: f64,
    /// Slips begun.
    slips: u64,
    /// Large slips completed (the slip in progress is not included).
    large: u64,
    stuck_samples: u64,
    samples: u64,
}

impl RegimeDetector {
    pub fn new(t_lo: f64, v_drive: f64) -> Self {
        RegimeDetector {
            t_lo,
            v_drive,
            phase: Phase::Free,
            top: f64::NAN,
            bottom: f64::NAN,
            slips: 0,
            large: 0,
            stuck_samples: 0,
            samples: 0,
        }
    }
    fn pending_large(&self) -> bool {
        self.phase == Phase::Slipping && self.top > 0.0 && self.top - self.bottom >= DROP * self.top
    }
    /// Large slips (stick-slip cycles), including a slip still in progress.
    pub fn cycles(&self) -> u64 {
        self.large + u64::from(self.pending_large())
    }
    /// All slips, large or not.
    pub fn slips(&self) -> u64 {
        self.slips
    }
    /// Fraction of window samples with `v < STICK * V`.
    pub fn stuck_fraction(&self) -> f64 {
        if self.samples == 0 { 0.0 } else { self.stuck_samples as f64 / self.samples as f64 }
    }
    pub fn regime(&self) -> Regime {
        let c = self.cycles();
        if self.v_drive > 0.0 && c >= MIN_CYCLES && 2 * c >= self.slips && self.stuck_fraction() >= MIN_STUCK_FRACTION {
            Regime::StickSlip
        } else {
            Regime::Smooth
        }
    }
    /// Feeds one sample: plate velocity `v` and friction `f`.
    pub fn push(&mut self, v: f64, f: f64) {
        self.samples += 1;
        let stuck = v < STICK * self.v_drive;
        if stuck {
            self.stuck_samples += 1;
        }
        match self.phase {
            Phase::Free => {
                if stuck {
                    self.phase = Phase::Stuck;
                    self.top = f;
                }
            }
            Phase::Stuck => {
                self.top = self.top.max(f);
                if v > SLIP * self.v_drive {
                    self.phase = Phase::Slipping;
                    self.bottom = f;
                    self.slips += 1;
                }
            }
            Phase::Slipping => {
                self.bottom = self.bottom.min(f);
                if stuck {
                    self.large += u64::from(self.pending_large());
                    self.phase = Phase::Stuck;
                    self.top = f;
                }
            }
        }
    }
}

impl Observer for RegimeDetector {
    fn sample(&mut self, s: &Sample) {
        if s.t >= self.t_lo {
            self.push(s.v, s.friction);
        }
    }
}

/// Classifies a series of `(velocity, friction)` samples taken at equal intervals.
pub fn classify(samples: &[(f64, f64)], v_drive: f64) -> Regime {
    detector_of(samples, v_drive).regime()
}

/// The detector after feeding it `(velocity, friction)` samples.
pub fn detector_of(samples: &[(f64, f64)], v_drive: f64) -> RegimeDetector {
    let mut d = RegimeDetector::new(f64::NEG_INFINITY, v_drive);
    samples.iter().for_each(|&(v, f)| d.push(v, f));
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sawtooth: stuck (v = 0) for 9 samples while the friction rises by `rise` per
    /// sample from `base`, then one sample of slip at `slip_v` that drops it back.
    fn sawtooth(cycles: usize, base: f64, rise: f64, slip_v: f64) -> Vec<(f64, f64)> {
        (0..10 * cycles)
            .map(|i| {
                let k = i % 10;
                if k == 9 { (slip_v, base) } else { (0.0, base + rise * k as f64) }
            })
            .collect()
    }

    #[test]
    fn sawtooth_is_stick_slip() {
        // Friction rises 10 -> 18 and drops back to 10: a 44% drop at every slip.
        let s = sawtooth(10, 10.0, 1.0, 2.5);
        let d = detector_of(&s, 0.5);
        assert_eq!(d.regime(), Regime::StickSlip);
        assert_eq!(d.slips(), 10);
        assert_eq!(d.cycles(), 10);
        assert!((d.stuck_fraction() - 0.9).abs() < 1e-12);
    }

    #[test]
    fn slips_that_do_not_lower_the_friction_are_not_stick_slip() {
        // The velocity alternates as in a sawtooth but the force varies by 1% (a plate
        // ringing against its junctions under a soft driving spring).
        let s = sawtooth(10, 100.0, 0.1, 2.5);
        let d = detector_of(&s, 0.5);
        assert_eq!(d.slips(), 10);
        assert_eq!(d.cycles(), 0);
        assert_eq!(d.regime(), Regime::Smooth);
    }

    #[test]
    fn occasional_large_drops_among_many_slips_are_not_enough() {
        // 10 slips, 4 of them large: fewer than half.
        let mut s = Vec::new();
        for c in 0..10 {
            let rise = if c < 4 { 1.0 } else { 0.01 };
            s.extend(sawtooth(1, 10.0, rise, 2.5));
        }
        let d = detector_of(&s, 0.5);
        assert_eq!((d.slips(), d.cycles()), (10, 4));
        assert_eq!(d.regime(), Regime::Smooth);
    }

    #[test]
    fn brief_dips_are_not_sticking() {
        // Large force swings, but the plate is stuck in only 1 sample of 20.
        let s: Vec<(f64, f64)> = (0..400)
            .map(|i| match i % 20 {
                0 => (0.0, 20.0),
                1 => (2.5, 10.0),
                _ => (0.5, 15.0),
            })
            .collect();
        let d = detector_of(&s, 0.5);
        assert_eq!(d.cycles(), 20);
        assert!((d.stuck_fraction() - 0.05).abs() < 1e-12);
        assert_eq!(d.regime(), Regime::Smooth);
    }

    #[test]
    fn noisy_sliding_is_smooth() {
        let s: Vec<(f64, f64)> = (0..1000).map(|i| (0.5 + 0.2 * ((i as f64) * 0.7).sin(), 10.0)).collect();
        assert_eq!(classify(&s, 0.5), Regime::Smooth);
    }

    #[test]
    fn one_slip_is_not_enough() {
        let mut s = vec![(0.5, 10.0); 100];
        for x in s.iter_mut().take(30).skip(10) {
            *x = (0.0, 20.0);
        }
        s[30] = (3.0, 5.0);
        let d = detector_of(&s, 0.5);
        assert_eq!(d.cycles(), 1);
        assert_eq!(d.regime(), Regime::Smooth);
        assert_eq!(classify(&[(0.0, 1.0); 10], 0.0), Regime::Smooth);
    }

    #[test]
    fn a_slip_in_progress_at_the_end_counts() {
        // The second slip is the last sample: it is still in progress when the window ends.
        let s = sawtooth(2, 10.0, 1.0, 2.5);
        let d = detector_of(&s, 0.5);
        assert_eq!(d.cycles(), 2);
        assert_eq!(d.regime(), Regime::StickSlip);
    }
}
