//! Regime classification: smooth sliding or stick-slip (an oscillation of the friction,
//! sawtooth or relaxation), from the friction `F = K (V t - X)` sampled on the output grid
//! inside the averaging window. The criterion and the derivation of every threshold are in
//! `docs/model.md` ("Regime criterion"); in short, a run is **stick-slip** when
//!
//! 1. **periodic**: the autocorrelation of `F` has a period `P` ([`autocorr::period`]), at
//!    least [`MIN_PERIODS`] whole periods fit in the window, and the coherence
//!    `rho(P) >= MIN_COHERENCE`: the part of `F` that repeats after one period carries at
//!    least half its variance;
//! 2. **regular**: the peak-to-trough ranges `R_k` of `F` over consecutive periods are too
//!    regular for noise. The fluctuations of `N` junctions around steady sliding are
//!    Gaussian (central limit theorem) and reach the friction through the plate, a damped
//!    oscillator; for such a process with `rho(P) >= 1/2` the ranges have a coefficient of
//!    variation of at least [`NULL_CV`] (0.42; Rayleigh's 0.52 in the narrow-band limit). The
//!    observed `cv = sd(R_k) / mean(R_k)` must lie below it by `Z` standard errors,
//!    `cv < NULL_CV - Z s`, `s = NULL_CV sqrt(NULL_CV^2 + 1/2) / sqrt(K_eff)`,
//!    `K_eff = K (1 - r1) / (1 + r1)` with `K` periods and `r1` the lag-1 correlation of
//!    the `R_k`: a one-sided test of the Gaussian null at level `ALPHA` (ranges equal to
//!    within the grid's [`resolution`] are regular whatever `K_eff`). A limit cycle has
//!    `cv ~ 1 / (A sqrt(N))`, so it passes for large enough `N`, and noise does not, however
//!    close to an instability (where its coherence approaches 1);
//! 3. **collective**: the amplitude `A = mean(R_k) / 2` is at least `sqrt(2)` times the
//!    friction fluctuation that `N` independent junctions would cause,
//!    `sigma_N = F_b sqrt((1 - n) / (n N))` (binomial fluctuation of the attached count,
//!    each junction carrying the mean attached force): the oscillation's variance
//!    (`A^2 / 2` for a sine) exceeds independent-junction noise.
//!
//! The plate's velocity hysteresis of the first version (stuck while `v < V/4`, a slip when
//! it then exceeds `2 V`, [`slips`]) is reported as a supporting sign (`stuck_fraction`,
//! `slips`): a sawtooth sticks, a relaxation oscillation need not. A scene with `V = 0` is
//! smooth.
//!
//! A fixed-step run whose plate step failed (predicted by the stability analysis, or seen as
//! a locked period-2 dt oscillation, [`numerics`]) is **unstable** instead: no physical
//! regime is given to it.
//!
//! Memory: the detector keeps a bounded, decimating record of `F` ([`buffer`], at most
//! [`buffer::CAPACITY`] buckets) and a few counters, whatever `t_end`; its state serialises
//! (it is part of a checkpoint). The analysis runs once, at the end ([`RegimeDetector::verdict`]).

pub mod autocorr;
pub mod buffer;
pub mod numerics;
pub mod slips;

use serde::{Deserialize, Serialize};

use super::observer::Observer;
use super::piece::Piece;
use super::report::{Sample, Segment};
use crate::scene::Scene;
use buffer::Decimator;
use numerics::{Numerics, NumericsDetector};
use slips::SlipCounter;

/// Coherence `rho(P)` needed: the periodic part carries at least half the variance
/// (`var p / (var p + var e) >= 1/2`).
pub const MIN_COHERENCE: f64 = 0.5;
/// Whole periods needed in the window (the autocorrelation is searched up to a quarter of
/// the window).
pub const MIN_PERIODS: usize = 4;
/// Smallest coefficient of variation of the per-period range of a stationary Gaussian
/// damped oscillation (`x'' + 2 gamma x' + w0^2 x` driven by white noise) with
/// `rho(P) >= 1/2`: reached at `rho(P) = 1/2`, where it is 0.431 +- 0.005 (rounded down
/// here), rising towards Rayleigh's 0.52 as `rho(P) -> 1`. Measured by the test
/// `null_cv_of_gaussian_damped_oscillations` (docs/model.md, "Regime criterion").
pub const NULL_CV: f64 = 0.42;
/// Level of the test of the Gaussian null: the suite's `ALPHA`, one-sided.
pub const ALPHA: f64 = 1e-3;
/// `z_{1 - ALPHA}` of the standard normal.
pub const Z: f64 = 3.090_232_306_167_813;
/// Amplitude needed, in units of the independent-junction fluctuation `sigma_N`.
pub const MIN_COLLECTIVE: f64 = std::f64::consts::SQRT_2;

/// The friction regime of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Regime {
    Smooth,
    StickSlip,
    /// The fixed-step scheme's plate step failed: no physical regime ([`numerics`]).
    Unstable,
}

impl Regime {
    pub fn as_str(self) -> &'static str {
        match self {
            Regime::Smooth => "smooth",
            Regime::StickSlip => "stick-slip",
            Regime::Unstable => "unstable",
        }
    }
}

/// What the detector measured over the window (reported in `summary.json`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Oscillation {
    /// Period `P` of the friction's oscillation (time), if its autocorrelation has one.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub oscillation_period: Option<f64>,
    /// Half the mean peak-to-trough range of `F` over whole periods (force); 0 without a
    /// period.
    pub oscillation_amplitude: f64,
    /// `rho(P)`, the fraction of the variance of `F` that repeats after one period; 0
    /// without a period.
    pub oscillation_coherence: f64,
    /// Coefficient of variation of the per-period ranges, and the limit it must stay below.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub amplitude_cv: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub amplitude_cv_limit: Option<f64>,
    /// `sigma_N`: the friction fluctuation of `N` independent junctions (force).
    pub junction_noise: f64,
    /// Supporting sign: fraction of window samples with `v < V/4`.
    pub stuck_fraction: f64,
    /// Supporting sign: slips (a stick followed by `v > 2 V`).
    pub slips: u64,
}

/// The detector's conclusion.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    pub regime: Regime,
    /// Whole periods in the window when stick-slip, else 0.
    pub cycles: u64,
    pub oscillation: Oscillation,
    /// A fixed-step run's numerics (`None` for the exact engine and a kinematic plate).
    pub numerics: Option<Numerics>,
}

/// Online regime detector over samples with `t >= t_lo`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegimeDetector {
    t_lo: f64,
    v_drive: f64,
    /// Number of junctions `N`.
    n: u64,
    friction: Decimator,
    slips: SlipCounter,
    samples: u64,
    /// Times of the first two samples (their difference is the sample spacing).
    t_first: f64,
    t_second: f64,
    /// Sums over samples of `F_b` and of the attached count.
    bond_sum: f64,
    attached_sum: f64,
    /// The plate step's verdict (fixed-step scenes with a plate equation only).
    numerics: Option<NumericsDetector>,
}

impl RegimeDetector {
    /// A detector for samples at `t >= t_lo` of a plate driven at `v_drive` by `n` junctions.
    pub fn new(t_lo: f64, v_drive: f64, n: u64) -> Self {
        RegimeDetector {
            t_lo,
            v_drive,
            n,
            friction: Decimator::new(),
            slips: SlipCounter::new(v_drive),
            samples: 0,
            t_first: f64::NAN,
            t_second: f64::NAN,
            bond_sum: 0.0,
            attached_sum: 0.0,
            numerics: None,
        }
    }

    /// The detector of a scene: its averaging window, driving velocity and `N`, and for a
    /// fixed-step scene the plate step's verdict.
    pub fn for_scene(scene: &Scene) -> Self {
        RegimeDetector {
            numerics: NumericsDetector::for_scene(scene),
            ..RegimeDetector::new(scene.run.t_warmup, scene.plate.v, scene.junctions.n as u64)
        }
    }

    /// Feeds one sample (whatever its time).
    pub fn push(&mut self, s: &Sample) {
        match self.samples {
            0 => self.t_first = s.t,
            1 => self.t_second = s.t,
            _ => {}
        }
        self.samples += 1;
        self.friction.push(s.friction);
        self.slips.push(s.v);
        self.bond_sum += s.bond_force;
        self.attached_sum += s.attached as f64;
    }

    /// Samples fed so far.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// `sigma_N = F_b sqrt((1 - n) / (n N))` from the sample means of `F_b` and `n`; 0 with
    /// no sample or no junction attached on average.
    fn junction_noise(&self) -> f64 {
        if self.samples == 0 || self.n == 0 {
            return 0.0;
        }
        let n = self.n as f64;
        let attached = self.attached_sum / self.samples as f64 / n;
        let bond = self.bond_sum / self.samples as f64;
        if attached > 0.0 { bond.abs() * ((1.0 - attached) / (attached * n)).sqrt() } else { 0.0 }
    }

    /// The analysis of everything fed so far: the physical regime, unless the plate step
    /// failed ([`numerics::NumericsDetector::judge`]).
    pub fn verdict(&self) -> Verdict {
        let mut v = self.physical();
        v.numerics = self.numerics.as_ref().map(|d| d.judge(v.oscillation.junction_noise));
        if v.numerics.as_ref().is_some_and(|n| n.unstable.is_some()) {
            v.regime = Regime::Unstable;
            v.cycles = 0;
        }
        v
    }

    /// The regime criterion on the trace alone.
    fn physical(&self) -> Verdict {
        let mut o = Oscillation {
            junction_noise: self.junction_noise(),
            stuck_fraction: self.slips.stuck_fraction(),
            slips: self.slips.slips(),
            ..Oscillation::default()
        };
        let smooth = |o: Oscillation| Verdict { regime: Regime::Smooth, cycles: 0, oscillation: o, numerics: None };
        let buckets = self.friction.buckets();
        let spacing = self.t_second - self.t_first;
        if buckets.len() < 2 * MIN_PERIODS || spacing.is_nan() || spacing <= 0.0 {
            return smooth(o);
        }
        let means: Vec<f64> = buckets.iter().map(|b| b.0).collect();
        let rho = autocorr::autocorrelation(&means, buckets.len() / MIN_PERIODS);
        let Some((lag, coherence)) = autocorr::period(&rho) else { return smooth(o) };
        let Some((amplitude, ranges)) = autocorr::half_range(buckets, lag) else { return smooth(o) };
        o.oscillation_period = Some(lag * spacing * self.friction.stride() as f64);
        o.oscillation_amplitude = amplitude;
        o.oscillation_coherence = coherence;
        let (cv, limit) = regularity(&ranges);
        o.amplitude_cv = cv;
        o.amplitude_cv_limit = limit;
        let periodic = ranges.len() >= MIN_PERIODS && coherence >= MIN_COHERENCE;
        let regular = match cv {
            Some(c) => c <= resolution(lag) || limit.is_some_and(|l| c < l),
            None => false,
        };
        let collective = amplitude > 0.0 && amplitude >= MIN_COLLECTIVE * o.junction_noise;
        if self.v_drive > 0.0 && periodic && regular && collective {
            Verdict { regime: Regime::StickSlip, cycles: ranges.len() as u64, oscillation: o, numerics: None }
        } else {
            smooth(o)
        }
    }

    /// The regime of everything fed so far.
    pub fn regime(&self) -> Regime {
        self.verdict().regime
    }
}

/// The relative resolution of a per-period range measured on buckets, for a period of `p`
/// buckets: a sampled extreme of a sine of amplitude `A` misses the true one by at most
/// `A (1 - cos(pi / p)) <= A (pi/p)^2 / 2`, so a range `2 A` is known to `(pi/p)^2 / 2` of
/// itself. Ranges whose spread is below this are equal as far as the record can tell (a
/// deterministic cycle sampled on a grid that beats with it).
pub fn resolution(p: f64) -> f64 {
    0.5 * (std::f64::consts::PI / p).powi(2)
}

/// The coefficient of variation of the per-period ranges and the limit of the Gaussian
/// null, `NULL_CV - Z s` with `s = NULL_CV sqrt(NULL_CV^2 + 1/2) / sqrt(K_eff)` (McKay's
/// standard error of a sample CV) and `K_eff = K (1 - r1) / (1 + r1)`, `r1 >= 0` the lag-1
/// correlation of the ranges. `None` for fewer than 3 ranges or ranges with a zero mean;
/// no limit when `K_eff = 0` (ranges perfectly correlated: nothing can be tested).
pub fn regularity(ranges: &[f64]) -> (Option<f64>, Option<f64>) {
    if ranges.len() < 3 {
        return (None, None);
    }
    let k = ranges.len() as f64;
    let mean = ranges.iter().sum::<f64>() / k;
    if mean.is_nan() || mean <= 0.0 {
        return (None, None);
    }
    let var = ranges.iter().map(|r| (r - mean) * (r - mean)).sum::<f64>() / k;
    let r1 = if var > 0.0 {
        (ranges.windows(2).map(|w| (w[0] - mean) * (w[1] - mean)).sum::<f64>() / k / var).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let k_eff = k * (1.0 - r1) / (1.0 + r1);
    let s = NULL_CV * (NULL_CV * NULL_CV + 0.5).sqrt() / k_eff.sqrt();
    let limit = NULL_CV - Z * s;
    (Some(var.sqrt() / mean), limit.is_finite().then_some(limit))
}

/// Stretches come from exact engines, which have no plate step to judge (a stretch is
/// taken and ignored).
impl Observer for RegimeDetector {
    const STRETCHES: bool = true;
    /// The fixed-step engine reports one segment per step, starting at `F_n`.
    #[inline]
    fn segment(&mut self, s: &Segment) {
        if let Some(d) = &mut self.numerics {
            d.step(s.friction);
        }
    }
    /// Pieces come from exact engines, which have no plate step to judge.
    #[inline]
    fn piece(&mut self, p: &Piece) {
        if let Some(d) = &mut self.numerics {
            d.step(p.segment().friction);
        }
    }
    /// Only the plate step's verdict reads integrals.
    #[inline]
    fn integrals_after(&self) -> f64 {
        if self.numerics.is_some() { f64::NEG_INFINITY } else { f64::INFINITY }
    }
    fn sample(&mut self, s: &Sample) {
        if s.t >= self.t_lo {
            self.push(s);
        }
    }
}

#[cfg(test)]
mod tests;
