//! The exact engine for the `tilted` force law at O(1) cost per event (`exact.tilted =
//! "series"`, the default; and every kinematic tilted scene).
//!
//! The junctions act on the plate only through `S(y) = sum_att f^x(y - c_i)`, kept as a
//! truncated Taylor series about a base point ([`SeriesSum`]: O(p) per attach/rupture, a
//! rigorous remainder bound). Between events the plate moves by the L-stable
//! [`Rosenbrock`](crate::ode::Rosenbrock) method ([`RosenbrockPlate`]) or exactly as `y = V tau` ([`DrivenPlate`]); strong
//! bonds rupture on a channel clock, weak bonds by thinning over each plate step against
//! the linear law's envelope ([`WeakKinetics`]). The series remainder and the integrator's
//! tolerance are the engine's approximations; both are reported in `summary.json`
//! (docs/engines.md, "Plate between events (tilted law): a series, Taylor steps and a stiff integrator").
//!
//! Layout: `engine` (the kernel of the exact core: the series, its error bound, the plate
//! step with thinning), `motion` (the plate), `kinetics` (ruptures), `sum` (the series: its
//! coefficients, double-double arithmetic, the bins' and direct mode's stores with direct
//! mode's graded orders and re-base, the error bound, the wire format and the local cubic).

mod engine;
pub mod kinetics;
pub mod plate;
pub mod sum;
pub mod taylor;

pub(crate) use crate::ode::{RosenbrockConfig, RosenbrockN, StiffSystem};
pub use engine::{ExactSeries, SeriesKernel};
pub use kinetics::{Kinetics, StrongKinetics, WeakKinetics};
pub use plate::{DrivenPlate, Motion, RosenbrockPlate};
pub use sum::{DIRECT_MAX, LocalCubic, SeriesSum, tilted_taylor};

use crate::engine::{EngineError, EngineVisitor};
use crate::physics::{Bond, Tilted};
use crate::scene::Scene;
use crate::scene::laws::BondVisitor;

/// Builds the series engine for the law `law` (a law's [`SeriesLaw::tilted_form`](crate::physics::SeriesLaw::tilted_form)) on
/// `scene`, specialised to the bond kind it visits and to the plate motion (kinematic or
/// dynamic), and hands it to `visitor`.
pub(in crate::engine::exact) struct Build<'a, V> {
    pub scene: &'a Scene,
    pub law: Tilted,
    pub visitor: V,
}

impl<V: EngineVisitor> BondVisitor for Build<'_, V> {
    type Output = Result<V::Output, EngineError>;
    /// Weak bonds thin against the envelope of slope `kappa` (the tilted law's thinning slope).
    fn visit<B: Bond>(self, bond: B) -> Self::Output {
        let Self { scene, law, visitor } = self;
        let (n, e) = (scene.junctions.n, &scene.exact);
        let plate = crate::physics::Plate::from_scene(scene);
        let k0 = bond.k0();
        let event_rate = n as f64 * k0.max(scene.junctions.kon0);
        let dynamic = || RosenbrockPlate::new(plate, law.kappa * n as f64, e.rtol, e.atol, event_rate);
        let weak = || WeakKinetics::try_new(k0, bond.force_sensitivity(), law.kappa, n);
        Ok(match (B::IS_WEAK, scene.plate.kinematic) {
            (false, false) => visitor.visit(ExactSeries::new(scene, law, StrongKinetics { k0 }, dynamic()?)?),
            (false, true) => {
                visitor.visit(ExactSeries::new(scene, law, StrongKinetics { k0 }, DrivenPlate::new(plate.v))?)
            }
            (true, false) => visitor.visit(ExactSeries::new(scene, law, weak()?, dynamic()?)?),
            (true, true) => visitor.visit(ExactSeries::new(scene, law, weak()?, DrivenPlate::new(plate.v))?),
        })
    }
}
