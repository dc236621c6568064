//! Calibration (`stickslip fit`): the free scene fields that make the simulated mean
//! friction per junction match a measured curve, with 95 % intervals.
//!
//! - [`data`]: the measured curve (`DATA.csv`), checked against the scene;
//! - [`free`]: the free parameters, their bounds and scales, unit coordinates;
//! - [`model`]: evaluations (replicas with common random numbers), the misfit, the cache
//!   and journal of evaluations;
//! - [`optimise`]: argmin's Nelder–Mead over the box of bounds;
//! - [`intervals`]: profile-likelihood intervals;
//! - [`prepare`]: a fit from the inputs of `stickslip fit` (and Python's `stickslip.fit`);
//! - [`solve`]: the whole fit (optimum, goodness of fit, intervals, band);
//! - [`report`]: its files (`fit.json`, `fit.csv`, `fit.toml`, `fit.svg`).
//!
//! The method is described in docs/calibration.md.

pub mod data;
pub mod free;
pub mod intervals;
pub mod model;
pub mod optimise;
pub mod prepare;
pub mod report;
pub mod solve;
