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
use crate::rng::{self, ParkMiller, PeriodExceeded, UniformSource};
use crate::scene::laws::{BondVisitor, LawVisitor, with_bond, with_force_law};
use crate::scene::{EngineKind, FlipRule, Initial, RngKind, Scene};

/// The uniforms a fixed-step run of `scene` draws in `steps` steps: `N` a step, and `N`
/// more before the first for `junctions.initial = "stationary"` (saturating at `u64::MAX`).
pub fn draws(scene: &Scene, steps: u64) -> u64 {
    let n = scene.junctions.n as u64;
    let start = if scene.junctions.initial == Initial::Stationary { n } else { 0 };
    n.saturating_mul(steps).saturating_add(start)
}

/// `Some` when `scene` runs the fixed-step engine on the Park–Miller generator and its
/// `steps` steps draw more numbers than the generator's period (the stream repeats).
pub fn park_miller_period_exceeded(scene: &Scene, steps: u64) -> Option<PeriodExceeded> {
    if scene.run.engine != EngineKind::Fixed || scene.fixed.rng != RngKind::ParkMiller {
        return None;
    }
    PeriodExceeded::of(draws(scene, steps))
}

/// The warning a run of `scene` to its `t_end` prints before it starts when it will draw
/// more than the Park–Miller generator's period ([`park_miller_period_exceeded`]).
pub fn period_warning(scene: &Scene) -> Option<String> {
    park_miller_period_exceeded(scene, scene.fixed.steps_for(scene.run.t_end)).map(|p| format!("warning: {p}"))
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes as testkit;

    /// `N` draws a step, `N` more for a stationary start; the period is exceeded from one
    /// draw past it, only by a fixed-step run on the Park–Miller generator.
    #[test]
    fn park_miller_period_is_exceeded_one_draw_past_it() {
        let n = 99_962u64;
        let lap = ParkMiller::PERIOD / n;
        let s = testkit::fig1_with(&["junctions.n=99962", "run.engine=fixed"]);
        assert_eq!(draws(&s, lap), ParkMiller::PERIOD);
        assert_eq!(park_miller_period_exceeded(&s, lap), None);
        let over = park_miller_period_exceeded(&s, lap + 1).unwrap();
        assert_eq!((over.draws, over.period), (ParkMiller::PERIOD + n, ParkMiller::PERIOD));
        let stationary = testkit::fig1_with(&["junctions.n=99962", "run.engine=fixed", "junctions.initial=stationary"]);
        assert_eq!(draws(&stationary, lap), ParkMiller::PERIOD + n);
        assert!(park_miller_period_exceeded(&stationary, lap).is_some());
        for other in ["fixed.rng=pcg", "run.engine=exact"] {
            let s = testkit::fig1_with(&["junctions.n=99962", other]);
            assert_eq!(park_miller_period_exceeded(&s, lap + 1), None, "{other}");
        }
        assert_eq!(draws(&s, u64::MAX), u64::MAX);
        // The warning counts the steps to t_end as the engine takes them.
        let t_end = format!("run.t_end={}", lap + 1);
        let at = testkit::fig1_with(&["junctions.n=99962", "run.engine=fixed", "fixed.dt=1", &t_end]);
        assert!(period_warning(&at).unwrap().starts_with("warning: the run draws 2147583608 numbers"));
        let t_end = format!("run.t_end={lap}");
        assert_eq!(period_warning(&testkit::fig1_with(&["junctions.n=99962", "fixed.dt=1", &t_end])), None);
    }
}
