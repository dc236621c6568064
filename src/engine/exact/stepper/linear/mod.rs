//! The exact engine for a law whose bond force is linear in the plate position: the engine
//! ([`ExactLinear`], the exact core with the closed-form plate and the rupture kinetics as
//! its kernel), the plate's closed form between events ([`propagator`]) and what a piece of
//! it reports (`report`).

mod engine;
mod path;
pub mod propagator;
mod report;

pub use engine::{ExactLinear, LinearKernel};
