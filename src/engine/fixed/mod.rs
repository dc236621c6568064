//! The fixed-step compatibility engine: the letter's eq. 5 scheme (docs/engines.md, "The
//! fixed-step engine").
//!
//! - [`dispatch`] resolves the scene's options into type parameters once per run;
//! - [`engine`] holds the state and the step, [`chunk`] the step's pass over one chunk of
//!   junctions, [`team`] the threads that share the chunks, `stored` the state's serde form;
//! - [`flip`] the flip rules, [`integrator`] the plate integrators, [`stability`] their
//!   stability limits at a scene's parameters (`stickslip stability`).

pub mod chunk;
pub mod engine;
pub mod flip;
pub mod integrator;
pub mod stability;
mod stored;
pub mod team;

pub use chunk::CHUNK;
pub use engine::{DIVERGENCE_LIMIT, FixedEngine};
pub use flip::{AsPrintedFlip, ExponentialFlip, Flip, LinearFlip};
pub use integrator::Integrator;
pub use team::PARALLEL_MIN;

use super::contract::{EngineError, EngineVisitor};
use crate::physics::{Bond, ForceLaw};
use crate::rng::{self, ParkMiller, UniformSource};
use crate::scene::laws::{BondVisitor, LawVisitor, with_bond, with_force_law};
use crate::scene::{FlipRule, RngKind, Scene};

/// Builds the fixed-step engine for `scene` and hands it to `visitor`.
///
/// Force law, bond kind (both from `scene::laws`), generator and flip rule become type
/// parameters here, once per run, so the step loop is compiled for exactly that combination
/// (a strong-bond scene runs no weak-bond code). The generator is `ParkMiller` seeded with
/// `run.seed` (which must lie in `[1, 2^31 - 2]`) or `Pcg64` from [`rng::pcg`]`(run.seed)`.
pub fn dispatch<V: EngineVisitor>(scene: &Scene, visitor: V) -> Result<V::Output, EngineError> {
    with_force_law(&scene.junctions, WithLaw { scene, visitor })?
}

struct WithLaw<'a, V> {
    scene: &'a Scene,
    visitor: V,
}

impl<V: EngineVisitor> LawVisitor for WithLaw<'_, V> {
    type Output = Result<V::Output, EngineError>;
    fn visit<L: ForceLaw>(self, law: L) -> Self::Output {
        let Self { scene, visitor } = self;
        with_bond(&scene.junctions, WithBond { scene, law, visitor })?
    }
}

struct WithBond<'a, L, V> {
    scene: &'a Scene,
    law: L,
    visitor: V,
}

impl<L: ForceLaw, V: EngineVisitor> BondVisitor for WithBond<'_, L, V> {
    type Output = Result<V::Output, EngineError>;
    fn visit<B: Bond>(self, bond: B) -> Self::Output {
        let Self { scene, law, visitor } = self;
        let seed = scene.run.seed;
        match scene.fixed.rng {
            RngKind::ParkMiller => {
                let rng = ParkMiller::new(seed).map_err(|_| EngineError::Unsupported {
                    engine: "fixed",
                    reason: "run.seed must lie in [1, 2^31 - 2] for the Park-Miller generator",
                })?;
                with_rng(scene, law, bond, rng, visitor)
            }
            RngKind::Pcg => with_rng(scene, law, bond, rng::pcg(seed), visitor),
        }
    }
}

fn with_rng<L: ForceLaw, B: Bond, R, V: EngineVisitor>(
    scene: &Scene,
    law: L,
    bond: B,
    rng: R,
    visitor: V,
) -> Result<V::Output, EngineError>
where
    R: UniformSource + Clone + std::fmt::Debug + serde::Serialize + serde::de::DeserializeOwned + Send + 'static,
{
    Ok(match scene.fixed.flip {
        FlipRule::Linear => visitor.visit(FixedEngine::try_new(scene, law, bond, rng, LinearFlip)?),
        FlipRule::Exponential => visitor.visit(FixedEngine::try_new(scene, law, bond, rng, ExponentialFlip)?),
        FlipRule::AsPrinted => visitor.visit(FixedEngine::try_new(scene, law, bond, rng, AsPrintedFlip)?),
    })
}
