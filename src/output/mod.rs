//! Output files: atomic writes, CSV writers (observers) and the summary.

pub mod atomic;
pub mod csv;
pub mod summary;

pub use summary::Summary;
