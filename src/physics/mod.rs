//! The model's physics as pure functions of state and parameters: no randomness, no
//! clock, no I/O, no scene format. Engines own time and randomness and call these;
//! `scene::laws` builds them from a scene.

pub mod bond;
pub mod force;
pub mod plate;
pub mod rates;
pub mod series;

pub use bond::{Bond, BondParams, Strong, Weak};
pub use force::{ExactMethod, ForceLaw, LawParams, Linear, ParamError, Tilted};
pub use plate::Plate;
pub use rates::Formation;
pub use series::{LocalCubic, SeriesSum, tilted_taylor};
