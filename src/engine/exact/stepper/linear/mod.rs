//! The closed-form plate stepper, for a law whose bond force is linear in the plate position:
//! the stepper ([`LinearStepper`]; the engine [`ExactLinear`] is the exact core with it and a
//! rupture model), the plate's closed form between events ([`propagator`]), what a piece of
//! it reports (`report`), and the plate's motion, dynamic or kinematic.

mod engine;
mod motion;
pub mod propagator;
mod report;

pub use engine::{ExactLinear, LinearStepper};
pub use motion::{Drive, Dynamic, Kinematic, PlateMotion};
