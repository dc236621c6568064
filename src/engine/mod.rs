//! Engines: the *methods* that advance a scene. The runner owns the loop, the output grid
//! and the observers; an engine only advances to the time it is asked for and reports
//! what happened on the way.

pub mod alloc;
pub mod contract;
pub mod exact;
pub mod fixed;

pub use contract::{Counters, Engine, EngineError, EngineVisitor};

use crate::scene::{EngineKind, Scene};

/// Builds the engine the scene asks for (`run.engine`), specialised to the scene's force
/// law, bond kind and options, and hands it to `visitor`.
pub fn with_engine<V: EngineVisitor>(scene: &Scene, visitor: V) -> Result<V::Output, EngineError> {
    // Every engine has a kinematic plate: the fixed engine (both laws), the exact linear
    // engine (`ExactLinear<_, _, Kinematic>`) and the exact tilted law's series engine.
    match scene.run.engine {
        EngineKind::Fixed => fixed::dispatch(scene, visitor),
        EngineKind::Exact => exact::dispatch(scene, visitor),
    }
}
