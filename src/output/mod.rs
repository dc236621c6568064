//! Output files: atomic writes, CSV writers (observers), the summary and checkpoints, and
//! the hold on an output directory.

pub mod atomic;
pub mod checkpoint;
pub mod csv;
pub mod lock;
pub mod state_codec;
pub mod summary;

pub use summary::Summary;

/// `summary.json`'s name: written last, its presence means the run is complete.
pub const SUMMARY: &str = "summary.json";
/// `trace.svg`'s name: drawn from `trace.csv` once the run has ended.
pub const TRACE_SVG: &str = "trace.svg";
/// Every file a run writes into its output directory (each first as `NAME.part`).
pub const RUN_FILES: [&str; 5] = [SUMMARY, csv::TraceWriter::NAME, csv::EventWriter::NAME, TRACE_SVG, checkpoint::FILE];

/// Number of time buckets `trace.svg` thins a long trace to ([`crate::plot::trace`]): one
/// per pixel column of the 1000-pixel-wide figure or finer, so the drawn envelope is the same
/// as the full trace's (SVG coordinates are whole pixels) while the file stays small. Here,
/// beside the files it sizes, so that the output estimate does not depend on the figures.
pub const TRACE_SVG_BUCKETS: usize = 1000;
