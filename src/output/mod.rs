//! Output files: atomic writes, CSV writers (observers), the summary and checkpoints.

pub mod atomic;
pub mod checkpoint;
pub mod csv;
pub mod state_codec;
pub mod summary;

pub use summary::Summary;
