//! Rupture kinetics of the series engine, chosen once per run.
//!
//! - [`StrongKinetics`]: rate `k0` per attached junction, one channel clock at `k0 N_att`,
//!   uniform picks; nothing happens inside a plate step.
//! - [`WeakKinetics`]: `r_i(s) = k0 exp(beta dx f(y(s) - c_i))` sampled by thinning over
//!   each plate step `[s0, s1]` on which `y_lo <= y <= y_hi` is proven (the integrator's
//!   [`component_bounds`](crate::ode::Rosenbrock::component_bounds), or `V s` for a kinematic
//!   plate). Since `f(x) = kappa (sqrt(x^2 + l0^2) - l0) <= kappa |x|`,
//!   `r_i(s) <= k0 exp(a |y(s) - c_i|) <= b_i = k0 (exp(a (y_hi - c_i)) + exp(a (c_i - y_lo)))`
//!   with `a = beta dx kappa`: the linear law's envelope, kept by [`WeakRupture`]'s sum tree.
//!   Candidates arrive at `B = sum b_i` (constant over the step), pick `i` with
//!   probability `b_i / B` and are accepted with probability `r_i(s) / b_i`
//!   (docs/engines.md, "Plate between events (tilted law): a series, Taylor steps and a stiff integrator").

use rand_distr::{Distribution, Exp1};
use serde::{Deserialize, Serialize, de::DeserializeOwned};

use crate::engine::EngineError;
use crate::engine::exact::bags::Attached;
use crate::engine::exact::rupture::{EXPONENT_CAP, RuptureModel, WeakRupture};
use crate::physics::{ForceLaw, Tilted};
use crate::rng::{Pcg64, UniformSource};

/// Target spread `a (y_hi - y_lo)` of a step (weak bonds): acceptance stays above `e^-1 / 2`.
pub const SPREAD: f64 = 1.0;
/// Largest `a = beta dx kappa` whose spread `SPREAD / a` a step is made to keep.
const A_RESOLVABLE: f64 = 1e12;

/// How attached junctions rupture, for the series engine.
pub trait Kinetics: Clone + std::fmt::Debug + Serialize + DeserializeOwned + Send + 'static {
    /// `true` for force-dependent rates (thinning inside steps).
    const IS_WEAK: bool;
    /// Rate of the rupture channel clock (`k0 N_att` for strong bonds, 0 for weak).
    fn channel_rate(&self, n_att: usize) -> f64;
    /// A junction was attached into `slot` with anchor `c` while the plate is at `y`.
    /// Returns `false` when its rate overflows (it must rupture at once).
    fn attached(&mut self, slot: usize, c: f64, y: f64) -> bool;
    /// The junction in `slot` was removed by `swap_remove` (`last` moved into it).
    fn detached(&mut self, slot: usize, last: usize);
    /// The coordinates were re-based: recompute from `attached`; slots whose rate overflows.
    fn rebuild(&mut self, attached: &[Attached]) -> Vec<usize>;
    /// Whether the frame must be re-based (weights `exp(+-a c)` about to lose range).
    fn needs_rebase(&self, y: f64) -> bool;
    /// The largest plate excursion `y_hi - y_lo` of one step (`+inf`: no limit).
    fn max_spread(&self) -> f64;
    /// Thinning over the step `[s0, s1]` on which `y_lo <= y(s) <= y_hi`; `y_at(s)` is the
    /// plate position. Returns the first accepted candidate `(time, slot)`, if any.
    #[allow(clippy::too_many_arguments)]
    fn thin<F: FnMut(f64) -> Result<f64, EngineError>>(
        &mut self,
        rng: &mut Pcg64,
        span: (f64, f64),
        bounds: (f64, f64),
        attached: &[Attached],
        law: &Tilted,
        y_at: F,
        candidates: &mut u64,
    ) -> Result<Option<(f64, usize)>, EngineError>;
}

/// Strong bonds: constant rate `k0`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrongKinetics {
    pub k0: f64,
}

impl Kinetics for StrongKinetics {
    const IS_WEAK: bool = false;
    #[inline]
    fn channel_rate(&self, n_att: usize) -> f64 {
        self.k0 * n_att as f64
    }
    #[inline]
    fn attached(&mut self, _slot: usize, _c: f64, _y: f64) -> bool {
        true
    }
    #[inline]
    fn detached(&mut self, _slot: usize, _last: usize) {}
    fn rebuild(&mut self, _attached: &[Attached]) -> Vec<usize> {
        Vec::new()
    }
    #[inline]
    fn needs_rebase(&self, _y: f64) -> bool {
        false
    }
    #[inline]
    fn max_spread(&self) -> f64 {
        f64::INFINITY
    }
    #[inline]
    fn thin<F: FnMut(f64) -> Result<f64, EngineError>>(
        &mut self,
        _rng: &mut Pcg64,
        _span: (f64, f64),
        _bounds: (f64, f64),
        _attached: &[Attached],
        _law: &Tilted,
        _y_at: F,
        _candidates: &mut u64,
    ) -> Result<Option<(f64, usize)>, EngineError> {
        Ok(None)
    }
}

/// Weak bonds: thinning against the linear law's envelope ([`WeakRupture`]'s sum tree).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WeakKinetics {
    pub k0: f64,
    /// `beta dx`.
    pub beta_dx: f64,
    envelope: WeakRupture,
}

impl WeakKinetics {
    pub fn new(k0: f64, beta_dx: f64, kappa: f64, n: usize) -> WeakKinetics {
        Self::try_new(k0, beta_dx, kappa, n).unwrap_or_else(|e| panic!("{e}"))
    }
    /// [`WeakKinetics::new`], with the envelope's sum tree reserved fallibly.
    pub fn try_new(
        k0: f64,
        beta_dx: f64,
        kappa: f64,
        n: usize,
    ) -> Result<WeakKinetics, crate::engine::alloc::AllocError> {
        Ok(WeakKinetics { k0, beta_dx, envelope: WeakRupture::try_new(k0, beta_dx * kappa, n)? })
    }
    /// `a = beta dx kappa`.
    #[inline]
    pub fn a(&self) -> f64 {
        self.envelope.a
    }
}

impl Kinetics for WeakKinetics {
    const IS_WEAK: bool = true;
    #[inline]
    fn channel_rate(&self, _n_att: usize) -> f64 {
        0.0
    }
    #[inline]
    fn attached(&mut self, slot: usize, c: f64, y: f64) -> bool {
        self.envelope.attached(slot, c, y)
    }
    #[inline]
    fn detached(&mut self, slot: usize, last: usize) {
        self.envelope.detached(slot, last, None);
    }
    fn rebuild(&mut self, attached: &[Attached]) -> Vec<usize> {
        self.envelope.rebuild(attached)
    }
    #[inline]
    fn needs_rebase(&self, y: f64) -> bool {
        self.envelope.needs_rebase(y, 0.0)
    }
    #[inline]
    fn max_spread(&self) -> f64 {
        // Beyond A_RESOLVABLE no plate step can keep the spread (rates change by e over less
        // than 1e-12 lengths): no limit, and the envelope overflows into immediate ruptures.
        if self.a() > 0.0 && self.a() <= A_RESOLVABLE { SPREAD / self.a() } else { f64::INFINITY }
    }
    fn thin<F: FnMut(f64) -> Result<f64, EngineError>>(
        &mut self,
        rng: &mut Pcg64,
        (s0, s1): (f64, f64),
        (y_lo, y_hi): (f64, f64),
        attached: &[Attached],
        law: &Tilted,
        mut y_at: F,
        candidates: &mut u64,
    ) -> Result<Option<(f64, usize)>, EngineError> {
        let n_att = attached.len();
        if n_att == 0 || self.k0 == 0.0 || s1 <= s0 {
            return Ok(None);
        }
        let rate = self.k0 * self.envelope.envelope(y_lo, y_hi);
        if rate.is_nan() {
            return Err(EngineError::NonFinite { t: s0, quantity: "weak-bond thinning envelope", value: rate });
        }
        if rate == f64::INFINITY {
            // Rates beyond any representable bound within the step: a junction ruptures at
            // once (docs/model.md, "Equations", item 6), one per call, as the linear engine's
            // immediate ruptures.
            *candidates += 1;
            return Ok(Some((s0, n_att - 1)));
        }
        let mut s = s0;
        loop {
            let e: f64 = Exp1.sample(rng);
            s += e / rate;
            if s >= s1 {
                return Ok(None);
            }
            *candidates += 1;
            let (slot, b) = self.envelope.envelope_candidate(rng, n_att);
            // The acceptance `r_i / b_i` is at most 1 only while the plate is within the
            // step's bounds: checked, so that thinning is exact or the run stops.
            let y = y_at(s)?;
            if !(y_lo <= y && y <= y_hi) {
                return Err(EngineError::EnvelopeViolated { t: s, y, lo: y_lo, hi: y_hi });
            }
            let x = y - attached[slot].c;
            // r_i / k0 = exp(beta dx f(x)) <= exp(a |x|) <= b (an overflowing rate is accepted).
            let exponent = self.beta_dx * law.tension(x);
            if exponent > EXPONENT_CAP || rng.uniform() * b < exponent.exp() {
                return Ok(Some((s, slot)));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::pcg;

    /// Thinning with a single junction at a frozen plate reproduces its rate: the number
    /// of accepted events per unit time, over many steps, matches `k0 exp(beta dx f(x))`
    /// within 4 standard deviations of the Poisson count.
    #[test]
    fn thinning_rate_matches_the_tilted_rate() {
        let law = Tilted { kappa: 0.5, l0: 1.0 };
        let mut k = WeakKinetics::new(0.3, 2.0, law.kappa, 4);
        let att = [Attached { c: -0.7, id: 0, bin: 0 }];
        assert!(k.attached(0, att[0].c, 0.0));
        let (y, mut rng, mut cand) = (0.2, pcg(7), 0u64);
        let expected_rate = 0.3 * (2.0 * law.tension(y - att[0].c)).exp();
        let mut count = 0u64;
        let steps = 200_000;
        for i in 0..steps {
            let s0 = i as f64 * 0.05;
            if k.thin(&mut rng, (s0, s0 + 0.05), (y - 0.1, y + 0.3), &att, &law, |_| Ok(y), &mut cand)
                .unwrap()
                .is_some()
            {
                count += 1;
            }
        }
        // At most one event per step: the per-step probability is 1 - exp(-r h).
        let p = 1.0 - (-expected_rate * 0.05).exp();
        let mean = p * steps as f64;
        let sd = (steps as f64 * p * (1.0 - p)).sqrt();
        assert!((count as f64 - mean).abs() < 4.0 * sd, "count {count}, expected {mean} +- {sd}");
        assert!(cand >= count);
    }

    /// A plate outside its step's bounds would make the acceptance exceed 1: the thinning
    /// refuses it rather than sample a wrong law.
    #[test]
    fn a_plate_outside_its_bounds_is_refused() {
        let law = Tilted { kappa: 0.5, l0: 1.0 };
        let mut k = WeakKinetics::new(5.0, 2.0, law.kappa, 4);
        let att = [Attached { c: -0.7, id: 0, bin: 0 }];
        assert!(k.attached(0, att[0].c, 0.0));
        let mut rng = pcg(3);
        let r = k.thin(&mut rng, (0.0, 10.0), (0.0, 0.1), &att, &law, |_| Ok(0.2), &mut 0);
        assert!(matches!(r, Err(EngineError::EnvelopeViolated { .. })), "{r:?}");
    }

    #[test]
    fn strong_kinetics_never_thins() {
        let mut k = StrongKinetics { k0: 0.1 };
        assert_eq!(k.channel_rate(10), 1.0);
        let law = Tilted { kappa: 0.1, l0: 1.0 };
        let r = k.thin(&mut pcg(1), (0.0, 1.0), (0.0, 1.0), &[], &law, |_| Ok(0.0), &mut 0).unwrap();
        assert_eq!(r, None);
    }
}
