//! What a closed-form piece of the linear engine reports: its raw time integrals
//! ([`Piece`]) from the propagator's integrals, with no division; or, for an observer that
//! takes stretches, the pieces summed ([`Sums`]) and reported as one [`Stretch`] per advance.
//!
//! With `w(s) = y(s) - y0 - V s` the lag is `lag0 + w(s)` and the friction `F = -K lag`, so
//! with `i1 = int (y - y0)` and `i2 = int w^2` over `[0, h]` ([`Integrals`]):
//!
//! ```text
//!     int (F - F0) = -K int w = -K (i1 - V h^2 / 2),      int (F - F0)^2 = K^2 i2,
//!     int F_b = kappa (N_att (h y0 + i1) - h C),          int eta y' = eta (y1 - y0).
//! ```
//!
//! [`Sums`] keeps the lag's shifted sums about the lag `r` at its first piece,
//! `S1 = sum int (lag - r)` and `S2 = sum int (lag - r)^2` (with `d = lag0 - r`, a piece adds
//! `h d + int w` and `h d^2 + 2 d int w + int w^2`: multiply-adds alone), the time and the
//! attached and detached counts' integrals; the friction's sums are `-K` and `K^2` times the lag's, and
//! the bond and viscous forces' integrals follow from the plate's state at the stretch's
//! two ends ([`Stretch`]). A piece on the short path is kept with its polynomial's
//! coefficients ([`Terms::Short`]) and summed in batches ([`BATCH`]), whose integrals are
//! computed four pieces at a time ([`integrals_in_lanes`]): the same bits, added in the same
//! order, as one piece at a time.

use crate::engine::exact::core::frame::Frame;
use crate::engine::exact::stepper::linear::propagator::{SHORT_LEN, Terms, integrals_in_lanes};
use crate::observe::shifted::ShiftedSums;
use crate::observe::{Piece, Stretch};
use crate::physics::Plate;

/// A finished piece `[tau0, tau1]` (local times, length `h`): the plate's state `(y0, v0)`
/// and lag `lag0` at its start, its state `(y1, v1)` at its end, the attached and detached
/// counts (constant on the piece) and the propagator's integrals over it, or the terms to compute them from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Span {
    pub tau0: f64,
    pub tau1: f64,
    pub h: f64,
    pub y0: f64,
    pub v0: f64,
    pub lag0: f64,
    pub y1: f64,
    pub v1: f64,
    pub n_att: usize,
    pub terms: Terms,
}

/// The span `s` in `frame` as a [`Piece`] of raw integrals, for the anchors' sum `C`
/// (`anchor_sum`, constant on the piece), drift `V` of the plate `p` and the law's slope `kappa`.
#[inline(always)]
pub(super) fn piece(s: &Span, frame: &Frame, anchor_sum: f64, p: &Plate, kappa: f64) -> Piece {
    let (h, ints) = (s.h, s.terms.integrals(s.h, p.v));
    let w1 = ints.i1 - 0.5 * p.v * h * h;
    let n = s.n_att as f64;
    Piece {
        t0: frame.time(s.tau0),
        t1: frame.time(s.tau1),
        h,
        friction0: -p.k * s.lag0,
        dev: -p.k * w1,
        dev2: p.k * p.k * ints.i2,
        bond: kappa * (n * (h * s.y0 + ints.i1) - h * anchor_sum),
        viscous: p.eta * (s.y1 - s.y0),
        attached: s.n_att as u64,
    }
}

/// The observers' window ([`Observer::integrals_after`](crate::observe::Observer::integrals_after),
/// [`Observer::stretch_until`](crate::observe::Observer::stretch_until)), read once per
/// advance, in local time: compared with a piece's local ends, with no conversion per piece.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Window {
    /// The absolute bounds.
    after: f64,
    until: f64,
    /// The same in local time.
    lo: f64,
    hi: f64,
}

impl Default for Window {
    /// No integrals read, nothing summed (until an advance reads the observers).
    fn default() -> Window {
        Window { after: f64::INFINITY, until: f64::NEG_INFINITY, lo: f64::INFINITY, hi: f64::NEG_INFINITY }
    }
}

impl Window {
    /// Integrals read after absolute time `after`, pieces summed up to `until`, in `frame`.
    #[inline]
    pub(super) fn new(after: f64, until: f64, frame: &Frame) -> Window {
        Window { after, until, lo: frame.local(after), hi: frame.local(until) }
    }

    /// The same bounds in the frame moved to `frame`.
    #[inline]
    pub(super) fn relocate(&mut self, frame: &Frame) {
        *self = Window::new(self.after, self.until, frame);
    }

    /// Whether a piece ending at local `tau1` is read with its integrals.
    #[inline(always)]
    pub(super) fn integrals(&self, tau1: f64) -> bool {
        tau1 > self.lo
    }

    /// Whether the piece `[tau0, tau1]` (local) is summed into the stretch.
    #[inline(always)]
    pub(super) fn sums(&self, tau0: f64, tau1: f64) -> bool {
        tau0 >= self.lo && tau1 <= self.hi
    }
}

/// Pieces on the short path kept for [`Sums`] before their integrals are computed: a
/// multiple of the lanes.
const BATCH: usize = 64;
/// Pieces whose integrals are computed side by side.
const LANES: usize = 4;
const _: () = assert!(BATCH % LANES == 0 && BATCH.is_power_of_two());

/// Short-path pieces not yet summed, by field: the coefficients `c_1 .. c_7` (row 0
/// unused), the length, the lag at the start, the attached count.
#[derive(Clone, Debug, PartialEq)]
struct Batch {
    len: usize,
    c: [[f64; BATCH]; SHORT_LEN],
    h: [f64; BATCH],
    lag0: [f64; BATCH],
    n_att: [f64; BATCH],
}

impl Default for Batch {
    fn default() -> Batch {
        let row = [0.0; BATCH];
        Batch { len: 0, c: [row; SHORT_LEN], h: row, lag0: row, n_att: row }
    }
}

/// The pieces summed since the last report: the sums, and the short-path pieces not yet in
/// them.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Sums {
    acc: Acc,
    batch: Batch,
    /// The number of junctions `N` ([`Sums::set_junctions`]), for the detached count's
    /// integral `sum (h N - h N_att)`.
    n: f64,
}

/// The sums (lag units, local positions): empty when `weight = 0`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Acc {
    /// Absolute start time and the lag `r` at it.
    t0: f64,
    lag_ref: f64,
    /// `W = sum h`, `S1`, `S2` (module doc).
    weight: f64,
    s1: f64,
    s2: f64,
    /// `sum h N_att`.
    attached: f64,
    /// `sum h (N - N_att)`.
    detached: f64,
    /// Absolute end time of the last piece.
    t1: f64,
    /// The plate's local position and velocity at the start and at the end.
    y0: f64,
    v0: f64,
    y1: f64,
    v1: f64,
}

impl Sums {
    /// Sets the number of junctions `n` (constant over a run).
    #[inline]
    pub(super) fn set_junctions(&mut self, n: usize) {
        self.n = n as f64;
    }

    /// Adds the span `p` in `frame`, with drift `v`: to the batch if it is on the short path
    /// (summed when the batch is full), else summed now, after the batch.
    #[inline(always)]
    pub(super) fn add(&mut self, p: &Span, frame: &Frame, v: f64) {
        if self.batch.len == 0 && self.acc.weight == 0.0 {
            self.acc.t0 = frame.time(p.tau0);
            self.acc.lag_ref = p.lag0;
            self.acc.y0 = p.y0;
            self.acc.v0 = p.v0;
        }
        self.acc.t1 = frame.time(p.tau1);
        self.acc.y1 = p.y1;
        self.acc.v1 = p.v1;
        if let Terms::Short(c) = p.terms {
            let b = &mut self.batch;
            let i = b.len % BATCH;
            #[allow(clippy::needless_range_loop)] // unrolled; the iterator form is not
            for n in 1..SHORT_LEN {
                b.c[n][i] = c[n];
            }
            (b.h[i], b.lag0[i], b.n_att[i]) = (p.h, p.lag0, p.n_att as f64);
            b.len = i + 1;
            if b.len == BATCH {
                self.flush(v);
            }
        } else {
            let ints = p.terms.integrals(p.h, v);
            self.flush(v);
            self.sum([p.h], [p.lag0], [p.n_att as f64], [ints.i1], [ints.i2], v, 1);
        }
    }

    /// Sums the batch's pieces, [`LANES`] at a time, and empties it.
    #[inline(never)]
    fn flush(&mut self, v: f64) {
        let len = self.batch.len;
        for j in 0..BATCH / LANES {
            let k = j * LANES;
            if k >= len {
                break;
            }
            let b = &self.batch;
            let lanes =
                |row: &[f64; BATCH]| -> [f64; LANES] { row[k..k + LANES].try_into().expect("within the batch") };
            let (h, lag0, n_att) = (lanes(&b.h), lanes(&b.lag0), lanes(&b.n_att));
            // Indexed loops: `array::map` and `Zip::new` are out-of-line calls in `release`.
            let mut c = [[0.0; LANES]; SHORT_LEN];
            #[allow(clippy::needless_range_loop)]
            for n in 1..SHORT_LEN {
                c[n] = lanes(&b.c[n]);
            }
            let (i1, i2) = integrals_in_lanes(&c, &h, v);
            self.sum(h, lag0, n_att, i1, i2, v, len - k);
        }
        self.batch.len = 0;
    }

    /// Adds the first `used` (all if more) of `L` pieces of lengths `h`, starting lags `lag0`, attached
    /// counts `n_att` and integrals `i1`, `i2`, in order. `d = lag0 - r`, `w1 = i1 - V h^2/2`;
    /// each piece adds `h d + w1` to `S1` and `h d^2 + 2 d w1 + i2` to `S2`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn sum<const L: usize>(
        &mut self,
        h: [f64; L],
        lag0: [f64; L],
        n_att: [f64; L],
        i1: [f64; L],
        i2: [f64; L],
        v: f64,
        used: usize,
    ) {
        let (mut e1, mut e2, mut e3, mut e4) = ([0.0; L], [0.0; L], [0.0; L], [0.0; L]);
        for l in 0..L {
            let d = lag0[l] - self.acc.lag_ref;
            let w1 = i1[l] - 0.5 * v * h[l] * h[l];
            let hd = h[l] * d;
            e1[l] = hd + w1;
            e2[l] = hd * d + (2.0 * d * w1 + i2[l]);
            e3[l] = h[l] * n_att[l];
            // `h N - h N_att`, each product rounded: at least 0 (rounding is monotone),
            // exactly 0 with every junction attached.
            e4[l] = h[l] * self.n - e3[l];
        }
        for l in 0..L.min(used) {
            self.acc.weight += h[l];
            self.acc.s1 += e1[l];
            self.acc.s2 += e2[l];
            self.acc.attached += e3[l];
            self.acc.detached += e4[l];
        }
    }

    /// The local origin moved by `dy` in position.
    #[inline]
    pub(super) fn shifted(&mut self, dy: f64) {
        self.acc.y0 -= dy;
        self.acc.y1 -= dy;
    }

    /// The stretch summed (empty, at `now`, if nothing was), for plate `p`; `self` empties.
    #[inline]
    pub(super) fn take(&mut self, p: &Plate, now: f64) -> Stretch {
        self.flush(p.v);
        let s = std::mem::take(&mut self.acc);
        if s.weight == 0.0 {
            return Stretch { t0: now, t1: now, ..Stretch::default() };
        }
        let k = p.k;
        let friction = ShiftedSums { reference: -k * s.lag_ref, weight: s.weight, s1: -k * s.s1, s2: (k * k) * s.s2 };
        // int F = -K int lag; M X'' + eta X' = F - F_b over the stretch.
        let int_f = -k * (s.lag_ref * s.weight + s.s1);
        let viscous = p.eta * (s.y1 - s.y0);
        Stretch {
            t0: s.t0,
            t1: s.t1,
            friction,
            bond: int_f - viscous - p.mass * (s.v1 - s.v0),
            viscous,
            attached: s.attached,
            detached: s.detached,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::exact::stepper::linear::propagator::LinearPlate;
    use crate::observe::Observer;
    use crate::observe::stats::WindowStats;
    use crate::rng::{UniformSource, pcg};

    /// The span `[tau, tau + h]` from `(y, v)` to `(y1, v1)` with `n_att` of 40 junctions
    /// attached.
    fn span_of(
        frame: &Frame,
        (tau, h): (f64, f64),
        (y, v): (f64, f64),
        (y1, v1): (f64, f64),
        n_att: usize,
        terms: Terms,
    ) -> Span {
        let lag0 = frame.lag(y, tau);
        Span { tau0: tau, tau1: tau + h, h, y0: y, v0: v, lag0, y1, v1, n_att, terms }
    }

    /// Gauss-Legendre nodes and weights on `[-1, 1]`, five points (exact to degree 9).
    const GL5: [(f64, f64); 5] = [
        (0.0, 0.568_888_888_888_888_9),
        (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
        (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
        (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
        (0.906_179_845_938_664, 0.236_926_885_056_189_1),
    ];

    /// `int_0^h g(s) ds`, composite five-point Gauss-Legendre on 16 panels.
    fn quad(h: f64, g: impl Fn(f64) -> f64) -> f64 {
        let panels = 16;
        let w = h / panels as f64;
        (0..panels)
            .map(|k| {
                let mid = (k as f64 + 0.5) * w;
                GL5.iter().map(|&(x, wt)| wt * g(mid + 0.5 * w * x)).sum::<f64>() * 0.5 * w
            })
            .sum()
    }

    /// Chains of pieces of random lengths up to the short path's limit (so that some lanes
    /// keep the square's higher terms), some off the short path, over several batches and
    /// part of one: summed through the batch, they give the same stretch bit for bit as
    /// the same pieces summed one at a time from their integrals.
    #[test]
    fn batched_pieces_sum_to_the_bits_of_one_at_a_time() {
        let mut rng = pcg(39);
        let mut u = || rng.uniform();
        let (mut batched, mut off_short) = (0, 0);
        for case in 0..40 {
            let p = Plate { mass: 0.1 + 5.0 * u(), eta: 0.01 + 3.0 * u(), k: 0.5 + 10.0 * u(), v: 0.5 * u() };
            let frame = Frame { epoch: u(), x_ref: 0.0, lag_ref: u() - 0.5, v: p.v };
            let (mut one, mut many) = (Sums::default(), Sums::default());
            one.set_junctions(40);
            many.set_junctions(40);
            let (mut tau, mut y, mut v) = (0.0, u() - 0.5, u() - 0.5);
            for _ in 0..(case * 7) % 200 + 1 {
                let n_att = (u() * 40.0) as usize;
                let plate = LinearPlate::new(p.mass, p.eta, p.k + 0.3 * n_att as f64);
                let tr = plate.trajectory(y, v, p.k * (p.v * tau - frame.lag_ref) + u(), p.k * p.v);
                // Up to four times the short path's longest step (2^-8 / rho).
                let h = 2f64.powf(-8.0 - 20.0 * u() + 2.0) / plate.rho();
                let (y1, v1, terms) = tr.at_maybe_terms(h, p.v, true);
                let ints = terms.integrals(h, p.v);
                match terms {
                    Terms::Short(_) => batched += 1,
                    Terms::Integrals(_) => off_short += 1,
                }
                let span = span_of(&frame, (tau, h), (y, v), (y1, v1), n_att, terms);
                many.add(&span, &frame, p.v);
                one.add(&Span { terms: Terms::Integrals(ints), ..span }, &frame, p.v);
                assert_eq!(one.batch.len, 0);
                (tau, y, v) = (tau + h, y1, v1);
            }
            let (a, b) = (one.take(&p, tau), many.take(&p, tau));
            assert_eq!(a, b, "case {case}");
            assert!(a.t1 > a.t0 && a.friction.weight > 0.0, "case {case}: {a:?}");
        }
        assert!(batched > 1000 && off_short > 100, "{batched} pieces batched, {off_short} off the short path");
    }

    /// The window in local time: a piece that starts where the window opens (the runner's
    /// stop at the warm-up's end, in local time `local(t_lo)`) is summed, one that ends
    /// there is not read, one that ends after the window's end is reported as a piece; the
    /// same after the frame moves; and before any advance nothing is read.
    #[test]
    fn window_in_local_time() {
        let mut frame = Frame { epoch: 1.25, x_ref: 0.0, lag_ref: 0.0, v: 0.5 };
        let (t_lo, t_hi) = (20.1, 40.3);
        let mut w = Window::new(t_lo, t_hi, &frame);
        let (lo, hi) = (frame.local(t_lo), frame.local(t_hi));
        assert!(!w.integrals(lo) && w.integrals(lo + 1e-9));
        assert!(w.sums(lo, lo + 1.0) && w.sums(hi - 1.0, hi));
        assert!(!w.sums(lo - 1e-9, lo + 1.0) && !w.sums(hi - 1.0, hi + 1e-9));
        frame.shift(7.5, 3.0);
        w.relocate(&frame);
        let (lo, hi) = (frame.local(t_lo), frame.local(t_hi));
        assert!(!w.integrals(lo) && w.integrals(lo + 1e-9));
        assert!(w.sums(lo, hi) && !w.sums(lo, hi + 1e-9));
        let none = Window::default();
        assert!(!none.integrals(1e300) && !none.sums(0.0, 0.0));
    }

    /// Random plates (under- and overdamped, `M = 0` too), random chains of pieces with
    /// random attached counts and anchors, random grid stops, a window from one piece
    /// boundary to another (the runner stops at both): the window statistics summed from
    /// the pieces ([`piece`], shifted sums folded at stops) equal a direct quadrature of the
    /// piecewise path (friction's mean and standard deviation, bond and viscous force,
    /// attached fraction); and so do the same pieces summed ([`Sums`]) and reported as
    /// stretches at the stops.
    #[test]
    fn summed_pieces_equal_a_quadrature_of_the_path() {
        let mut rng = pcg(38);
        let mut u = || rng.uniform();
        for case in 0..200 {
            let (mass, eta) = if case % 10 == 0 { (0.0, 0.5 + 2.0 * u()) } else { (0.1 + 5.0 * u(), 0.01 + 3.0 * u()) };
            let p = Plate { mass, eta, k: 0.5 + 10.0 * u(), v: 0.5 * u() };
            let kappa = 0.1 + u();
            // Local frame: absolute time t = epoch + tau, lag = y - V tau + lag_ref.
            let (epoch, lag_ref) = (u() - 0.5, 3.0 * (u() - 0.5));
            let frame = Frame { epoch, x_ref: 0.0, lag_ref, v: p.v };
            let hs: Vec<f64> = (0..8 + (u() * 20.0) as usize).map(|_| 0.01 + 0.4 * u()).collect();
            let mut ends = Vec::new();
            hs.iter().fold(0.0, |tau, h| {
                ends.push(epoch + (tau + h));
                tau + h
            });
            let (t_lo, t_hi) = (ends[1], ends[hs.len() - 2]);
            let mut stats = WindowStats::new(t_lo, t_hi, 40);
            // The same pieces summed in the kernel's way, reported at random stops.
            let (mut summed, mut sums) = (WindowStats::new(t_lo, t_hi, 40), Sums::default());
            sums.set_junctions(40);
            let (mut tau, mut y, mut v) = (0.0, 2.0 * (u() - 0.5), u() - 0.5);
            let (mut want_f, mut want_f2, mut want_b, mut want_v, mut want_a, mut covered) =
                (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            for &h in &hs {
                let n_att = (u() * 40.0) as usize;
                let anchor_sum = n_att as f64 * (y - 1.5 * u());
                let k_eff = p.k + kappa * n_att as f64;
                // M y'' + eta y' + k_eff y = K (V (tau + s) - lag_ref) + kappa C.
                let a = p.k * (p.v * tau - lag_ref) + kappa * anchor_sum;
                let tr = LinearPlate::new(p.mass, p.eta, k_eff).trajectory(y, v, a, p.k * p.v);
                let (y1, v1, terms) = tr.at_maybe_terms(h, p.v, true);
                let span = span_of(&frame, (tau, h), (y, v), (y1, v1), n_att, terms);
                let inside = frame.time(tau) >= t_lo && frame.time(tau + h) <= t_hi;
                stats.piece(&piece(&span, &frame, anchor_sum, &p, kappa));
                if inside {
                    sums.add(&span, &frame, p.v);
                }
                if u() < 0.3 {
                    stats.stop();
                    summed.stretch(&sums.take(&p, epoch + (tau + h)));
                }
                // The reference: the path on the pieces inside the window.
                if inside {
                    let f = |s: f64| -p.k * ((tr.at(s).0 - p.v * (tau + s)) + lag_ref);
                    want_f += quad(h, f);
                    want_f2 += quad(h, |s| f(s) * f(s));
                    want_b += quad(h, |s| kappa * (n_att as f64 * tr.at(s).0 - anchor_sum));
                    want_v += quad(h, |s| p.eta * tr.at(s).1);
                    want_a += h * n_att as f64;
                    covered += h;
                }
                (tau, y, v) = (tau + h, y1, v1);
            }
            summed.stretch(&sums.take(&p, epoch + tau));
            let mean = want_f / covered;
            let std = (want_f2 / covered - mean * mean).sqrt();
            let scale = mean.abs() + std;
            let ctx = format!("case {case}: {p:?}, {} pieces", hs.len());
            assert!((stats.covered() - covered).abs() < 1e-12, "{ctx}: covered {} of {covered}", stats.covered());
            assert!((stats.friction_mean() - mean).abs() < 1e-10 * scale, "{ctx}: {} vs {mean}", stats.friction_mean());
            // The reference's E[F^2] - E[F]^2 loses the digits of (mean/std)^2.
            let tol = 1e-10 * scale * scale / std;
            assert!((stats.friction_std() - std).abs() < tol, "{ctx}: std {} vs {std}", stats.friction_std());
            let bscale = kappa * 40.0 * 4.0;
            assert!((stats.bond_force_mean() - want_b / covered).abs() < 1e-10 * bscale, "{ctx}: bond");
            assert!((stats.viscous_mean() - want_v / covered).abs() < 1e-10 * (1.0 + p.eta), "{ctx}: viscous");
            assert!((stats.attached_fraction_mean() - want_a / covered / 40.0).abs() < 1e-12, "{ctx}: attached");
            // Summed: the bond and viscous forces from the plate equation at the ends.
            let s = &summed;
            assert!((s.covered() - covered).abs() < 1e-12, "{ctx}: summed covered {} of {covered}", s.covered());
            assert!((s.friction_mean() - mean).abs() < 1e-10 * scale, "{ctx}: summed {} vs {mean}", s.friction_mean());
            assert!((s.friction_std() - std).abs() < tol, "{ctx}: summed std {} vs {std}", s.friction_std());
            assert!((s.bond_force_mean() - want_b / covered).abs() < 1e-10 * (bscale + scale), "{ctx}: summed bond");
            assert!((s.viscous_mean() - want_v / covered).abs() < 1e-10 * (1.0 + p.eta), "{ctx}: summed viscous");
            assert!((s.attached_fraction_mean() - want_a / covered / 40.0).abs() < 1e-12, "{ctx}: summed attached");
        }
    }
}
