//! Studies: many runs of one scene, varied and replicated, with statistics across runs.
//!
//! - [`sweep`]: scene fields swept over values, with replicas (`stickslip sweep`).
//! - [`law`]: a friction law for continuum codes from a velocity-temperature map
//!   (`stickslip friction-law`).
//! - [`compare`]: error against run time of the fixed-step and exact engines
//!   (`stickslip compare`).
//! - [`scaling`]: one scene at growing `N` in both engines, timed (`stickslip bench`).
//! - [`seeds`]: how each run's seed is derived from the scene's seed (one mixer for all).
//! - [`stats`]: statistics across replicas (means, spreads, Student-t intervals).
//! - [`format`](mod@format): numbers as text for reports.
//! - [`journal`]: the journal of finished runs a study keeps in its output directory, and
//!   [`execute`]: running the runs it does not hold yet, stoppable.
//!
//! Layers, each depending only on those before it: a study's data (plan, runs, outcome,
//! tables) -> its figure ([`crate::plot`], which reads the outcome and draws) -> its files
//! ([`crate::plot::files`]: tables and figure written to disk) -> the CLI.

pub mod compare;
pub mod execute;
pub mod format;
pub mod journal;
pub mod law;
pub mod scaling;
pub mod seeds;
pub mod stats;
pub mod sweep;
