//! Output files: atomic writes, CSV writers (observers), the summary and checkpoints, and
//! the hold on an output directory.

pub mod atomic;
pub mod checkpoint;
pub mod csv;
pub mod lock;
pub mod state_codec;
pub mod summary;

pub use summary::Summary;
