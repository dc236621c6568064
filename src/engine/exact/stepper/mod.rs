//! The plate steppers of the exact engine and their contract, [`Stepper`]: how the plate
//! moves between events and reports a piece. The core composes one with a rupture model
//! ([`super::rupture`]) and does the rest ([`super::core::junctions`], [`super::core::engine`]).
//!
//! - [`linear`]: the closed form of a law whose bond force is linear in the plate position;
//! - [`series`]: the tilted law's bond force as a truncated series, the plate by a stiff
//!   integrator or Taylor steps;
//! - [`direct`]: any law, the bond force summed directly, the plate by DOP853.

pub mod contract;
pub mod direct;
pub mod linear;
pub mod series;

pub use contract::{Moved, Step, Stepper, Target, WeakRuptures};
