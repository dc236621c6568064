//! The model's physics as pure functions of state and parameters: no randomness, no
//! clock, no I/O, no scene format. Engines own time and randomness and call these;
//! `scene::laws` builds them from a scene.

pub mod bond;
pub mod exp;
pub mod force;
pub mod plate;
pub mod rates;

pub use bond::{Bond, BondKind, BondParams, BondVisitor, Strong, Weak};
pub use force::{
    ClosedForm, Direct, ExactMethod, ExactMethodOf, ForceLaw, ForceLawKind, LawParams, LawVisitor, Linear, LinearLaw,
    MethodVisitor, ParamError, Series, SeriesLaw, Tilted, exact_method,
};
pub use plate::Plate;
pub use rates::Formation;
