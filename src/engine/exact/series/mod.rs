//! The exact engine for the `tilted` force law at O(1) cost per event (`exact.tilted =
//! "series"`, the default; and every kinematic tilted scene).
//!
//! The junctions act on the plate only through `S(y) = sum_att f^x(y - c_i)`, kept as a
//! truncated Taylor series about a base point ([`SeriesSum`]: O(p) per attach/rupture, a
//! rigorous remainder bound). Between events the plate moves by the L-stable
//! [`Rosenbrock`](crate::ode::Rosenbrock) method ([`Dynamic`]) or exactly as `y = V tau` ([`Kinematic`]); strong
//! bonds rupture on a channel clock, weak bonds by thinning over each plate step against
//! the linear law's envelope ([`WeakKinetics`]). The series remainder and the integrator's
//! tolerance are the engine's approximations; both are reported in `summary.json`
//! (docs/engines.md, "Plate between events (tilted law): a series and a stiff integrator").
//!
//! Layout: `engine` (event loop, bookkeeping), `motion` (the plate), `kinetics` (ruptures).

mod engine;
pub mod kinetics;
pub mod motion;

pub(crate) use crate::ode::{RosenbrockConfig, RosenbrockN, StiffSystem};
pub(crate) use crate::physics::SeriesSum;
pub use engine::ExactSeries;
pub use kinetics::{Kinetics, StrongKinetics, WeakKinetics};
pub use motion::{Dynamic, Kinematic, Motion};

use crate::engine::{EngineError, EngineVisitor};
use crate::scene::{BondKind, Scene};

/// Builds the series engine for a tilted-law `scene`, specialised to its bond kind and
/// plate motion (kinematic or dynamic), and hands it to `visitor`.
pub fn dispatch<V: EngineVisitor>(scene: &Scene, visitor: V) -> Result<V::Output, EngineError> {
    let j = &scene.junctions;
    let e = &scene.exact;
    let plate = crate::physics::Plate::from_scene(scene);
    match (j.bond, scene.plate.kinematic) {
        (BondKind::Strong, false) => Ok(visitor.visit(ExactSeries::new(
            scene,
            StrongKinetics { k0: j.k0 },
            Dynamic::new(plate, j.kappa * j.n as f64, e.rtol, e.atol)?,
        )?)),
        (BondKind::Strong, true) => {
            Ok(visitor.visit(ExactSeries::new(scene, StrongKinetics { k0: j.k0 }, Kinematic::new(plate.v))?))
        }
        (BondKind::Weak, false) => Ok(visitor.visit(ExactSeries::new(
            scene,
            WeakKinetics::try_new(j.k0, j.beta_dx(), j.kappa, j.n)?,
            Dynamic::new(plate, j.kappa * j.n as f64, e.rtol, e.atol)?,
        )?)),
        (BondKind::Weak, true) => Ok(visitor.visit(ExactSeries::new(
            scene,
            WeakKinetics::try_new(j.k0, j.beta_dx(), j.kappa, j.n)?,
            Kinematic::new(plate.v),
        )?)),
    }
}
