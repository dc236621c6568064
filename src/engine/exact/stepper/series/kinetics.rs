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
//!   The acceptance is first squeezed between `max(1, e^{-a l0} lo_i)` and `hi_i`
//!   ([`Bracket`], from the leaf weights), which decides most candidates without the
//!   plate's position, the junction or an exponential, with the same draws.

use rand_distr::{Distribution, Exp1};
use serde::{Deserialize, Serialize, de::DeserializeOwned};

use crate::engine::EngineError;
use crate::engine::exact::core::bags::Attached;
use crate::engine::exact::rupture::{Bracket, EXPONENT_CAP, RuptureModel, WeakRupture};
use crate::physics::{ForceLaw, Tilted};
use crate::rng::{Pcg64, UniformSource};

/// A step's spread: the largest `a (y_hi - y_lo)` (dimensionless, `a = beta dx kappa`) over
/// the plate's range `[y_lo, y_hi]` within one plate step of the tilted law (weak bonds), so
/// a step travels at most `STEP_SPREAD / a` and a candidate's acceptance stays above
/// `e^-1 / 2`. (The linear law's thinning horizon has its own target,
/// [`horizon::SPREAD`](crate::engine::exact::rupture::horizon::SPREAD), over a horizon of its
/// closed-form trajectory.)
pub const STEP_SPREAD: f64 = 1.0;
/// Largest `a = beta dx kappa` whose spread `STEP_SPREAD / a` a step is made to keep.
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
    /// `e^{-a l0}` for the acceptance squeeze (a function of the parameters: not saved).
    #[serde(skip)]
    shrink: Shrink,
}

/// Above this bound of `e^{a |x|}` (`e^{EXPONENT_CAP} / 4`) a candidate is decided by the
/// exact test alone, which accepts an overflowing rate without a uniform.
const SQUEEZE_RATE_MAX: f64 = 9.4e259;

/// `e^{-a l0}`, computed once for the `(a, l0)` it was asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Shrink {
    a: f64,
    l0: f64,
    factor: f64,
}

impl Default for Shrink {
    fn default() -> Self {
        Shrink { a: f64::NAN, l0: f64::NAN, factor: 0.0 }
    }
}

impl Shrink {
    /// `e^{-a l0}` (0, a valid lower factor, for non-finite products).
    #[inline]
    fn factor(&mut self, a: f64, l0: f64) -> f64 {
        if a != self.a || l0 != self.l0 {
            let f = (-a * l0).exp();
            *self = Shrink { a, l0, factor: if f.is_finite() { f } else { 0.0 } };
        }
        self.factor
    }
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
        Ok(WeakKinetics {
            k0,
            beta_dx,
            envelope: WeakRupture::try_new(k0, beta_dx * kappa, n)?,
            shrink: Shrink::default(),
        })
    }
    /// `a = beta dx kappa`.
    #[inline]
    pub fn a(&self) -> f64 {
        self.envelope.a
    }
    /// The anchor of `slot` as its leaf weights give it, `ln(w1) / a` (tests).
    #[cfg(test)]
    fn envelope_anchor(&self, slot: usize) -> f64 {
        self.envelope.anchor_of(slot)
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
        self.envelope.weigh(slot, c, y)
    }
    #[inline]
    fn detached(&mut self, slot: usize, last: usize) {
        self.envelope.unweigh(slot, last);
    }
    fn rebuild(&mut self, attached: &[Attached]) -> Vec<usize> {
        self.envelope.reweigh(attached)
    }
    #[inline]
    fn needs_rebase(&self, y: f64) -> bool {
        self.envelope.needs_rebase(y, 0.0)
    }
    #[inline]
    fn max_spread(&self) -> f64 {
        // Beyond A_RESOLVABLE no plate step can keep the spread (rates change by e over less
        // than 1e-12 lengths): no limit, and the envelope overflows into immediate ruptures.
        if self.a() > 0.0 && self.a() <= A_RESOLVABLE { STEP_SPREAD / self.a() } else { f64::INFINITY }
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
        let shrink = self.shrink.factor(self.a(), law.l0);
        // The acceptance `r_i / b_i` is at most 1 only while the plate is within the step's
        // bounds: checked wherever the position is computed, so that thinning is exact or
        // the run stops.
        let mut position = |s: f64| -> Result<f64, EngineError> {
            let y = y_at(s)?;
            if !(y_lo <= y && y <= y_hi) {
                return Err(EngineError::EnvelopeViolated { t: s, y, lo: y_lo, hi: y_hi });
            }
            Ok(y)
        };
        let mut s = s0;
        loop {
            let e: f64 = Exp1.sample(rng);
            s += e / rate;
            if s >= s1 {
                return Ok(None);
            }
            *candidates += 1;
            let (slot, br) = self.envelope.envelope_candidate(rng, n_att);
            // The junction is read only if the squeeze cannot decide, or by the rupture:
            // start loading it now.
            crate::engine::exact::core::pick::prefetch(&attached[slot]);
            // r_i / k0 = exp(a (l - l0)) with |x| <= l <= |x| + l0, so
            // max(1, e^{-a l0} lo) <= r_i / k0 <= hi: the squeeze decides most candidates
            // without the plate's position, the junction or an exponential, as the exact
            // test `U b < r_i / k0` below would. Below SQUEEZE_RATE_MAX the exponent cannot
            // pass EXPONENT_CAP, so the exact test would draw its uniform anyway: drawn here
            // first, the draws are the same as without the squeeze.
            let ub = if br.hi <= SQUEEZE_RATE_MAX {
                let ub = rng.uniform() * br.b;
                match Bracket::squeeze(ub, (shrink * br.lo).max(1.0), br.hi) {
                    Some(true) => {
                        position(s)?;
                        return Ok(Some((s, slot)));
                    }
                    Some(false) => continue,
                    None => Some(ub),
                }
            } else {
                None
            };
            let x = position(s)? - attached[slot].c;
            // r_i / k0 = exp(beta dx f(x)) <= exp(a |x|) <= b (an overflowing rate is accepted).
            let exponent = self.beta_dx * law.tension(x);
            let accepted = match ub {
                Some(ub) => ub < exponent.exp(),
                None => exponent > EXPONENT_CAP || rng.uniform() * br.b < exponent.exp(),
            };
            if accepted {
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

    /// The squeeze's bracket holds the tilted rate for every plate position within the
    /// bounds: `max(1, e^{-a l0} lo) <= r_i / k0 <= hi <= b` (`a l0` from 0.05 to 5).
    #[test]
    fn bracket_holds_the_tilted_rate() {
        let mut rng = pcg(11);
        for (beta_dx, kappa, l0) in [(1.0, 0.1, 0.5), (2.0, 0.5, 1.0), (1.0, 1.0, 5.0), (0.3, 2.0, 0.2)] {
            let law = Tilted { kappa, l0 };
            let mut k = WeakKinetics::new(1.0, beta_dx, kappa, 64);
            let shrink = (-k.a() * l0).exp();
            for slot in 0..64 {
                assert!(k.attached(slot, (rng.uniform() - 0.5) * 8.0 / k.a(), 0.0));
            }
            for _ in 0..2000 {
                let y_lo = (rng.uniform() - 0.5) * 4.0 / k.a();
                let y_hi = y_lo + rng.uniform() / k.a();
                k.envelope.envelope(y_lo, y_hi);
                let (slot, br) = k.envelope.envelope_candidate(&mut rng, 64);
                let c = k.envelope_anchor(slot);
                for j in 0..=16 {
                    let y = y_lo + (y_hi - y_lo) * j as f64 / 16.0;
                    let r = (beta_dx * law.tension(y - c)).exp();
                    let tol = 1.0 + 1e-12;
                    assert!((shrink * br.lo).max(1.0) <= r * tol, "lo: y {y} c {c} {} > {r}", shrink * br.lo);
                    assert!(r <= br.hi * tol && br.hi <= br.b, "hi: y {y} c {c} {r} {} {}", br.hi, br.b);
                }
            }
        }
    }

    /// The thinning without the squeeze: the plate's position, the junction and an
    /// exponential for every candidate (the oracle of [`squeeze_keeps_every_draw`]).
    #[allow(clippy::too_many_arguments)]
    fn plain_thin(
        k: &mut WeakKinetics,
        rng: &mut Pcg64,
        (s0, s1): (f64, f64),
        (y_lo, y_hi): (f64, f64),
        attached: &[Attached],
        law: &Tilted,
        y_at: impl Fn(f64) -> f64,
    ) -> Option<(f64, usize)> {
        let rate = k.k0 * k.envelope.envelope(y_lo, y_hi);
        let mut s = s0;
        loop {
            let e: f64 = Exp1.sample(rng);
            s += e / rate;
            if s >= s1 {
                return None;
            }
            let (slot, br) = k.envelope.envelope_candidate(rng, attached.len());
            let exponent = k.beta_dx * law.tension(y_at(s) - attached[slot].c);
            if exponent > EXPONENT_CAP || rng.uniform() * br.b < exponent.exp() {
                return Some((s, slot));
            }
        }
    }

    /// The squeeze decides as the exact test would and draws the same numbers: over many
    /// steps, with `a l0` small (most candidates squeezed) and large (many in the band), the
    /// accepted candidates, their times and the generator's state agree bit for bit with
    /// [`plain_thin`].
    #[test]
    fn squeeze_keeps_every_draw() {
        for (beta_dx, kappa, l0) in [(1.0, 0.1, 1.0), (2.0, 1.0, 1.5)] {
            let law = Tilted { kappa, l0 };
            let mut k = WeakKinetics::new(0.5, beta_dx, kappa, 40);
            let mut scene_rng = pcg(5);
            let att: Vec<Attached> = (0..40)
                .map(|i| Attached { c: (scene_rng.uniform() - 0.5) * 6.0 / (beta_dx * kappa), id: i, bin: 0 })
                .collect();
            for (slot, a) in att.iter().enumerate() {
                assert!(k.attached(slot, a.c, 0.0));
            }
            let mut plain = k.clone();
            let (mut r1, mut r2) = (pcg(9), pcg(9));
            let mut events = 0;
            for i in 0..20_000 {
                let (s0, s1) = (i as f64 * 0.1, (i + 1) as f64 * 0.1);
                let y0 = (scene_rng.uniform() - 0.5) * 2.0;
                let (y_lo, y_hi) = (y0, y0 + 0.5 / (beta_dx * kappa));
                let path = |s: f64| y_lo + (y_hi - y_lo) * (s - s0) / (s1 - s0);
                let got = k.thin(&mut r1, (s0, s1), (y_lo, y_hi), &att, &law, |s| Ok(path(s)), &mut 0).unwrap();
                let want = plain_thin(&mut plain, &mut r2, (s0, s1), (y_lo, y_hi), &att, &law, path);
                assert_eq!(got, want, "step {i}");
                events += usize::from(got.is_some());
            }
            assert!(events > 1000, "{events} events");
            assert_eq!(r1.uniform(), r2.uniform(), "the generators have drawn the same numbers");
        }
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
