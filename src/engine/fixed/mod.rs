//! The fixed-step compatibility engine (being built).

use super::{EngineError, EngineVisitor};
use crate::scene::Scene;

/// Builds the fixed-step engine for `scene`.
pub fn dispatch<V: EngineVisitor>(_scene: &Scene, _visitor: V) -> Result<V::Output, EngineError> {
    Err(EngineError::Unsupported { engine: "fixed", reason: "not built yet" })
}
