//! Flip rules of the fixed-step scheme (docs/engines.md, "The fixed-step engine", step 1).
//!
//! A junction whose rate is `k` flips in a step of size `dt` when its uniform `xi` in
//! `(0, 1)` passes a test against `k dt`. Each rule splits the test into a per-rate
//! [`FlipTest::threshold`] (computed once per step for rates shared by many junctions) and a
//! cheap per-junction comparison [`FlipTest::flips`], the same for every rule:
//! `s xi < threshold` with the rule's sign `s = +-1` folded into the threshold. Negation is
//! exact, so `-xi < -k dt` is `xi > k dt` bit for bit, and the rule is a value chosen once
//! per run rather than a type: one compiled step loop serves all three rules.

use serde::{Deserialize, Serialize};

use crate::scene::FlipRule;

/// A flip rule resolved for a run: its sign and its threshold function.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlipTest {
    rule: FlipRule,
    /// `+1` for `xi < threshold` rules, `-1` for `xi > k dt` (`as-printed`).
    sign: f64,
}

impl FlipTest {
    /// The test of `rule`.
    pub fn new(rule: FlipRule) -> Self {
        let sign = if rule == FlipRule::AsPrinted { -1.0 } else { 1.0 };
        FlipTest { rule, sign }
    }

    /// Which scene option this is.
    pub fn rule(&self) -> FlipRule {
        self.rule
    }

    /// The signed threshold `s * th(k dt)` the signed uniform is compared with, from
    /// `k dt >= 0` (`+inf` allowed):
    /// - `linear`: `min(1, k dt)`;
    /// - `exponential`: `1 - exp(-k dt) = -expm1(-k dt)` (accurate for small `k dt`; `+inf` gives 1);
    /// - `as-printed`: `-k dt`.
    #[inline]
    pub fn threshold(&self, k_dt: f64) -> f64 {
        match self.rule {
            FlipRule::Linear => k_dt.min(1.0),
            FlipRule::Exponential => -(-k_dt).exp_m1(),
            FlipRule::AsPrinted => -k_dt,
        }
    }

    /// Whether a junction with uniform `xi` flips against `threshold` (from
    /// [`FlipTest::threshold`]): `s xi < threshold`, i.e. `xi < th` or, for `as-printed`,
    /// `xi > k dt`.
    #[inline(always)]
    pub fn flips(&self, xi: f64, threshold: f64) -> bool {
        self.sign * xi < threshold
    }

    /// The one-step flip probability `P(flips(xi, threshold(k dt)))` for `xi ~ U(0, 1)`.
    #[inline]
    pub fn probability(&self, k_dt: f64) -> f64 {
        let th = self.threshold(k_dt);
        match self.rule {
            FlipRule::AsPrinted => (1.0 + th).clamp(0.0, 1.0),
            _ => th.clamp(0.0, 1.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn test(rule: FlipRule) -> FlipTest {
        FlipTest::new(rule)
    }

    #[test]
    fn linear_rule() {
        let f = test(FlipRule::Linear);
        assert!(f.flips(0.29, f.threshold(0.3)));
        assert!(!f.flips(0.31, f.threshold(0.3)));
        assert_eq!(f.threshold(5.0), 1.0);
        assert!(f.flips(1.0 - 1e-16, f.threshold(f64::INFINITY)));
        assert!(!f.flips(1e-300, f.threshold(0.0)));
        assert_eq!(f.probability(0.25), 0.25);
        assert_eq!(f.probability(3.0), 1.0);
    }

    #[test]
    fn exponential_rule() {
        let f = test(FlipRule::Exponential);
        let th = f.threshold(0.5);
        assert!((th - (1.0 - (-0.5f64).exp())).abs() < 1e-16);
        // expm1 keeps full relative accuracy where 1 - exp(-x) would cancel.
        assert!((f.threshold(1e-12) / 1e-12 - 1.0).abs() < 1e-12);
        assert_eq!(f.threshold(f64::INFINITY), 1.0);
        assert_eq!(f.threshold(0.0), 0.0);
        assert!(f.flips(0.39, th) && !f.flips(0.40, th));
    }

    #[test]
    fn as_printed_rule() {
        let f = test(FlipRule::AsPrinted);
        assert!(f.flips(0.31, f.threshold(0.3)));
        assert!(!f.flips(0.29, f.threshold(0.3)));
        assert!(!f.flips(0.99, f.threshold(f64::INFINITY)));
        assert!((f.probability(0.3) - 0.7).abs() < 1e-16);
        assert_eq!(f.probability(2.0), 0.0);
    }

    /// The signed comparison is the letter's `xi > k dt` bit for bit, ties included (a tie
    /// does not flip), over uniforms and rates on a grid and at their edges.
    #[test]
    fn signed_test_is_the_printed_comparison() {
        let f = test(FlipRule::AsPrinted);
        let values = [0.0, 1e-300, 1e-17, 0.1, 0.3, 0.5, 1.0 - 1e-16, 1.0, 2.0, f64::INFINITY];
        for &xi in &values {
            for &k_dt in &values {
                assert_eq!(f.flips(xi, f.threshold(k_dt)), xi > k_dt, "xi {xi}, k dt {k_dt}");
            }
        }
        let g = test(FlipRule::Linear);
        for &xi in &values {
            for &k_dt in &values {
                assert_eq!(g.flips(xi, g.threshold(k_dt)), xi < k_dt.min(1.0), "xi {xi}, k dt {k_dt}");
            }
        }
    }
}
