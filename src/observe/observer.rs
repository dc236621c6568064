//! The [`Observer`] contract (what an engine calls, and which of it an observer wants, as
//! constants), its combinations (pairs, options, references), [`Nothing`] and [`Recorder`].

use super::piece::Piece;
use super::report::{JunctionEvent, Sample, Segment};
use super::stretch::Stretch;

/// Receives what an engine reports. All methods have empty defaults.
pub trait Observer {
    /// Whether this observer wants [`JunctionEvent`]s. Engines test this constant, so the
    /// event path costs nothing when it is `false`.
    const EVENTS: bool = false;
    /// Whether this observer wants formations too, when it wants events (an observer of
    /// ruptures alone sets it false, and engines then build no event for a formation).
    const FORMATIONS: bool = Self::EVENTS;
    /// Whether this observer reads [`Segment`]s. Engines may skip computing a segment's
    /// time integrals when it is `false` (and still call [`Observer::segment`], with
    /// integrals that are not meaningful).
    const SEGMENTS: bool = true;
    /// Whether this observer takes the pieces inside
    /// `[integrals_after(), stretch_until()]` summed by the engine, as one [`Stretch`] per
    /// advance ([`Observer::stretch`]), in place of one [`Observer::piece`] each (an engine
    /// that sums them reports no piece that ends before `integrals_after()` either).
    const STRETCHES: bool = false;
    /// A junction ruptured or formed. Only called when `EVENTS` is true.
    #[inline]
    fn event(&mut self, _e: &JunctionEvent) {}
    /// The engine advanced over `[s.t0, s.t1]`.
    #[inline]
    fn segment(&mut self, _s: &Segment) {}
    /// The engine advanced over `[p.t0, p.t1]`, reported as raw integrals. Default: as the
    /// segment [`Piece::segment`] (whose division is dropped by the compiler for an
    /// observer that reads no segments).
    #[inline]
    fn piece(&mut self, p: &Piece) {
        self.segment(&p.segment());
    }
    /// The time up to which this observer reads no piece's integrals: a piece that ends at
    /// or before it may be reported with its integrals zero (an engine then skips computing
    /// them). `-inf` (every piece's integrals) by default; the window's start for window
    /// statistics; `+inf` for an observer that reads times or samples only. An engine may
    /// read it (and [`Observer::stretch_until`]) once per advance: neither may change
    /// between two grid stops.
    #[inline]
    fn integrals_after(&self) -> f64 {
        f64::NEG_INFINITY
    }
    /// The time after which this observer reads no stretch: a piece that ends after it is
    /// reported as a piece. `+inf` by default; the window's end for window statistics.
    #[inline]
    fn stretch_until(&self) -> f64 {
        f64::INFINITY
    }
    /// The pieces an engine summed since the last report, at the end of an advance (only
    /// when `STRETCHES` and `SEGMENTS`); `s.t1` is the time reached.
    #[inline]
    fn stretch(&mut self, _s: &Stretch) {}
    /// The engine stands at a grid stop of the runner's loop (between two advances).
    #[inline]
    fn stop(&mut self) {}
    /// A state on the output grid.
    fn sample(&mut self, _s: &Sample) {}
}

/// Observes nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Nothing;
impl Observer for Nothing {
    const SEGMENTS: bool = false;
    const STRETCHES: bool = true;
    #[inline]
    fn integrals_after(&self) -> f64 {
        f64::INFINITY
    }
}

impl<A: Observer, B: Observer> Observer for (A, B) {
    const EVENTS: bool = A::EVENTS || B::EVENTS;
    const FORMATIONS: bool = (A::EVENTS && A::FORMATIONS) || (B::EVENTS && B::FORMATIONS);
    const SEGMENTS: bool = A::SEGMENTS || B::SEGMENTS;
    const STRETCHES: bool = A::STRETCHES && B::STRETCHES;
    #[inline]
    fn event(&mut self, e: &JunctionEvent) {
        if A::EVENTS {
            self.0.event(e);
        }
        if B::EVENTS {
            self.1.event(e);
        }
    }
    #[inline]
    fn segment(&mut self, s: &Segment) {
        self.0.segment(s);
        self.1.segment(s);
    }
    #[inline]
    fn piece(&mut self, p: &Piece) {
        self.0.piece(p);
        self.1.piece(p);
    }
    #[inline]
    fn integrals_after(&self) -> f64 {
        self.0.integrals_after().min(self.1.integrals_after())
    }
    #[inline]
    fn stretch_until(&self) -> f64 {
        self.0.stretch_until().min(self.1.stretch_until())
    }
    #[inline]
    fn stretch(&mut self, s: &Stretch) {
        self.0.stretch(s);
        self.1.stretch(s);
    }
    #[inline]
    fn stop(&mut self) {
        self.0.stop();
        self.1.stop();
    }
    fn sample(&mut self, s: &Sample) {
        self.0.sample(s);
        self.1.sample(s);
    }
}

impl<A: Observer> Observer for Option<A> {
    const EVENTS: bool = A::EVENTS;
    const FORMATIONS: bool = A::FORMATIONS;
    const SEGMENTS: bool = A::SEGMENTS;
    const STRETCHES: bool = A::STRETCHES;
    #[inline]
    fn event(&mut self, e: &JunctionEvent) {
        if let Some(a) = self {
            a.event(e)
        }
    }
    #[inline]
    fn segment(&mut self, s: &Segment) {
        if let Some(a) = self {
            a.segment(s)
        }
    }
    #[inline]
    fn piece(&mut self, p: &Piece) {
        if let Some(a) = self {
            a.piece(p)
        }
    }
    #[inline]
    fn integrals_after(&self) -> f64 {
        match self {
            Some(a) => a.integrals_after(),
            None => f64::INFINITY,
        }
    }
    #[inline]
    fn stretch_until(&self) -> f64 {
        match self {
            Some(a) => a.stretch_until(),
            None => f64::INFINITY,
        }
    }
    #[inline]
    fn stretch(&mut self, s: &Stretch) {
        if let Some(a) = self {
            a.stretch(s)
        }
    }
    #[inline]
    fn stop(&mut self) {
        if let Some(a) = self {
            a.stop()
        }
    }
    fn sample(&mut self, s: &Sample) {
        if let Some(a) = self {
            a.sample(s)
        }
    }
}

impl<A: Observer + ?Sized> Observer for &mut A {
    const EVENTS: bool = A::EVENTS;
    const FORMATIONS: bool = A::FORMATIONS;
    const SEGMENTS: bool = A::SEGMENTS;
    const STRETCHES: bool = A::STRETCHES;
    #[inline]
    fn event(&mut self, e: &JunctionEvent) {
        (**self).event(e)
    }
    #[inline]
    fn segment(&mut self, s: &Segment) {
        (**self).segment(s)
    }
    #[inline]
    fn piece(&mut self, p: &Piece) {
        (**self).piece(p)
    }
    #[inline]
    fn integrals_after(&self) -> f64 {
        (**self).integrals_after()
    }
    #[inline]
    fn stretch_until(&self) -> f64 {
        (**self).stretch_until()
    }
    #[inline]
    fn stretch(&mut self, s: &Stretch) {
        (**self).stretch(s)
    }
    #[inline]
    fn stop(&mut self) {
        (**self).stop()
    }
    fn sample(&mut self, s: &Sample) {
        (**self).sample(s)
    }
}

/// Collects everything an engine reports, in memory and in order: the public way to look
/// at a trajectory (`runner::record` runs a whole scene into one; `runner::Simulation`
/// feeds one advance by advance). It wants events, so engines report them to it. Memory
/// grows with the run: one entry per event, segment and sample.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recorder {
    /// Junction events, in the order they happened.
    pub events: Vec<JunctionEvent>,
    /// Segments, tiling the time advanced over.
    pub segments: Vec<Segment>,
    /// Samples fed by the runner (or pushed by the caller).
    pub samples: Vec<Sample>,
}

impl Recorder {
    /// An empty recorder.
    pub fn new() -> Self {
        Recorder::default()
    }
    /// Forgets everything recorded (keeping the memory).
    pub fn clear(&mut self) {
        self.events.clear();
        self.segments.clear();
        self.samples.clear();
    }
}

impl Observer for Recorder {
    const EVENTS: bool = true;
    fn event(&mut self, e: &JunctionEvent) {
        self.events.push(*e);
    }
    fn segment(&mut self, s: &Segment) {
        self.segments.push(*s);
    }
    fn sample(&mut self, s: &Sample) {
        self.samples.push(*s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observe::report::EventKind;

    #[test]
    fn a_recorder_keeps_everything_in_order_until_cleared() {
        let mut r = Recorder::new();
        const { assert!(<Recorder as Observer>::EVENTS, "engines must report events to a recorder") };
        let e = |t| JunctionEvent { t, junction: 3, kind: EventKind::Rupture, extension: 0.5, tension: 0.1 };
        let seg = |t0| Segment { t0, t1: t0 + 1.0, ..Default::default() };
        let s = Sample { t: 2.0, x: 1.0, v: 0.5, friction: 3.0, bond_force: 2.0, attached: 4, n: 8 };
        r.event(&e(0.5));
        r.segment(&seg(0.0));
        r.event(&e(1.5));
        r.segment(&seg(1.0));
        r.sample(&s);
        assert_eq!(r.events, [e(0.5), e(1.5)]);
        assert_eq!(r.segments, [seg(0.0), seg(1.0)]);
        assert_eq!(r.samples, [s]);
        r.clear();
        assert_eq!(r, Recorder::default());
    }
}
