//! What engines report, and the observers that receive it.
//!
//! Engines report three things:
//! - [`Segment`]s: time integrals of the observables over consecutive pieces of the
//!   trajectory that tile `[0, t]` (between events for the exact engine, one step for the
//!   fixed engine). Window statistics are built from these, so they are exact integrals
//!   of the engine's trajectory, not averages of a sampled trace. An engine that has the
//!   raw integrals of a piece reports a [`Piece`] instead ([`Observer::piece`]), which an
//!   observer turns into a segment ([`Piece::segment`]) or sums as it is.
//! - [`JunctionEvent`]s: ruptures and formations, only when an observer wants them
//!   ([`Observer::EVENTS`] is a constant, so engines compile the event path away otherwise).
//! - [`Sample`]s: the state on the runner's output grid.
//!
//! - [`Stretch`]es ([`Observer::stretch`]): for an observer that takes them
//!   ([`Observer::STRETCHES`]), an engine may sum the pieces inside
//!   `[integrals_after, stretch_until]` itself and report them once per advance.
//! - Grid stops ([`Observer::stop`]): the runner's loop says when the engine stands at one,
//!   so that an observer may fold what it has summed since the last.
//!
//! Observers are combined with tuples and dispatched statically.

pub mod piece;
pub mod regime;
pub mod shifted;
pub mod stats;
pub mod stretch;

pub use piece::Piece;
pub use stretch::Stretch;

use serde::{Deserialize, Serialize};

/// The state at one instant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Time `t`.
    pub t: f64,
    /// Plate position `X`.
    pub x: f64,
    /// Plate velocity `Xd`.
    pub v: f64,
    /// Driving-spring force `F = K (V t - X)` (the friction force; with a kinematic plate, `F_b`).
    pub friction: f64,
    /// Bond force `F_b = sum_i q_i f_i^x`.
    pub bond_force: f64,
    /// Number of attached junctions.
    pub attached: u64,
    /// Number of junctions `N`.
    pub n: u64,
}

impl Sample {
    /// `n(t) = attached / N`.
    pub fn attached_fraction(&self) -> f64 {
        self.attached as f64 / self.n as f64
    }
}

/// Kind of a junction event.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EventKind {
    Rupture,
    Formation,
}

impl EventKind {
    pub fn as_str(self) -> &'static str {
        match self {
            EventKind::Rupture => "rupture",
            EventKind::Formation => "formation",
        }
    }
}

/// One junction switching state.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JunctionEvent {
    /// Time of the event (for the fixed engine, the start of the step in which it flipped).
    pub t: f64,
    /// Junction index in `0..N`.
    pub junction: u32,
    pub kind: EventKind,
    /// Extension `x_i` at the event (after re-attachment rules are applied, for formations).
    pub extension: f64,
    /// Tension `f_i` at the event.
    pub tension: f64,
}

/// Time integrals of the observables over one piece `[t0, t1]` of the trajectory.
///
/// Means are `(1/h) int_{t0}^{t1} (.) dt` with `h = t1 - t0`; `friction_m2` is
/// `int (F - friction)^2 dt`, so variances combine without cancellation (Chan et al.).
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct Segment {
    pub t0: f64,
    pub t1: f64,
    /// Mean driving-spring force `F = K (V t - X)` over the segment (kinematic plate: mean `F_b`).
    pub friction: f64,
    /// `int (F - mean)^2 dt` over the segment (>= 0).
    pub friction_m2: f64,
    /// Mean bond force `F_b`.
    pub bond_force: f64,
    /// Mean viscous force `eta Xd`.
    pub viscous: f64,
    /// Attached count (constant on a segment).
    pub attached: u64,
}

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
    /// statistics; `+inf` for an observer that reads times or samples only.
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
