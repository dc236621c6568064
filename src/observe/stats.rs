//! Time-weighted statistics over the averaging window `[t_warmup, t_end]`, built from
//! [`Segment`]s and [`Piece`]s, plus rupture-force statistics from events.

use serde::{Deserialize, Serialize};

use super::shifted::ShiftedSums;
use super::{EventKind, JunctionEvent, Observer, Piece, Segment, Stretch};

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

/// Window statistics of a run. Segments are clipped to the window; a segment that
/// straddles a window edge (only the fixed engine's, which are constant) is weighted by
/// its overlap. The friction's moments are summed about a reference between grid stops
/// ([`ShiftedSums`]) and merged into `friction` at each stop ([`Observer::stop`]), so a
/// checkpoint, written at a stop, holds them whole; the accessors include a stretch not
/// yet merged.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WindowStats {
    pub t_lo: f64,
    pub t_hi: f64,
    pub n: u64,
    friction: Moments,
    bond_force_integral: f64,
    viscous_integral: f64,
    attached_integral: f64,
    /// The stretch since the last stop (empty at a stop).
    #[serde(skip)]
    stretch: ShiftedSums,
}

impl WindowStats {
    pub fn new(t_lo: f64, t_hi: f64, n: u64) -> Self {
        WindowStats {
            t_lo,
            t_hi,
            n,
            friction: Moments::default(),
            bond_force_integral: 0.0,
            viscous_integral: 0.0,
            attached_integral: 0.0,
            stretch: ShiftedSums::default(),
        }
    }
    /// The friction's moments so far.
    pub fn friction(&self) -> Moments {
        let mut m = self.friction;
        self.stretch.fold_into(&mut m);
        m
    }
    /// Time covered so far.
    pub fn covered(&self) -> f64 {
        self.friction().weight
    }
    pub fn friction_mean(&self) -> f64 {
        self.friction().mean
    }
    pub fn friction_std(&self) -> f64 {
        self.friction().std()
    }
    pub fn bond_force_mean(&self) -> f64 {
        self.bond_force_integral / self.covered()
    }
    pub fn viscous_mean(&self) -> f64 {
        self.viscous_integral / self.covered()
    }
    pub fn attached_fraction_mean(&self) -> f64 {
        self.attached_integral / self.covered() / self.n as f64
    }
}

impl Observer for WindowStats {
    const STRETCHES: bool = true;
    #[inline]
    fn segment(&mut self, s: &Segment) {
        let lo = s.t0.max(self.t_lo);
        let hi = s.t1.min(self.t_hi);
        let w = hi - lo;
        if w.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return;
        }
        let h = s.t1 - s.t0;
        let m2 = if w < h { s.friction_m2 * (w / h) } else { s.friction_m2 };
        self.stretch.add_mean(w, s.friction, m2);
        self.bond_force_integral += w * s.bond_force;
        self.viscous_integral += w * s.viscous;
        self.attached_integral += w * s.attached as f64;
    }

    /// A piece inside the window is summed as it is (no division); one before it costs a
    /// comparison; one that straddles an edge (an advance that did not stop there) is
    /// clipped as its segment.
    #[inline]
    fn piece(&mut self, p: &Piece) {
        if p.t1 <= self.t_lo || p.t0 >= self.t_hi {
            return;
        }
        if p.t0 >= self.t_lo && p.t1 <= self.t_hi && p.h > 0.0 {
            self.stretch.add_piece(p.h, p.friction0, p.dev, p.dev2);
            self.bond_force_integral += p.bond;
            self.viscous_integral += p.viscous;
            self.attached_integral += p.h * p.attached as f64;
        } else {
            self.straddling(p);
        }
    }

    /// Nothing before the window is read.
    #[inline]
    fn integrals_after(&self) -> f64 {
        self.t_lo
    }

    /// Nothing after the window is read.
    #[inline]
    fn stretch_until(&self) -> f64 {
        self.t_hi
    }

    /// A stretch inside the window (the engine summed only such pieces), merged as it is.
    #[inline]
    fn stretch(&mut self, s: &Stretch) {
        if s.friction.weight > 0.0 {
            s.friction.fold_into(&mut self.friction);
            self.bond_force_integral += s.bond;
            self.viscous_integral += s.viscous;
            self.attached_integral += s.attached;
        }
    }

    #[inline]
    fn stop(&mut self) {
        self.stretch.fold_into(&mut self.friction);
        self.stretch = ShiftedSums::default();
    }
}

impl WindowStats {
    /// A piece across a window edge, clipped as its segment. Rare: kept out of line.
    #[cold]
    #[inline(never)]
    fn straddling(&mut self, p: &Piece) {
        if p.h > 0.0 {
            self.segment(&p.segment());
        }
    }
}

/// Statistics of the tension at rupture, for ruptures inside the window.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RuptureForces {
    pub t_lo: f64,
    pub t_hi: f64,
    pub count: u64,
    pub sum: f64,
    pub sum_sq: f64,
}

impl RuptureForces {
    pub fn new(t_lo: f64, t_hi: f64) -> Self {
        RuptureForces { t_lo, t_hi, ..Default::default() }
    }
    pub fn mean(&self) -> f64 {
        self.sum / self.count as f64
    }
    /// Standard error of the mean rupture force.
    pub fn standard_error(&self) -> f64 {
        let c = self.count as f64;
        let var = (self.sum_sq - self.sum * self.sum / c) / (c - 1.0);
        (var.max(0.0) / c).sqrt()
    }
}

impl Observer for RuptureForces {
    const EVENTS: bool = true;
    const STRETCHES: bool = true;
    /// Ruptures only: engines build no event for a formation.
    const FORMATIONS: bool = false;
    #[inline]
    fn integrals_after(&self) -> f64 {
        f64::INFINITY
    }
    #[inline]
    fn event(&mut self, e: &JunctionEvent) {
        if e.kind == EventKind::Rupture && e.t >= self.t_lo && e.t <= self.t_hi {
            self.count += 1;
            self.sum += e.tension;
            self.sum_sq += e.tension * e.tension;
        }
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

    #[test]
    fn window_clips_segments() {
        let mut w = WindowStats::new(1.0, 3.0, 10);
        for k in 0..5 {
            let t0 = k as f64 * 0.75;
            w.segment(&Segment { t0, t1: t0 + 0.75, friction: k as f64, attached: 5, ..Default::default() });
        }
        assert!((w.covered() - 2.0).abs() < 1e-15);
        // weights: k=1 covers [1,1.5]=0.5, k=2 [1.5,2.25]=0.75, k=3 [2.25,3]=0.75
        assert!((w.friction_mean() - (0.5 * 1.0 + 0.75 * 2.0 + 0.75 * 3.0) / 2.0).abs() < 1e-15);
        assert!((w.attached_fraction_mean() - 0.5).abs() < 1e-15);
    }
}
