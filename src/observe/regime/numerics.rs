//! Whether a fixed-step run's numerics failed: the verdict `unstable`, which replaces the
//! physical regime (docs/stability.md, "Unstable runs"). One function decides it,
//! [`NumericsDetector::judge`]; `run`, `sweep`, the Python package and `compare` all read it
//! from the run's summary.
//!
//! A run is **unstable** when its plate step amplifies the plate's oscillation:
//!
//! - **predicted**: the stability analysis ([`crate::engine::fixed::stability::analyse`]) puts the scene's
//!   `dt` at or beyond the limit of its integrator for the most favourable attached count
//!   (verdict `at the limit` or `unstable`: nothing damps the oscillation) and its growth
//!   factor per step exceeds 1 for some attached count; or
//! - **seen**: where the analysis leaves it open (`conditional`: stable for some attached
//!   counts only, or neutral at the limit), the run shows a *locked* period-2 dt
//!   oscillation: the alternating component of the per-step friction,
//!   `a_n = (-1)^n (F_n - 2 F_{n-1} + F_{n-2}) / 4`, keeps one sign for at least
//!   [`LOCK_STEPS`] steps, does not decay over that stretch (the centroid of its energy
//!   `a_n^2` lies at least [`MIN_CENTROID`] of the way along it), and its RMS amplitude over
//!   the stretch is at least [`MIN_NOISE_MULTIPLE`] times the friction fluctuation `sigma_N`
//!   of `N` independent junctions.
//!
//! A step the analysis calls stable for every attached count is never unstable, and the
//! exact engine (no step) has no detector: it is never unstable.

use serde::{Deserialize, Serialize};

use crate::engine::fixed::stability::{self, AT_LIMIT, Verdict};
use crate::scene::{EngineKind, Scene};

/// Steps a period-2 oscillation must stay locked (its alternating component of one sign).
/// A noise-driven, decaying period-2 mode changes its sign every few dozen steps
/// (the letter's Fig. 1 at `dt = 0.95` .. 0.975: 324 .. 80 sign changes in 3000 steps,
/// longest stretch 60 .. 289); a growing or sustained one never does.
pub const LOCK_STEPS: u64 = 64;
/// Where the energy of a locked stretch must lie (0 its start, 1 its end, 1/2 a constant
/// amplitude): not decaying, within the wander of a sustained oscillation's amplitude. A mode
/// decaying by 1 % per step over 64 steps has its energy at 0.38.
pub const MIN_CENTROID: f64 = 0.4;
/// Amplitude a locked oscillation must reach, in units of the independent-junction
/// fluctuation `sigma_N` (the regime criterion's `junction_noise`).
pub const MIN_NOISE_MULTIPLE: f64 = 8.0;

/// Why a run is unstable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Cause {
    /// By the stability analysis alone.
    Predicted,
    /// By the locked period-2 oscillation of the run.
    Seen,
}

impl Cause {
    pub fn as_str(self) -> &'static str {
        match self {
            Cause::Predicted => "predicted",
            Cause::Seen => "seen",
        }
    }
}

/// What `summary.json` reports about a fixed-step run's numerics (`stability`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Numerics {
    /// Growth factor per step of the plate's oscillation with every junction attached
    /// (the largest over attached counts for the integrators here; `compare`'s `plate_growth`).
    /// `None` (absent from `summary.json`, which holds finite numbers only) when it is not a
    /// finite number: plate parameters at the edge of the floating-point range (a subnormal
    /// `plate.mass`) leave it infinite or undefined.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub growth_factor: Option<f64>,
    /// Below this `dt` the plate step is stable for every attached count. `None` (absent
    /// from `summary.json`) when it is not a finite number: the step is stable at every `dt`
    /// (a plate without stiffness, `K + kappa N = 0`, and without mass or damping), or, at
    /// the edge of the floating-point range, the limit is undefined.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub largest_stable_dt: Option<f64>,
    /// Why the run is unstable; absent when it is not.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub unstable: Option<Cause>,
    /// Steps of the strongest locked stretch (the period-2 component of one sign, not
    /// decaying), or of the longest stretch of one sign when none is locked.
    pub locked_steps: u64,
    /// RMS amplitude (force) of the period-2 component over that stretch. `None` (absent
    /// from `summary.json`) when it is not a finite number: its squares overflow the
    /// floating-point range (forces beyond about `1e154`).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub locked_amplitude: Option<f64>,
}

/// The analysis's side of the verdict, fixed by the scene.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct Prediction {
    growth_factor: f64,
    largest_stable_dt: f64,
    /// At or beyond the limit for the most favourable attached count, growing for some.
    unstable: bool,
    /// The analysis leaves it open: the run decides.
    open: bool,
}

/// A stretch of steps over which the period-2 component kept one sign.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
struct Stretch {
    len: u64,
    /// `sum a_k^2` and `sum k a_k^2` over its values, `k = 0, 1, ..` from its start.
    energy: f64,
    moment: f64,
}

impl Stretch {
    fn push(&mut self, a2: f64) {
        self.energy += a2;
        self.moment += self.len as f64 * a2;
        self.len += 1;
    }
    /// RMS amplitude over the stretch.
    fn amplitude(&self) -> f64 {
        if self.len == 0 { 0.0 } else { (self.energy / self.len as f64).sqrt() }
    }
    /// Where its energy lies, from 0 (all at the start) to 1 (all at the end): 1/2 for a
    /// constant amplitude, less for a decaying one.
    fn centroid(&self) -> f64 {
        if self.len < 2 || self.energy <= 0.0 { 0.0 } else { self.moment / self.energy / (self.len - 1) as f64 }
    }
    /// Long enough and not decaying.
    fn locked(&self) -> bool {
        self.len >= LOCK_STEPS && self.centroid() >= MIN_CENTROID
    }
}

/// Follows the period-2 dt component of the per-step friction of a fixed-step run (fed by
/// the engine's one segment per step) and holds the analysis's prediction. Bounded state;
/// part of a checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NumericsDetector {
    prediction: Prediction,
    /// `F_{n-1}`, `F_{n-2}` and the steps seen.
    last: [f64; 2],
    steps: u64,
    /// Sign of the current stretch (`0.0` before the first `a_n`).
    sign: f64,
    current: Stretch,
    /// The locked stretch with the largest amplitude so far, and the longest stretch.
    best: Option<Stretch>,
    longest: Stretch,
}

impl NumericsDetector {
    /// The detector of a fixed-step scene with a plate equation; `None` for the exact engine
    /// and for a kinematic plate (no plate step to fail).
    pub fn for_scene(scene: &Scene) -> Option<Self> {
        if scene.run.engine != EngineKind::Fixed || scene.plate.kinematic {
            return None;
        }
        let a = stability::analyse(scene);
        let r = a.selected();
        let growth_factor = r.radius_all.max(r.radius_none);
        let beyond = matches!(r.verdict, Verdict::Unstable | Verdict::AtLimit);
        let prediction = Prediction {
            growth_factor,
            largest_stable_dt: r.dt_stable,
            unstable: beyond && growth_factor > 1.0 + AT_LIMIT,
            open: r.verdict != Verdict::Stable,
        };
        Some(NumericsDetector {
            prediction,
            last: [0.0; 2],
            steps: 0,
            sign: 0.0,
            current: Stretch::default(),
            best: None,
            longest: Stretch::default(),
        })
    }

    /// Feeds the friction `F_n` at the start of step `n` (steps in order).
    pub fn step(&mut self, friction: f64) {
        if self.steps >= 2 {
            let d2 = friction - 2.0 * self.last[0] + self.last[1];
            let a = if self.steps % 2 == 0 { d2 } else { -d2 } / 4.0;
            let sign = if a > 0.0 {
                1.0
            } else if a < 0.0 {
                -1.0
            } else {
                0.0
            };
            if sign != self.sign || sign == 0.0 {
                self.close();
                self.sign = sign;
            }
            if sign != 0.0 && a.is_finite() {
                self.current.push(a * a);
            }
        }
        self.last = [friction, self.last[0]];
        self.steps += 1;
    }

    /// Ends the current stretch.
    fn close(&mut self) {
        let s = std::mem::take(&mut self.current);
        self.keep(s);
    }

    fn keep(&mut self, s: Stretch) {
        if s.len > self.longest.len {
            self.longest = s;
        }
        if s.locked() && self.best.is_none_or(|b| s.amplitude() > b.amplitude()) {
            self.best = Some(s);
        }
    }

    /// THE verdict: whether the run is unstable, and what `summary.json` reports, given the
    /// independent-junction fluctuation `sigma_N` of the run (`junction_noise`).
    pub fn judge(&self, junction_noise: f64) -> Numerics {
        // The stretch still open at the end counts as closed there.
        let mut d = self.clone();
        d.close();
        let p = self.prediction;
        let seen = d.best.filter(|s| s.amplitude() >= MIN_NOISE_MULTIPLE * junction_noise);
        let unstable = if p.unstable {
            Some(Cause::Predicted)
        } else if p.open && seen.is_some() {
            Some(Cause::Seen)
        } else {
            None
        };
        let shown = seen.or(d.best).unwrap_or(d.longest);
        Numerics {
            growth_factor: Some(p.growth_factor).filter(|g| g.is_finite()),
            largest_stable_dt: Some(p.largest_stable_dt).filter(|dt| dt.is_finite()),
            unstable,
            locked_steps: shown.len,
            locked_amplitude: Some(shown.amplitude()).filter(|a| a.is_finite()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes::fig1_with;

    fn detector(overrides: &[&str]) -> NumericsDetector {
        NumericsDetector::for_scene(&fig1_with(overrides)).expect("a fixed-step scene")
    }

    fn feed(d: &mut NumericsDetector, f: impl Iterator<Item = f64>) {
        for x in f {
            d.step(x);
        }
    }

    /// A tiny deterministic generator for the noise of the synthetic traces.
    fn noise(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            // Sum of 4 uniforms, centred: close enough to Gaussian, variance 1/3.
            (0..4).map(|k| ((s.rotate_left(16 * k) >> 11) as f64 / (1u64 << 53) as f64) - 0.5).sum::<f64>()
        }
    }

    #[test]
    fn the_analysis_decides_outside_its_open_range() {
        // fig1: stable below 0.9399 for every attached count, at the limit at dt = 1.
        let d = detector(&[]);
        assert!(d.prediction.unstable && d.prediction.open);
        assert!((d.prediction.growth_factor - 1.4).abs() < 1e-12);
        assert_eq!(d.judge(1.0).unstable, Some(Cause::Predicted));
        for dt in ["fixed.dt=0.93", "fixed.dt=0.5"] {
            let mut d = detector(&[dt]);
            assert!(!d.prediction.unstable && !d.prediction.open);
            // Even a growing period-2 oscillation does not overrule "stable".
            feed(&mut d, (0..500).map(|n| if n % 2 == 0 { 1.01f64.powi(n) } else { -(1.01f64.powi(n)) }));
            assert_eq!(d.judge(0.0).unstable, None);
        }
        let d = detector(&["fixed.dt=0.95"]);
        assert!(!d.prediction.unstable && d.prediction.open);
        assert_eq!(d.judge(0.0).unstable, None, "nothing seen yet");
        assert!(NumericsDetector::for_scene(&fig1_with(&["run.engine=exact"])).is_none());
        assert!(NumericsDetector::for_scene(&fig1_with(&["plate.kinematic=true"])).is_none());
    }

    #[test]
    fn a_growing_or_sustained_period_two_oscillation_is_seen() {
        for growth in [1.05f64, 1.0] {
            let mut d = detector(&["fixed.dt=0.99"]);
            let mut e = noise(7);
            // Drift, noise of size 1 and a period-2 mode from amplitude 1 (growing) or 20.
            let start = if growth > 1.0 { 1.0 } else { 20.0 };
            let alternate = |n: i32| if n % 2 == 0 { 1.0 } else { -1.0 };
            feed(&mut d, (0..200).map(|n| 3.0 * f64::from(n) + e() + start * growth.powi(n).min(1e3) * alternate(n)));
            let v = d.judge(1.0);
            assert_eq!(v.unstable, Some(Cause::Seen), "growth {growth}: {v:?}");
            assert!(v.locked_steps >= 150, "{v:?}");
            // Too small against the junctions' noise: not the scheme's.
            assert_eq!(d.judge(v.locked_amplitude.unwrap()).unstable, None);
        }
    }

    #[test]
    fn a_decaying_kick_and_noise_are_not_seen() {
        let mut e = noise(3);
        // The start-up kick of a stable step decaying by 2 % per step, then noise through a
        // period-2 mode decaying by 5 % per step.
        let mut d = detector(&["fixed.dt=0.96"]);
        let mut mode = 0.0;
        feed(
            &mut d,
            (0..20000).map(|n| {
                mode = -0.95 * mode + e();
                let kick = 40.0 * 0.98f64.powi(n) * if n % 2 == 0 { 1.0 } else { -1.0 };
                0.5 * n as f64 + kick + mode
            }),
        );
        // sigma_N of the order of the mode's own standard deviation (1.85), as in runs.
        let v = d.judge(2.0);
        assert_eq!(v.unstable, None, "{v:?}");
        assert!(v.locked_steps < 20000);
    }
}
