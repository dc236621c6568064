//! The exact engine for the `tilted` force law at O(1) cost per event (`exact.tilted =
//! "series"`, the default; and every kinematic tilted scene).
//!
//! The junctions act on the plate only through `S(y) = sum_att f^x(y - c_i)`, kept as a
//! truncated Taylor series about a base point ([`SeriesSum`]: O(p) per attach/rupture, a
//! rigorous remainder bound). Between events the plate moves by the L-stable
//! [`Rosenbrock`](crate::ode::Rosenbrock) method ([`RosenbrockPlate`]) or exactly as `y = V tau` ([`DrivenPlate`]); strong
//! bonds rupture on a channel clock, weak bonds by thinning over each plate step against
//! the envelope of slope `kappa` (any weak-bond rupture model, [`crate::engine::exact::rupture::thin()`];
//! the tilted law's acceptance is [`TiltedRate`](crate::engine::exact::rupture::TiltedRate)). The series remainder and the integrator's
//! tolerance are the engine's approximations; both are reported in `summary.json`
//! (docs/engines.md, "Plate between events (tilted law): a series, Taylor steps and a stiff integrator").
//!
//! Layout: `engine` (the stepper of the exact core: the series, its error bound, the plate
//! step), `plate` (the plate's motions), `taylor` (Taylor steps), `sum` (the series: its
//! coefficients, double-double arithmetic, the bins' and direct mode's stores with direct
//! mode's graded orders and re-base, the error bound, the wire format and the local cubic).

mod engine;
pub mod plate;
pub mod sum;
pub mod taylor;

pub use engine::{ExactSeries, PREFETCH_MIN_N, SeriesStepper};
pub use plate::{DrivenPlate, Motion, RosenbrockPlate};
pub use sum::{DIRECT_MAX, LocalCubic, SeriesSum, tilted_taylor};

use crate::engine::exact::rupture::binned::uses_bins;
use crate::engine::exact::rupture::{BinnedRupture, StrongRupture, TreeRupture};
use crate::engine::{EngineError, EngineVisitor};
use crate::physics::{Bond, Tilted};
use crate::scene::Scene;
use crate::scene::laws::BondVisitor;

/// Builds the series engine for the law `law` (a law's [`SeriesLaw::tilted_form`](crate::physics::SeriesLaw::tilted_form)) on
/// `scene`, specialised to the bond kind it visits and to the plate motion (kinematic or
/// dynamic), and hands it to `visitor`.
pub(crate) struct Build<'a, V> {
    pub scene: &'a Scene,
    pub law: Tilted,
    pub visitor: V,
}

impl<V: EngineVisitor> BondVisitor for Build<'_, V> {
    type Output = Result<V::Output, EngineError>;
    /// Weak bonds thin against the envelope of slope `kappa` (the tilted law's thinning slope),
    /// their candidates drawn from bins of anchors from [`BINNED_FROM`](crate::engine::exact::BINNED_FROM) junctions on, from a
    /// sum tree below.
    fn visit<B: Bond>(self, bond: B) -> Self::Output {
        let Self { scene, law, visitor } = self;
        let (n, e) = (scene.junctions.n, &scene.exact);
        let plate = crate::physics::Plate::from_scene(scene);
        let (k0, beta_dx) = (bond.k0(), bond.force_sensitivity());
        let a = beta_dx * law.kappa;
        let event_rate = n as f64 * k0.max(scene.junctions.kon0);
        let dynamic = || RosenbrockPlate::new(plate, law.kappa * n as f64, e.rtol, e.atol, event_rate);
        let driven = || DrivenPlate::new(plate.v);
        let strong = |rng: &mut _| Ok(StrongRupture::<false>::new(k0, rng));
        let binned = |rng: &mut _| BinnedRupture::try_new(k0, a, n, rng);
        let tree = |_: &mut _| TreeRupture::try_new(k0, a, n);
        let bins = uses_bins(n);
        Ok(match (B::IS_WEAK, bins, scene.plate.kinematic) {
            (false, _, false) => visitor.visit(ExactSeries::new(scene, law, beta_dx, strong, dynamic()?)?),
            (false, _, true) => visitor.visit(ExactSeries::new(scene, law, beta_dx, strong, driven())?),
            (true, true, false) => visitor.visit(ExactSeries::new(scene, law, beta_dx, binned, dynamic()?)?),
            (true, true, true) => visitor.visit(ExactSeries::new(scene, law, beta_dx, binned, driven())?),
            (true, false, false) => visitor.visit(ExactSeries::new(scene, law, beta_dx, tree, dynamic()?)?),
            (true, false, true) => visitor.visit(ExactSeries::new(scene, law, beta_dx, tree, driven())?),
        })
    }
}
