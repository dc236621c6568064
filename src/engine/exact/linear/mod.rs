//! The exact engine for a law whose bond force is linear in the plate position: the engine
//! ([`ExactLinear`], the exact core with the closed-form plate and the rupture kinetics as
//! its kernel) and the plate's closed form between events ([`propagator`]).

mod engine;
pub mod propagator;

pub use engine::{ExactLinear, LinearKernel};
