//! The integration tests, one test binary: each module is one topic (its file says which).
//! A test that needs its own process (a global allocator) lives beside this folder, in
//! `tests/ode_alloc.rs`. Run one topic with `cargo test --release --test suite MODULE::`.

mod common;
mod ode_support;
mod rosenbrock_support;

mod cli_bad_input;
mod cli_output;
mod compare;
mod convergence;
mod creep;
mod docs;
mod estimate;
mod exact_invariants;
mod exact_stats;
mod extreme;
mod fit;
mod fixed_convergence;
mod fixed_scheme;
mod fixed_statistics;
mod friction_law;
mod house;
mod kinds;
mod kinematic;
mod law_extension;
mod ode_accuracy;
mod ode_convergence;
mod ode_errors;
mod ode_events;
mod ode_state;
mod out_lock;
mod propagator_props;
mod regime;
mod renewal;
mod resume;
mod rosenbrock;
mod run_fuzz;
mod rupture_models;
mod scaling;
mod scenarios;
mod scene_fuzz;
mod series_engine;
mod series_props;
mod study_resume;
mod sumtree_props;
mod sweep;
mod thermal;
mod tilted_series;
mod unstable;
mod validate_scenarios;
