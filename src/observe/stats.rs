//! Time-weighted statistics over the averaging window `[t_warmup, t_end]`, built from
//! [`Segment`]s and [`Piece`]s, plus rupture-force statistics from events.

use serde::{Deserialize, Serialize};

use super::moments::Moments;
use super::observer::Observer;
use super::piece::Piece;
use super::report::{EventKind, JunctionEvent, Segment};
use super::shifted::ShiftedSums;
use super::stretch::Stretch;

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
    /// `int (N - N_att) dt`: with `attached_integral`, `N` times the time covered, summed on
    /// the same pieces ([`WindowStats::attached_fraction_mean`]).
    detached_integral: f64,
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
            detached_integral: 0.0,
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
    /// The attached fraction's time average, `int N_att / (int N_att + int (N - N_att))`: both
    /// sums over the same pieces, so it lies in `[0, 1]` by construction (rounding is monotone,
    /// so the sum of the two is not below the first) and is exactly 1 when every junction
    /// stayed attached, 0 when none did.
    pub fn attached_fraction_mean(&self) -> f64 {
        let (a, d) = (self.attached_integral, self.detached_integral);
        a / (a + d)
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
        self.detached_integral += w * (self.n - s.attached) as f64;
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
            self.detached_integral += p.h * (self.n - p.attached) as f64;
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
            self.detached_integral += s.detached;
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
    use crate::rng::{UniformSource, pcg};

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

    /// Segments of `0.1` (whose clipped lengths round differently) from `t = 0` to `100`,
    /// with `attached(k)` of 300 junctions on the `k`-th, a stop after every `stride`-th.
    fn tenths(attached: impl Fn(usize) -> u64, stride: usize) -> WindowStats {
        let mut w = WindowStats::new(0.0, 100.0, 300);
        for k in 0..1000 {
            let t0 = k as f64 * 0.1;
            w.segment(&Segment { t0, t1: t0 + 0.1, attached: attached(k), ..Default::default() });
            if k % stride == 0 {
                w.stop();
            }
        }
        w
    }

    #[test]
    fn attached_fraction_is_exactly_one_with_every_junction_attached_and_within_zero_and_one() {
        for stride in [1, 7, 1000] {
            assert_eq!(tenths(|_| 300, stride).attached_fraction_mean(), 1.0, "stride {stride}");
            assert_eq!(tenths(|_| 0, stride).attached_fraction_mean(), 0.0, "stride {stride}");
            // 299 or 300 attached: just below 1.
            let mut rng = pcg(stride as u64);
            let counts: Vec<u64> = (0..1000).map(|_| 299 + (rng.uniform() * 2.0) as u64).collect();
            let f = tenths(|k| counts[k], stride).attached_fraction_mean();
            assert!((0.99..=1.0).contains(&f), "stride {stride}: {f}");
        }
    }
}
