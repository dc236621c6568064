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

pub mod moments;
pub mod observer;
pub mod piece;
pub mod regime;
pub mod report;
pub mod shifted;
pub mod stats;
pub mod stretch;

pub use observer::{Nothing, Observer, Recorder};
pub use piece::Piece;
pub use report::{EventKind, JunctionEvent, Sample, Segment};
pub use stretch::Stretch;
