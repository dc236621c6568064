//! Studies: many runs of one scene, varied and replicated, with statistics across runs.
//!
//! - [`sweep`]: one scene field swept over a list of values, with replicas (`stickslip sweep`).
//! - [`seeds`]: how each run's seed is derived from the scene's seed.

pub mod seeds;
pub mod sweep;
