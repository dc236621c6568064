//! The exact engine for a law whose bond force is linear in the plate position: the engine
//! ([`ExactLinear`], event loop and bookkeeping) and the plate's closed form between events
//! ([`propagator`]).

mod engine;
pub mod propagator;

pub use engine::ExactLinear;
