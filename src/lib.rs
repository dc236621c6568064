//! `stickslip`: friction from the formation and rupture of junctions between two surfaces
//! (the Filippov–Klafter–Urbakh bond model), simulated by an exact event-driven kinetic
//! Monte Carlo engine and by the letter's fixed-step scheme.
//!
//! Layout: [`scene`] is the problem (validated parameters), [`physics`] the model's pure
//! functions, [`engine`] the methods that advance a scene, [`runner`] the loop that drives
//! an engine along the output grid and feeds the [`observe`]rs and [`output`] writers;
//! [`studies`] run many scenes (sweeps, work-precision comparisons) and [`plot`] draws
//! their figures.

pub mod cli;
pub mod engine;
pub mod estimate;
pub mod observe;
pub mod ode;
pub mod output;
pub mod physics;
pub mod plot;
pub mod propagator;
pub mod rng;
pub mod runner;
pub mod scene;
pub mod stability;
pub mod studies;
#[cfg(test)]
mod test_scenes;

pub use runner::{RunError, run_scene};
pub use scene::{Scene, SceneError};
