//! The runner owns the loop: it builds the engine a scene asks for, walks it along the
//! output grid, feeds the observers (statistics, regime detector, writers) and assembles
//! the summary.
//!
//! - [`grid`]: the output grid and a walk along it;
//! - [`mod@drive`]: THE loop, [`drive_walk`], which returns why it stopped ([`Termination`]:
//!   the end, or a request on a [`StopFlag`]) with the final state and counters;
//! - [`observers`]: the core observers, the writers and the event observers of a run;
//! - [`control`]: what a run does at grid stops (progress, flushes, checkpoints);
//! - [`run`]: a run from start to end ([`run_scene`]), and its [`summarize`]d results;
//! - [`plan`]: what a run is and where it starts ([`RunOptions`]);
//! - [`checkpoint`]: writing checkpoints; [`mod@resume`]: [`resume()`], continuing from one;
//!   [`progress`]: progress on stderr;
//! - [`simulation`]: [`Simulation`], an engine whose type is chosen from the scene behind
//!   one handle; [`record`](mod@record): [`record()`], everything a run reports, in memory;
//! - [`mod@error`]: why a run failed ([`RunError`]).
//!
//! Long runs (docs/runs.md): outputs are streamed to `NAME.part` and flushed at line
//! boundaries at least every [`FLUSH_EVERY`]; with [`RunOptions::checkpoint_every`] the
//! runner writes `checkpoint.bin` at output-grid stops, from which [`resume()`] continues a
//! killed run to the same bytes.

pub mod checkpoint;
pub mod control;
pub mod drive;
pub mod error;
pub mod grid;
pub mod observers;
pub mod plan;
pub mod progress;
pub mod record;
pub mod resume;
pub mod run;
pub mod simulation;

pub use control::FLUSH_EVERY;
pub use drive::{Outcome, StopFlag, Termination, check_finite, drive, drive_walk};
pub use error::RunError;
pub use grid::{GridPosition, OutputGrid, Stop, Walk};
pub use observers::{CoreObservers, EventObservers, core_observers};
pub use plan::RunOptions;
pub use record::{Recording, record};
pub use resume::{ResumeError, Resumed, resume};
pub use run::{run_scene, run_scene_with, summarize};
pub use simulation::{Observed, Simulation, StateError};
