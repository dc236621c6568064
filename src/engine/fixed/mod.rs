//! The fixed-step compatibility engine: the letter's eq. 5 scheme (docs/engines.md, "The
//! fixed-step engine").
//!
//! - [`dispatch`] resolves the scene's options into type parameters once per run;
//! - [`engine`] holds the state and the step;
//! - [`flip`] the flip rules, [`integrator`] the plate integrators.

pub mod engine;
pub mod flip;
pub mod integrator;

pub use engine::{DIVERGENCE_LIMIT, FixedEngine, Generator, Law, Rupture};
pub use flip::{AsPrintedFlip, ExponentialFlip, Flip, LinearFlip};
pub use integrator::Integrator;

use super::{EngineError, EngineVisitor};
use crate::physics::{Linear, Strong, Tilted, Weak};
use crate::rng::{self, ParkMiller};
use crate::scene::{BondKind, FlipRule, ForceLawKind, RngKind, Scene};

/// Builds the fixed-step engine for `scene` and hands it to `visitor`.
///
/// Force law, bond kind, generator and flip rule become type parameters here, once per
/// run, so the step loop is compiled for exactly that combination (a strong-bond scene runs
/// no weak-bond code). The generator is `ParkMiller` seeded with `run.seed` (which must lie
/// in `[1, 2^31 - 2]`) or `Pcg64` from [`rng::pcg`]`(run.seed)`.
pub fn dispatch<V: EngineVisitor>(scene: &Scene, visitor: V) -> Result<V::Output, EngineError> {
    match scene.junctions.force_law {
        ForceLawKind::Linear => with_law(scene, Linear::from_scene(scene), visitor),
        ForceLawKind::Tilted => with_law(scene, Tilted::from_scene(scene), visitor),
    }
}

fn with_law<L: Law, V: EngineVisitor>(scene: &Scene, law: L, visitor: V) -> Result<V::Output, EngineError> {
    match scene.junctions.bond {
        BondKind::Strong => with_bond(scene, law, Strong::from_scene(scene), visitor),
        BondKind::Weak => with_bond(scene, law, Weak::from_scene(scene), visitor),
    }
}

fn with_bond<L: Law, B: Rupture, V: EngineVisitor>(
    scene: &Scene,
    law: L,
    bond: B,
    visitor: V,
) -> Result<V::Output, EngineError> {
    let seed = scene.run.seed;
    match scene.fixed.rng {
        RngKind::ParkMiller => {
            let rng = ParkMiller::new(seed).map_err(|_| EngineError::Unsupported {
                engine: "fixed",
                reason: "run.seed must lie in [1, 2^31 - 2] for the Park-Miller generator",
            })?;
            Ok(with_rng(scene, law, bond, rng, visitor))
        }
        RngKind::Pcg => Ok(with_rng(scene, law, bond, rng::pcg(seed), visitor)),
    }
}

fn with_rng<L: Law, B: Rupture, R: Generator, V: EngineVisitor>(
    scene: &Scene,
    law: L,
    bond: B,
    rng: R,
    visitor: V,
) -> V::Output {
    match scene.fixed.flip {
        FlipRule::Linear => visitor.visit(FixedEngine::new(scene, law, bond, rng, LinearFlip)),
        FlipRule::Exponential => visitor.visit(FixedEngine::new(scene, law, bond, rng, ExponentialFlip)),
        FlipRule::AsPrinted => visitor.visit(FixedEngine::new(scene, law, bond, rng, AsPrintedFlip)),
    }
}
