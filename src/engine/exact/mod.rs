//! The exact event-driven kinetic Monte Carlo engine.
//!
//! Junction rupture and formation events are drawn from their exact, continuously
//! changing rates, with no time step; the plate moves in closed form between events
//! (`linear` law) or, for the `tilted` law, by an L-stable integrator on a truncated series
//! of the bond force ([`series`]) or, as the O(N) reference, by DOP853 on the direct sum
//! ([`tilted`]), each with a stated tolerance. See `docs/engines.md`.
//!
//! Why no junction needs its own clock: every rate of the model is either shared by all
//! junctions of a state (strong rupture `k0`, formation `kon0 g(v)`) or, for weak bonds,
//! a shared time factor times a per-junction constant weight (`k0 exp(a |y(t) - c_i|)`,
//! bounded by `exp(a y_hi) exp(-a c_i) + exp(-a y_lo) exp(a c_i)`), so one channel clock
//! per kind of event plus a sum tree for the weighted choice is exact and cheaper than a
//! clock per junction.

pub mod bags;
pub mod clocks;
pub mod frame;
pub mod linear;
pub mod motion;
pub mod pick;
pub mod rupture;
pub mod series;
pub mod sumtree;
pub mod tilted;

use super::{EngineError, EngineVisitor};
use crate::physics::{Strong, Weak};
use crate::scene::{BondKind, ForceLawKind, Scene, TiltedMethod};

pub use clocks::{ArrayQueue, ChannelQueue, PqQueue};
pub use linear::ExactLinear;
pub use motion::{Dynamic, Kinematic, PlateMotion};
pub use rupture::{StrongRupture, WeakRupture};
pub use tilted::ExactTilted;

/// The event queue the engine uses (chosen by `benches/exact.rs`, see docs/performance.md).
pub type DefaultQueue = ArrayQueue;

/// The exact engine for a `linear`-law scene with strong bonds.
pub fn strong_linear<Q: ChannelQueue>(scene: &Scene) -> ExactLinear<StrongRupture, Q> {
    strong_linear_with::<Q, Dynamic>(scene)
}

/// The exact engine for a `linear`-law scene with weak bonds.
pub fn weak_linear<Q: ChannelQueue>(scene: &Scene) -> ExactLinear<WeakRupture, Q> {
    weak_linear_with::<Q, Dynamic>(scene)
}

/// [`strong_linear`] with plate motion `M` ([`Kinematic`] for `plate.kinematic`).
pub fn strong_linear_with<Q: ChannelQueue, M: PlateMotion>(scene: &Scene) -> ExactLinear<StrongRupture, Q, M> {
    ExactLinear::new(scene, |rng| StrongRupture::new(scene.junctions.k0, rng))
}

/// [`weak_linear`] with plate motion `M` ([`Kinematic`] for `plate.kinematic`).
pub fn weak_linear_with<Q: ChannelQueue, M: PlateMotion>(scene: &Scene) -> ExactLinear<WeakRupture, Q, M> {
    let j = &scene.junctions;
    ExactLinear::new(scene, |_| WeakRupture::new(j.k0, j.beta_dx() * j.kappa, j.n))
}

/// Builds the exact engine for `scene`, specialised to its force law and bond kind: for the
/// tilted law, the series engine ([`series`]) unless `exact.tilted = "direct"` (the O(N)
/// reference [`ExactTilted`], which has no kinematic plate).
pub fn dispatch<V: EngineVisitor>(scene: &Scene, visitor: V) -> Result<V::Output, EngineError> {
    let kinematic = scene.plate.kinematic;
    match (scene.junctions.force_law, scene.junctions.bond) {
        (ForceLawKind::Linear, BondKind::Strong) if kinematic => {
            Ok(visitor.visit(strong_linear_with::<DefaultQueue, Kinematic>(scene)))
        }
        (ForceLawKind::Linear, BondKind::Weak) if kinematic => {
            Ok(visitor.visit(weak_linear_with::<DefaultQueue, Kinematic>(scene)))
        }
        (ForceLawKind::Linear, BondKind::Strong) => Ok(visitor.visit(strong_linear::<DefaultQueue>(scene))),
        (ForceLawKind::Linear, BondKind::Weak) => Ok(visitor.visit(weak_linear::<DefaultQueue>(scene))),
        (ForceLawKind::Tilted, _) if scene.exact.tilted == TiltedMethod::Series || scene.plate.kinematic => {
            series::dispatch(scene, visitor)
        }
        (ForceLawKind::Tilted, BondKind::Strong) => {
            Ok(visitor.visit(ExactTilted::new(scene, Strong::from_scene(scene))?))
        }
        (ForceLawKind::Tilted, BondKind::Weak) => Ok(visitor.visit(ExactTilted::new(scene, Weak::from_scene(scene))?)),
    }
}
