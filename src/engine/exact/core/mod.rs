//! The one core of the exact engines ([`ExactLinear`](super::ExactLinear),
//! [`ExactSeries`](super::series::ExactSeries), [`ExactDirect`](super::ExactDirect)): each
//! is an [`Exact`] engine, the [`Core`] it shares with the others composed with a plate
//! [`Stepper`](super::stepper::Stepper) and a [`RuptureModel`](super::rupture::RuptureModel).
//!
//! - [`Core`]: the junctions ([`bags::Bags`]), the channel clocks
//!   ([`clocks`]), the frame ([`frame`]), the counters, the formation rate and
//!   the generator;
//! - [`junctions`]: formation, rupture, re-attachment, the frame's re-base
//!   ([`REBASE`]), the clocks' renewal after an event, and event emission;
//! - [`engine`]: [`Exact`] and its event loop;
//! - [`bags`], [`clocks`], [`frame`], [`pick`]: the junctions' storage, the channel clocks,
//!   the local frame and uniform picks drawn ahead, shared by every stepper and model.
//!
//! Everything is generic and `#[inline]`: an engine compiles, monomorphised for its stepper
//! and model, to what it would be with the code written into it (no `dyn`, no run-time branch
//! on the kind of engine; their constants, such as [`Stepper::WEAK_RUPTURES`](super::stepper::Stepper::WEAK_RUPTURES), fold away).

pub mod bags;
pub mod clocks;
pub mod engine;
pub mod frame;
pub mod junctions;
pub mod pick;
pub mod policy;
pub mod state;

pub use engine::Exact;
pub use policy::{REBASE, RebasePolicy, emit, reattached_extension};
pub use state::{Core, FORMATION, HORIZON, RUPTURE};
