//! [`Moments`]: a time-weighted mean and second central moment, merged piece by piece.

use serde::{Deserialize, Serialize};

/// Time-weighted mean and second central moment, merged segment by segment with the
/// pairwise update of Chan, Golub & LeVeque (stable: no `E[F^2] - E[F]^2` cancellation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Moments {
    /// Total weight (time).
    pub weight: f64,
    pub mean: f64,
    /// `int (F - mean)^2 dt`.
    pub m2: f64,
}

impl Moments {
    /// Merges a piece of weight `w`, mean `m` and second central moment `m2`.
    #[inline]
    pub fn merge(&mut self, w: f64, m: f64, m2: f64) {
        if w <= 0.0 {
            return;
        }
        let total = self.weight + w;
        let delta = m - self.mean;
        let share = w / total;
        self.mean += delta * share;
        self.m2 += m2 + delta * delta * (self.weight * share);
        self.weight = total;
    }
    /// Time-weighted standard deviation.
    pub fn std(&self) -> f64 {
        if self.weight > 0.0 { (self.m2.max(0.0) / self.weight).sqrt() } else { f64::NAN }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merged_moments_equal_direct_ones() {
        // Piecewise-constant signal: direct mean and variance against the merged ones.
        let pieces = [(0.5, 3.0), (1.5, -1.0), (2.0, 10.0), (0.25, 1e-3)];
        let mut m = Moments::default();
        for &(w, v) in &pieces {
            m.merge(w, v, 0.0);
        }
        let tw: f64 = pieces.iter().map(|p| p.0).sum();
        let mean: f64 = pieces.iter().map(|p| p.0 * p.1).sum::<f64>() / tw;
        let var: f64 = pieces.iter().map(|p| p.0 * (p.1 - mean).powi(2)).sum::<f64>() / tw;
        assert!((m.mean - mean).abs() < 1e-14);
        assert!((m.std() - var.sqrt()).abs() < 1e-13);
    }

    #[test]
    fn no_cancellation_for_large_offsets() {
        // Values 1e9 +- 1e-3: a naive E[F^2] - E[F]^2 has an error of order eps * 1e18 ~ 200.
        let vals: Vec<f64> = (0..1000).map(|i| 1e9 + if i % 2 == 0 { 1e-3 } else { -1e-3 }).collect();
        let mut m = Moments::default();
        vals.iter().for_each(|&v| m.merge(1.0, v, 0.0));
        // Deviations from 1e9 are exact in f64 (Sterbenz), so this reference is exact.
        let d: Vec<f64> = vals.iter().map(|v| v - 1e9).collect();
        let dm = d.iter().sum::<f64>() / d.len() as f64;
        let exact = (d.iter().map(|x| (x - dm).powi(2)).sum::<f64>() / d.len() as f64).sqrt();
        assert!((m.std() - exact).abs() < 1e-12 * 1e3, "{} vs {exact}", m.std());
    }
}
