//! [`ShiftedSums`]: the friction's time integral and its square's about a fixed reference,
//! summed piece by piece with multiply-adds alone (no division, no chain of divisions
//! from piece to piece), and folded into [`Moments`] once per stretch (a grid stop).
//!
//! With reference `r` (the friction at the stretch's start), weight `W = sum h`,
//! `S1 = sum int (F - r) dt` and `S2 = sum int (F - r)^2 dt`, the stretch has
//!
//! ```text
//!     mean = r + S1 / W,        int (F - mean)^2 dt = S2 - S1^2 / W,
//! ```
//!
//! merged into the run's moments by the pairwise update ([`Moments::merge`]). The
//! subtraction loses at most the digits of `(mean - r)^2 / var`: `|mean - r|` is at most
//! the range of `F` over the stretch, so the result is the time average to rounding.

use super::moments::Moments;

/// Shifted sums of one stretch.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShiftedSums {
    /// The reference `r` (set by the first piece of the stretch).
    pub reference: f64,
    /// `W = sum h`.
    pub weight: f64,
    /// `S1 = sum int (F - r) dt`.
    pub s1: f64,
    /// `S2 = sum int (F - r)^2 dt`.
    pub s2: f64,
}

impl ShiftedSums {
    /// Adds a piece of length `h > 0` starting at friction `f0`, with `dev = int (F - f0)`
    /// and `dev2 = int (F - f0)^2` ([`super::Piece`]).
    #[inline(always)]
    pub fn add_piece(&mut self, h: f64, f0: f64, dev: f64, dev2: f64) {
        if self.weight == 0.0 {
            self.reference = f0;
        }
        let d = f0 - self.reference;
        let hd = h * d;
        self.weight += h;
        self.s1 += hd + dev;
        self.s2 += hd * d + (2.0 * d * dev + dev2);
    }

    /// Adds a piece of weight `w > 0`, mean `mean` and `m2 = int (F - mean)^2`.
    #[inline(always)]
    pub fn add_mean(&mut self, w: f64, mean: f64, m2: f64) {
        if self.weight == 0.0 {
            self.reference = mean;
        }
        let d = mean - self.reference;
        let wd = w * d;
        self.weight += w;
        self.s1 += wd;
        self.s2 += wd * d + m2;
    }

    /// Merges the stretch into `m` (nothing if it is empty).
    #[inline]
    pub fn fold_into(&self, m: &mut Moments) {
        if self.weight > 0.0 {
            let shift = self.s1 / self.weight;
            m.merge(self.weight, self.reference + shift, (self.s2 - self.s1 * shift).max(0.0));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A piecewise-constant signal summed in stretches: the moments of the direct sums.
    #[test]
    fn stretches_fold_to_the_direct_moments() {
        let pieces = [(0.5, 3.0), (1.5, -1.0), (2.0, 10.0), (0.25, 1e-3), (1.0, 4.0)];
        let mut m = Moments::default();
        for stretch in pieces.chunks(2) {
            let mut s = ShiftedSums::default();
            stretch.iter().for_each(|&(w, v)| s.add_mean(w, v, 0.0));
            s.fold_into(&mut m);
        }
        let tw: f64 = pieces.iter().map(|p| p.0).sum();
        let mean: f64 = pieces.iter().map(|p| p.0 * p.1).sum::<f64>() / tw;
        let var: f64 = pieces.iter().map(|p| p.0 * (p.1 - mean).powi(2)).sum::<f64>() / tw;
        assert!((m.weight - tw).abs() < 1e-15);
        assert!((m.mean - mean).abs() < 1e-14, "{} vs {mean}", m.mean);
        assert!((m.std() - var.sqrt()).abs() < 1e-13);
        // An empty stretch changes nothing.
        let before = m;
        ShiftedSums::default().fold_into(&mut m);
        assert_eq!(m, before);
    }

    /// Values 1e9 +- 1e-3 in stretches of 10: no cancellation of the offset.
    #[test]
    fn no_cancellation_for_large_offsets() {
        let vals: Vec<f64> = (0..1000).map(|i| 1e9 + if i % 2 == 0 { 1e-3 } else { -1e-3 }).collect();
        let mut m = Moments::default();
        for stretch in vals.chunks(10) {
            let mut s = ShiftedSums::default();
            stretch.iter().for_each(|&v| s.add_piece(1.0, v, 0.0, 0.0));
            s.fold_into(&mut m);
        }
        // Deviations from 1e9 are exact in f64 (Sterbenz), so this reference is exact.
        let d: Vec<f64> = vals.iter().map(|v| v - 1e9).collect();
        let dm = d.iter().sum::<f64>() / d.len() as f64;
        let exact = (d.iter().map(|x| (x - dm).powi(2)).sum::<f64>() / d.len() as f64).sqrt();
        assert!((m.std() - exact).abs() < 1e-12 * exact, "{} vs {exact}", m.std());
    }
}
