//! Estimates of what a run needs before it starts: peak memory (the engine's state per
//! junction for its engine, bond kind and force law, plus buffers), the expected number of
//! steps or events, and the size of each output file; and the checks that refuse a run the
//! machine cannot hold ([`check`]). `stickslip validate` prints the estimates; `run`,
//! `sweep` and `compare` check them first (docs/runs.md, "Memory and disk: estimated
//! before a run starts"). [`Estimate`] (in `run.rs`) gathers them for one run.

pub mod check;
pub mod memory;
pub mod outputs;
mod run;
pub mod system;
pub mod work;

pub use check::{ResourceError, check_run, fit_threads, threads_for};
pub use memory::{BASELINE_BYTES, Method, Part};
pub use outputs::OutputFile;
pub use run::{Estimate, bytes};
pub use system::{Available, available_memory, free_disk};
pub use work::Work;
