//! Flip rules of the fixed-step scheme (docs/engines.md, "The fixed-step engine", step 1).
//!
//! A junction whose rate is `k` flips in a step of size `dt` when its uniform `xi` in
//! `(0, 1)` passes a test against `k dt`. Each rule splits the test into a per-rate
//! [`Flip::threshold`] (computed once per step for rates shared by many junctions) and a
//! cheap per-junction comparison [`Flip::flips`].

use serde::{Deserialize, Serialize};

use crate::rng::UniformSource;
use crate::scene::FlipRule;

/// A flip rule, chosen once per run (a type parameter of the engine).
pub trait Flip: Copy + Send + Sync + std::fmt::Debug + Serialize + serde::de::DeserializeOwned + 'static {
    /// Which scene option this is.
    const RULE: FlipRule;
    /// The threshold the uniform is compared with, from `k dt >= 0` (`+inf` allowed).
    fn threshold(k_dt: f64) -> f64;
    /// Whether a junction with uniform `xi` flips against `threshold`.
    fn flips(xi: f64, threshold: f64) -> bool;
    /// The threshold on a generator's raw draws that flips the same draws as `threshold`
    /// does on their uniforms: `flips(r, raw_threshold::<R>(th)) == flips(R::to_uniform(r),
    /// th)` for every raw draw `r` of `R` ([`UniformSource::raws`]). Exact (no rounding
    /// argument): `flips` is monotone in `xi` and `to_uniform` non-decreasing, so the
    /// draws that flip are those below (or above) one raw value, found by bisection.
    #[inline]
    fn raw_threshold<R: UniformSource>(threshold: f64) -> f64 {
        if !R::has_raw_scale() {
            return threshold;
        }
        match Self::RULE {
            // `xi > th`: the draws that do not flip are those below the cut; a raw draw
            // (an integer) flips iff it exceeds `cut - 1`.
            FlipRule::AsPrinted => R::raw_partition(|u| !Self::flips(u, threshold)) - 1.0,
            // `xi < th`: the draws that flip are those below the cut.
            _ => R::raw_partition(|u| Self::flips(u, threshold)),
        }
    }
    /// The one-step flip probability `P(flips(xi, threshold(k dt)))` for `xi ~ U(0, 1)`.
    #[inline]
    fn probability(k_dt: f64) -> f64 {
        let th = Self::threshold(k_dt);
        match Self::RULE {
            FlipRule::AsPrinted => (1.0 - th).clamp(0.0, 1.0),
            _ => th.clamp(0.0, 1.0),
        }
    }
}

/// `linear` (the default): flip when `xi < min(1, k dt)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LinearFlip;

impl Flip for LinearFlip {
    const RULE: FlipRule = FlipRule::Linear;
    /// `min(1, k dt)`.
    #[inline]
    fn threshold(k_dt: f64) -> f64 {
        k_dt.min(1.0)
    }
    /// `xi < min(1, k dt)`.
    #[inline]
    fn flips(xi: f64, threshold: f64) -> bool {
        xi < threshold
    }
}

/// `exponential`: flip when `xi < 1 - exp(-k dt)`, the exact one-step probability of a
/// frozen rate, evaluated as `-expm1(-k dt)` (accurate for small `k dt`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ExponentialFlip;

impl Flip for ExponentialFlip {
    const RULE: FlipRule = FlipRule::Exponential;
    /// `1 - exp(-k dt) = -expm1(-k dt)`; `k dt = +inf` gives 1.
    #[inline]
    fn threshold(k_dt: f64) -> f64 {
        -(-k_dt).exp_m1()
    }
    /// `xi < 1 - exp(-k dt)`.
    #[inline]
    fn flips(xi: f64, threshold: f64) -> bool {
        xi < threshold
    }
}

/// `as-printed`: flip when `xi > k dt`, the letter's `theta(xi - dt k)` taken literally.
/// It flips with probability `1 - k dt` (most junctions, every step); it exists only to
/// show what the printed formula does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct AsPrintedFlip;

impl Flip for AsPrintedFlip {
    const RULE: FlipRule = FlipRule::AsPrinted;
    /// `k dt`.
    #[inline]
    fn threshold(k_dt: f64) -> f64 {
        k_dt
    }
    /// `xi > k dt`.
    #[inline]
    fn flips(xi: f64, threshold: f64) -> bool {
        xi > threshold
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_rule() {
        assert!(LinearFlip::flips(0.29, LinearFlip::threshold(0.3)));
        assert!(!LinearFlip::flips(0.31, LinearFlip::threshold(0.3)));
        assert_eq!(LinearFlip::threshold(5.0), 1.0);
        assert!(LinearFlip::flips(1.0 - 1e-16, LinearFlip::threshold(f64::INFINITY)));
        assert!(!LinearFlip::flips(1e-300, LinearFlip::threshold(0.0)));
        assert_eq!(LinearFlip::probability(0.25), 0.25);
        assert_eq!(LinearFlip::probability(3.0), 1.0);
    }

    #[test]
    fn exponential_rule() {
        let th = ExponentialFlip::threshold(0.5);
        assert!((th - (1.0 - (-0.5f64).exp())).abs() < 1e-16);
        // expm1 keeps full relative accuracy where 1 - exp(-x) would cancel.
        assert!((ExponentialFlip::threshold(1e-12) / 1e-12 - 1.0).abs() < 1e-12);
        assert_eq!(ExponentialFlip::threshold(f64::INFINITY), 1.0);
        assert_eq!(ExponentialFlip::threshold(0.0), 0.0);
        assert!(ExponentialFlip::flips(0.39, th) && !ExponentialFlip::flips(0.40, th));
    }

    /// Park-Miller: every state flips against the raw threshold exactly when its uniform
    /// flips against the threshold, checked at the states around each cut.
    #[test]
    fn raw_thresholds_flip_the_same_draws() {
        use crate::rng::ParkMiller;
        fn check<F: Flip>(k_dt: f64) {
            let th = F::threshold(k_dt);
            let raw = F::raw_threshold::<ParkMiller>(th);
            let m = f64::from(ParkMiller::MODULUS);
            let near = (raw.max(1.0) - 3.0).max(1.0);
            let states = (0..8).map(|i| near + f64::from(i)).chain([1.0, 2.0, m - 2.0, m - 1.0]);
            for r in states.filter(|&r| (1.0..m).contains(&r)) {
                let want = F::flips(ParkMiller::to_uniform(r), th);
                assert_eq!(F::flips(r, raw), want, "{:?} k dt = {k_dt}, state {r}, raw threshold {raw}", F::RULE);
            }
        }
        let mut g = ParkMiller::new(3).unwrap();
        let mut cases = vec![0.0, 1e-12, 0.01, 0.1, 0.5, 1.0, 2.0, f64::INFINITY, f64::NAN];
        cases.extend((0..100).map(|_| g.uniform()));
        for k_dt in cases {
            check::<LinearFlip>(k_dt);
            check::<ExponentialFlip>(k_dt);
            check::<AsPrintedFlip>(k_dt);
        }
    }

    #[test]
    fn as_printed_rule() {
        assert!(AsPrintedFlip::flips(0.31, AsPrintedFlip::threshold(0.3)));
        assert!(!AsPrintedFlip::flips(0.29, AsPrintedFlip::threshold(0.3)));
        assert!(!AsPrintedFlip::flips(0.99, AsPrintedFlip::threshold(f64::INFINITY)));
        assert!((AsPrintedFlip::probability(0.3) - 0.7).abs() < 1e-16);
        assert_eq!(AsPrintedFlip::probability(2.0), 0.0);
    }
}
