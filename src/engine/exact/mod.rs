//! The exact event-driven engine (issue 3): not built yet.

use super::{EngineError, EngineVisitor};
use crate::scene::Scene;

/// Builds the exact engine for `scene`.
pub fn dispatch<V: EngineVisitor>(_scene: &Scene, _visitor: V) -> Result<V::Output, EngineError> {
    Err(EngineError::Unsupported { engine: "exact", reason: "the exact engine is not implemented yet; use --engine fixed" })
}
