//! `stickslip`: friction from the formation and rupture of junctions between two surfaces
//! (the Filippov–Klafter–Urbakh bond model), simulated by an exact event-driven kinetic
//! Monte Carlo engine and by the letter's fixed-step scheme.
//!
//! Code map (every module):
//!
//! - [`scene`]: the problem: a scene file, its validation into typed parameters, and the one
//!   table of force laws and bond kinds (`scene::laws`);
//! - [`physics`]: the model's pure functions: force laws and bond kinds (each with its table),
//!   formation rate, plate, the weak-bond rate's exponential;
//! - [`engine`]: the methods that advance a scene: [`engine::fixed`] (the letter's
//!   fixed-step scheme, and [`engine::fixed::stability`], where each of its plate integrators
//!   is stable) and [`engine::exact`] (event-driven kinetic Monte Carlo: one core, with the
//!   event loop and the junctions' bookkeeping, composing a plate stepper (the closed form
//!   with its propagator, the series with its bond-force series, the direct sum) with a
//!   rupture model (strong; weak from a sum tree or from bins));
//! - [`ode`]: the adaptive integrators the exact engines use (DOP853, Rosenbrock);
//! - [`rng`]: the named, portable random generators (Park–Miller, PCG);
//! - [`runner`]: the loop that drives an engine along the output grid and feeds the
//!   [`observe`]rs (statistics, regime detector) and the [`output`] writers (CSV,
//!   `summary.json`, checkpoints);
//! - [`estimate`]: memory, work and output-size estimates made before a run, and the checks
//!   that refuse what will not fit;
//! - [`studies`]: many scenes at once: sweeps, work-precision comparisons;
//! - [`fit`]: calibration: scene fields fitted to a measured friction curve, with intervals;
//! - [`plot`]: the figures of runs and studies (SVG), and the files of studies and fits
//!   written with their figure ([`plot::files`]);
//! - [`cli`]: the `stickslip` command line, and the text of its reports (such as the
//!   stability table).

pub mod cli;
pub mod engine;
pub mod estimate;
pub mod fit;
pub mod observe;
pub mod ode;
pub mod output;
pub mod physics;
pub mod plot;
pub mod rng;
pub mod runner;
pub mod scene;
pub mod studies;
#[cfg(test)]
mod test_scenes;

pub use runner::{RunError, run_scene};
pub use scene::{Scene, SceneError};
