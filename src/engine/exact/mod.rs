//! The exact event-driven kinetic Monte Carlo engine.
//!
//! Junction rupture and formation events are drawn from their exact, continuously
//! changing rates, with no time step; the plate moves in closed form between events
//! (`linear` law) or, for the `tilted` law, by an L-stable integrator on a truncated series
//! of the bond force ([`series`]) or, for any law and as the tilted law's O(N) reference, by
//! DOP853 on the direct sum ([`stepper::direct`]), each with a stated tolerance. The law's
//! type picks the method ([`ForceLaw::Exact`]; a law gets the closed form or the series only
//! by implementing [`LinearLaw`] or [`SeriesLaw`]; see `docs/engines.md`).
//!
//! Layout: [`core`] (the event loop and the junctions' bookkeeping, and what every engine
//! shares: bags, clocks, frame, picks) composes a plate stepper from [`stepper`] (`linear`,
//! `series`, `direct`) with a rupture model from [`rupture`] (strong; weak from a sum tree or
//! from bins, over a closed-form horizon or a plate step; the direct stepper's hazard).
//!
//! Why no junction needs its own clock: every rate of the model is either shared by all
//! junctions of a state (strong rupture `k0`, formation `kon0 g(v)`) or, for weak bonds,
//! a shared time factor times a per-junction constant weight (`k0 exp(a |y(t) - c_i|)`,
//! bounded by `exp(a y_hi) exp(-a c_i) + exp(-a y_lo) exp(a c_i)`), so one channel clock
//! per kind of event plus a sum tree (or bins) for the weighted choice is exact and cheaper
//! than a clock per junction.

pub mod core;
pub mod rupture;
pub mod stepper;

use super::contract::{EngineError, EngineVisitor};
use crate::physics::{
    Bond, ExactMethod, ExactMethodOf, ForceLaw, LawParams, Linear, LinearLaw, MethodVisitor, SeriesLaw, Tilted,
    exact_method,
};
use crate::scene::laws::{BondVisitor, LawVisitor, with_bond, with_force_law};
use crate::scene::{Scene, TiltedMethod};

pub use self::core::clocks::{ArrayQueue, ChannelQueue, PqQueue};
pub use self::core::{Core, Exact};
pub use rupture::binned::{BINNED_FROM, BinnedRupture, uses_bins};
pub use rupture::{RuptureModel, StrongRupture, TreeRupture};
pub use stepper::Stepper;
pub use stepper::direct::{DirectStepper, ExactDirect};
pub use stepper::linear::{Dynamic, ExactLinear, Kinematic, LinearStepper, PlateMotion};
use stepper::series;

/// The event queue the engine uses (chosen by `benches/exact.rs`, see docs/performance.md).
pub type DefaultQueue = ArrayQueue;

/// The exact engine for a `linear`-law scene with strong bonds.
pub fn strong_linear<Q: ChannelQueue>(scene: &Scene) -> ExactLinear<StrongRupture, Q> {
    strong_linear_with::<Q, Dynamic>(scene)
}

/// The exact engine for a `linear`-law scene with weak bonds, its rupture candidates drawn
/// from bins of anchors (what a run uses from [`BINNED_FROM`] junctions on).
pub fn weak_linear<Q: ChannelQueue>(scene: &Scene) -> ExactLinear<BinnedRupture, Q> {
    weak_linear_with::<Q, Dynamic>(scene)
}

/// [`weak_linear`] with the candidates drawn from a sum tree of the junctions' weights
/// ([`TreeRupture`]) instead of bins: the same process, another random stream (what a run
/// uses below [`BINNED_FROM`] junctions, and the bench's comparison for the bins).
pub fn weak_linear_tree<Q: ChannelQueue>(scene: &Scene) -> ExactLinear<TreeRupture, Q> {
    let j = &scene.junctions;
    ExactLinear::new(scene, &Linear::from_scene(scene), |_| TreeRupture::new(j.k0, j.beta_dx() * j.kappa, j.n))
}

/// [`strong_linear`] with plate motion `M` ([`Kinematic`] for `plate.kinematic`).
pub fn strong_linear_with<Q: ChannelQueue, M: PlateMotion>(scene: &Scene) -> ExactLinear<StrongRupture, Q, M> {
    ExactLinear::new(scene, &Linear::from_scene(scene), |rng| StrongRupture::<true>::new(scene.junctions.k0, rng))
}

/// [`weak_linear`] with plate motion `M` ([`Kinematic`] for `plate.kinematic`): the rupture
/// envelope's exponent is `beta dx c` with the linear law's thinning slope `c = kappa`.
pub fn weak_linear_with<Q: ChannelQueue, M: PlateMotion>(scene: &Scene) -> ExactLinear<BinnedRupture, Q, M> {
    let j = &scene.junctions;
    ExactLinear::try_new(scene, &Linear::from_scene(scene), |rng| {
        BinnedRupture::try_new(j.k0, j.beta_dx() * j.kappa, j.n, rng)
    })
    .unwrap_or_else(|e| panic!("{e}"))
}

/// The method the exact engine uses for law `L` in `scene`: the law's own
/// ([`ForceLaw::Exact`]), except that `exact.tilted = "direct"` turns a dynamic plate's
/// series method into the direct one (a kinematic plate keeps the series method).
pub fn method<L: ForceLaw>(scene: &Scene) -> ExactMethod {
    match exact_method::<L>() {
        ExactMethod::Series if direct_instead_of_series(scene) => ExactMethod::Direct,
        m => m,
    }
}

/// `exact.tilted = "direct"` on a dynamic plate.
fn direct_instead_of_series(scene: &Scene) -> bool {
    scene.exact.tilted == TiltedMethod::Direct && !scene.plate.kinematic
}

/// Builds the exact engine for `scene`, specialised to its force law and bond kind (both
/// from `scene::laws`) by the law's method ([`ForceLaw::Exact`]): closed form
/// ([`ExactLinear`], built from the law's [`LinearLaw::slope`]), the series engine
/// ([`series`], from the law's [`SeriesLaw::tilted_form`]), or the direct sum
/// ([`ExactDirect`], any law; it has no kinematic plate).
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
        <L::Exact as ExactMethodOf<L>>::visit(law, self)
    }
}

impl<L: ForceLaw, V: EngineVisitor> MethodVisitor<L> for WithLaw<'_, V> {
    type Output = Result<V::Output, EngineError>;

    fn closed_form(self, law: L) -> Self::Output
    where
        L: LinearLaw,
    {
        let Self { scene, visitor } = self;
        with_bond(&scene.junctions, ClosedFormBuild { scene, law, visitor })?
    }

    fn series(self, law: L) -> Self::Output
    where
        L: SeriesLaw,
    {
        if direct_instead_of_series(self.scene) {
            return self.direct(law);
        }
        let Self { scene, visitor } = self;
        let LawParams { kappa, l0 } = law.tilted_form();
        with_bond(&scene.junctions, series::Build { scene, law: Tilted { kappa, l0 }, visitor })?
    }

    fn direct(self, law: L) -> Self::Output
    where
        L: ForceLaw,
    {
        let Self { scene, visitor } = self;
        if scene.plate.kinematic {
            return Err(EngineError::Unsupported {
                engine: "exact",
                reason: "the direct method integrates the plate equation, so it cannot run plate.kinematic = true",
            });
        }
        with_bond(&scene.junctions, DirectBuild { scene, law, visitor })?
    }
}

struct ClosedFormBuild<'a, L, V> {
    scene: &'a Scene,
    law: L,
    visitor: V,
}

impl<L: LinearLaw, V: EngineVisitor> BondVisitor for ClosedFormBuild<'_, L, V> {
    type Output = Result<V::Output, EngineError>;
    /// Weak bonds: the rupture envelope `k0 exp(a |x|)`, `a = s c` from the bond's force
    /// sensitivity `s = beta dx` and the law's thinning slope `c = kappa`; its candidates
    /// drawn from bins of anchors from [`BINNED_FROM`] junctions on, from a sum tree below.
    fn visit<B: Bond>(self, bond: B) -> Self::Output {
        let Self { scene, law, visitor } = self;
        let (k0, n) = (bond.k0(), scene.junctions.n);
        let a = bond.force_sensitivity() * law.thinning_slope();
        let binned = |rng: &mut _| BinnedRupture::try_new(k0, a, n, rng);
        let tree = |_: &mut _| TreeRupture::try_new(k0, a, n);
        let strong = |rng: &mut _| Ok(StrongRupture::<true>::new(k0, rng));
        let bins = uses_bins(n);
        Ok(match (B::IS_WEAK, scene.plate.kinematic) {
            (true, true) if bins => {
                visitor.visit(ExactLinear::<_, DefaultQueue, Kinematic>::try_new(scene, &law, binned)?)
            }
            (true, false) if bins => {
                visitor.visit(ExactLinear::<_, DefaultQueue, Dynamic>::try_new(scene, &law, binned)?)
            }
            (true, true) => visitor.visit(ExactLinear::<_, DefaultQueue, Kinematic>::try_new(scene, &law, tree)?),
            (true, false) => visitor.visit(ExactLinear::<_, DefaultQueue, Dynamic>::try_new(scene, &law, tree)?),
            (false, true) => visitor.visit(ExactLinear::<_, DefaultQueue, Kinematic>::try_new(scene, &law, strong)?),
            (false, false) => visitor.visit(ExactLinear::<_, DefaultQueue, Dynamic>::try_new(scene, &law, strong)?),
        })
    }
}

struct DirectBuild<'a, L, V> {
    scene: &'a Scene,
    law: L,
    visitor: V,
}

impl<L: ForceLaw, V: EngineVisitor> BondVisitor for DirectBuild<'_, L, V> {
    type Output = Result<V::Output, EngineError>;
    fn visit<B: Bond>(self, bond: B) -> Self::Output {
        Ok(self.visitor.visit(ExactDirect::new(self.scene, self.law, bond)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::{Linear, Tilted};
    use crate::test_scenes::fig1_with;

    /// The law's method, except `exact.tilted = "direct"` on a dynamic plate.
    #[test]
    fn method_follows_the_law_and_the_scene() {
        let series = fig1_with(&["run.engine=exact"]);
        let direct = fig1_with(&["run.engine=exact", "exact.tilted=direct"]);
        let kinematic = fig1_with(&["run.engine=exact", "plate.kinematic=true"]);
        assert_eq!(method::<Tilted>(&series), ExactMethod::Series);
        assert_eq!(method::<Tilted>(&direct), ExactMethod::Direct);
        assert_eq!(method::<Tilted>(&kinematic), ExactMethod::Series);
        assert_eq!(method::<Linear>(&direct), ExactMethod::ClosedForm);
    }
}
