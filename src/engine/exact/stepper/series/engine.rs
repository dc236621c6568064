//! The series stepper of the exact core ([`crate::engine::exact::core`]): the bond force kept
//! as a [`SeriesSum`] with its error tracked, the plate stepped by its [`Motion`]; the core
//! thins weak bonds' rupture candidates over each step ([`WeakRuptures::Steps`]).

use serde::{Deserialize, Serialize};

use super::plate::{Motion, StepCtx};
use super::sum::SeriesSum;
use crate::engine::EngineError;
use crate::engine::alloc::{self, AllocError};
use crate::engine::exact::core::bags::Attached;
use crate::engine::exact::core::clocks::ArrayQueue;
use crate::engine::exact::core::engine::Exact;
use crate::engine::exact::core::pick::{Pick, prefetch};
use crate::engine::exact::core::state::{Core, FORMATION};
use crate::engine::exact::rupture::horizon::SPREAD;
use crate::engine::exact::rupture::{RuptureModel, TiltedRate};
use crate::engine::exact::stepper::contract::{Moved, Step, Stepper, Target, WeakRuptures};
use crate::observe::Observer;
use crate::physics::{ForceLaw, Tilted};
use crate::rng::{Pcg64, UniformSource, below};
use crate::scene::Scene;

/// Fewest junctions for which the next pick's record is prefetched: below it the bags (16
/// or 24 bytes a junction, under 100 KB) stay in the core's own caches, and predicting the
/// pick (a copy of the generator and its draws) costs more than the load it would hide.
pub const PREFETCH_MIN_N: usize = 1 << 12;
/// Largest `a = beta dx kappa` whose spread `SPREAD / a` a step is made to keep.
const A_RESOLVABLE: f64 = 1e12;

/// Exact engine for the tilted law with the bond force kept as a [`SeriesSum`]: rupture
/// model `R`, plate motion `P`.
pub type ExactSeries<R, P> = Exact<SeriesStepper<P>, R>;

/// The series stepper: the law, the bond-force series and its error bound, the plate motion
/// `P`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct SeriesStepper<P: Motion> {
    law: Tilted,
    /// The law's acceptance of weak-bond rupture candidates.
    rate: TiltedRate,
    /// The attached junctions' bond force.
    series: SeriesSum,
    /// Each attached junction's handle in `series`, by slot of the attached bag.
    handles: Vec<u32>,
    /// Weak bonds with at least [`PREFETCH_MIN_N`] junctions: the formations' picks, drawn
    /// ahead so that the detached record is prefetched events before it is read (the
    /// thinning's draws make a pick from the generator unknown until the step ends). `None`:
    /// drawn from the generator at the formation.
    #[serde(default)]
    next_formation: Option<Pick>,
    motion: P,
    /// Weak bonds: their candidates are thinned over each plate step, which keeps its
    /// excursion within `max_spread` (`+inf` for strong bonds).
    weak: bool,
    max_spread: f64,
    /// The series' re-base count when the current step was taken.
    #[serde(skip)]
    rebases_at_step: Option<u64>,
    /// `exact.rtol`: the series' stated tolerance, relative to `kappa l0 max(N_att, 1)`.
    rtol: f64,
    /// The relative error bound just after the engine last refreshed the series (see
    /// [`SeriesKernel::track_error`]); a refresh is taken only when the bound has doubled since.
    error_floor: f64,
    /// The series changed (attach, rupture, shift) since its error bound was last recorded.
    /// Not serialised: a resumed run records it again at its first plate step.
    #[serde(skip, default = "yes")]
    error_stale: bool,
    /// The series' relative error bound as last recorded by [`SeriesKernel::track_error`]; a
    /// step that evaluated the local cubic records it plus the cubic's remainder. Not
    /// serialised: recorded again at a resumed run's first plate step (`error_stale`).
    #[serde(skip)]
    last_rel: f64,
}

fn yes() -> bool {
    true
}

impl<R: RuptureModel, P: Motion> ExactSeries<R, P> {
    /// The engine at `t = 0` for `scene` under the tilted-form law `law` with bond sensitivity
    /// `beta_dx`; `rupture` (made from the generator after the initial state is drawn) and
    /// `motion` are built by the caller.
    pub fn new(
        scene: &Scene,
        law: Tilted,
        beta_dx: f64,
        rupture: impl FnOnce(&mut crate::rng::Pcg64) -> Result<R, AllocError>,
        motion: P,
    ) -> Result<Self, EngineError> {
        let mut core = Core::new(scene, 2)?;
        core.counters.series_rebases = Some(0);
        core.counters.series_error = Some(0.0);
        if !P::KINEMATIC {
            core.counters.ode_steps = Some(0);
            core.counters.ode_rejected = Some(0);
        }
        let rupture = rupture(&mut core.rng)?;
        let next_formation = (R::IS_WEAK && scene.junctions.n >= PREFETCH_MIN_N).then(|| Pick::draw(&mut core.rng));
        let a = beta_dx * law.kappa;
        // Beyond A_RESOLVABLE no plate step can keep the spread (rates change by e over less
        // than 1e-12 lengths): no limit, and the bound overflows into immediate ruptures.
        let resolvable = a > 0.0 && a <= A_RESOLVABLE;
        let stepper = SeriesStepper {
            law,
            rate: TiltedRate::new(law, beta_dx),
            series: SeriesSum::for_junctions(law, scene.exact.rtol, scene.junctions.n),
            handles: alloc::with_capacity(scene.junctions.n, "the series handles")?,
            next_formation,
            motion,
            weak: R::IS_WEAK,
            max_spread: if R::IS_WEAK && resolvable { SPREAD / a } else { f64::INFINITY },
            rebases_at_step: None,
            rtol: scene.exact.rtol,
            error_floor: 0.0,
            error_stale: true,
            last_rel: 0.0,
        };
        Ok(Exact::start(core, stepper, rupture))
    }

    /// The engine with its formations' picks drawn from the generator at each formation, as
    /// below [`PREFETCH_MIN_N`] junctions or with strong bonds (the same law as the picks
    /// drawn ahead, another stream: the tests compare the two).
    pub fn with_formations_drawn_at_use(mut self) -> Self {
        self.stepper.next_formation = None;
        self
    }
}

impl<P: Motion> SeriesStepper<P> {
    /// Records the largest relative bound of the series' error, `error_bound / (kappa l0
    /// max(N_att, 1))`. The bound is a function of the series' state only, so it is
    /// recomputed only when that changed (`error_stale`, or a re-basing of the series inside
    /// the step): the same maximum as recording it after every step, at O(1) per step.
    ///
    /// Between re-basings the series' bound grows: the residue of junctions counted through
    /// the bins at the last re-base and removed since, and the round-off allowance
    /// ([`super::sum`], module doc), both relative to a count of attached junctions that
    /// may have fallen. In a stick phase the plate may not move far enough to re-base for a
    /// long time, so the series is refreshed in place (a re-base at its own base point,
    /// [`SeriesKernel::refresh_series`], which resets both): at a removal that takes the
    /// residue count above the attached count (so the truncation part stays `<= rtol/2`;
    /// amortised, once each time the count halves), and here, once the whole bound passes
    /// `rtol / 2`, unless that did not halve it the last time.
    /// Returns the bound recorded (before a refresh); `last_rel` is the bound after it.
    #[inline]
    fn track_error(&mut self, core: &mut Core<ArrayQueue>) -> f64 {
        self.error_stale = false;
        let scale = self.series.scale();
        let rel = self.series.error_bound() / scale;
        self.last_rel = rel;
        if rel > 0.5 * self.rtol && rel > 2.0 * self.error_floor {
            self.refresh_series(core);
            self.error_floor = self.series.error_bound() / scale;
            self.last_rel = self.error_floor;
        }
        record_error(core, rel);
        rel
    }

    /// Re-bases the series at its own base point: the residue and the round-off allowance
    /// start again from zero. O(bins p^2).
    fn refresh_series(&mut self, core: &mut Core<ArrayQueue>) {
        let base = self.series.base();
        self.series.rebase(base);
        *core.counters.series_rebases.get_or_insert(0) += 1;
    }

    /// Strong bonds (with at least [`PREFETCH_MIN_N`] junctions): the plate step draws no
    /// random numbers, so the junction the due event on channel `ch` will pick is already
    /// known; asking for its record now lets the memory access (a random one among millions
    /// at large N) overlap the step. The picks are drawn on a copy of the generator, exactly
    /// as the event will draw them (formation: after the thinning's uniform when `g < 1`, so
    /// both candidates), and the run's stream is untouched.
    #[inline]
    fn prefetch_pick(&self, core: &Core<ArrayQueue>, ch: usize) {
        match ch {
            FORMATION => {
                let n = core.bags.n_detached();
                if n > 0 {
                    let mut rng = core.rng.clone();
                    prefetch(&core.bags.detached[below(&mut rng.clone(), n)]);
                    rng.uniform();
                    prefetch(&core.bags.detached[below(&mut rng, n)]);
                }
            }
            _ => {
                let n = core.bags.n_attached();
                if n > 0 {
                    let i = below(&mut core.rng.clone(), n);
                    prefetch(&core.bags.attached[i]);
                    prefetch(&self.handles[i]);
                }
            }
        }
    }
}

/// `series_error = max(series_error, rel)`.
#[inline]
fn record_error(core: &mut Core<ArrayQueue>, rel: f64) {
    let e = core.counters.series_error.get_or_insert(0.0);
    if rel > *e {
        *e = rel;
    }
}

impl<P: Motion> Stepper for SeriesStepper<P> {
    type Queue = ArrayQueue;
    type Rate = TiltedRate;
    const KINEMATIC: bool = P::KINEMATIC;
    const WEAK_RUPTURES: WeakRuptures = WeakRuptures::Steps;

    fn start(&mut self, core: &mut Core<ArrayQueue>) {
        self.track_error(core);
        self.motion.open_piece(0.0, &self.series, &core.frame);
    }

    #[inline(always)]
    fn rate(&self) -> TiltedRate {
        self.rate
    }

    /// Inside the step just taken.
    #[inline(always)]
    fn position(&mut self, tau: f64) -> Result<f64, EngineError> {
        self.motion.y_at(tau)
    }

    #[inline]
    fn y(&self, core: &Core<ArrayQueue>) -> f64 {
        self.motion.y(core.tau)
    }

    #[inline]
    fn velocity(&self, core: &Core<ArrayQueue>) -> f64 {
        self.motion.velocity(&self.series, &core.frame, core.tau)
    }

    #[inline]
    fn lag(&self, core: &Core<ArrayQueue>) -> f64 {
        self.motion.lag(core.tau, &core.frame)
    }

    fn bond_force(&self, core: &Core<ArrayQueue>) -> f64 {
        self.series.force(self.y(core))
    }

    /// One plate step towards the target (weak bonds: the core thins over it, then ends it,
    /// [`Stepper::finish`]). Strong bonds (with at least [`PREFETCH_MIN_N`] junctions): the
    /// due event's pick is prefetched while the step runs.
    #[inline]
    fn step<O: Observer>(
        &mut self,
        core: &mut Core<ArrayQueue>,
        to: Target,
        _obs: &mut O,
    ) -> Result<Moved, EngineError> {
        if core.tau < to.tau {
            if !self.weak && to.due && core.n >= PREFETCH_MIN_N {
                self.prefetch_pick(core, to.ch);
            }
            self.rebases_at_step = core.counters.series_rebases;
            let mut ctx = StepCtx {
                series: &mut self.series,
                frame: &core.frame,
                counters: &mut core.counters,
                max_spread: self.max_spread,
            };
            return Ok(Moved::Stepped(self.motion.step(&mut ctx, core.tau, to.tau)?));
        }
        core.finite("X", self.y(core))?;
        Ok(Moved::There)
    }

    /// Ends the step at the rupture `hit` inside it, or at its end; records the series' error
    /// bound over it. Weak bonds: the handle the rupture model's next candidates will likely
    /// read (`upcoming`) is asked for, and a hit's own.
    #[inline]
    fn finish(
        &mut self,
        core: &mut Core<ArrayQueue>,
        step: &Step,
        hit: Option<(f64, usize)>,
        upcoming: usize,
        to: Target,
    ) -> Result<Moved, EngineError> {
        if self.weak && core.n >= PREFETCH_MIN_N {
            // The handle a later candidate will likely read, asked for an event ahead.
            if let Some(h) = self.handles.get(upcoming) {
                prefetch(h);
            }
            // The rupture reads the junction's handle: asked for while the step ends.
            if let Some((_, slot)) = hit {
                prefetch(&self.handles[slot]);
            }
        }
        let end = hit.map_or(step.s1, |(s, _)| s);
        self.motion.finish(step, end, &self.series)?;
        core.tau = end;
        self.motion.sync_counters(&mut core.counters);
        // The series' bound over the step: as it was when the step took its cubic.
        let series_rel = if self.error_stale || core.counters.series_rebases != self.rebases_at_step {
            self.track_error(core)
        } else {
            self.last_rel
        };
        if step.cubic_error > 0.0 {
            record_error(core, series_rel + step.cubic_error);
        }
        core.finite("X", self.y(core))?;
        Ok(match hit {
            Some((_, slot)) => Moved::Ruptured(slot),
            None if core.tau < to.tau => Moved::Short,
            None => Moved::There,
        })
    }

    /// Reports the piece up to now (the plate is there already).
    #[inline]
    fn close<O: Observer>(&mut self, core: &mut Core<ArrayQueue>, _t: f64, obs: &mut O) -> Result<(), EngineError> {
        if let Some(mut s) = self.motion.segment(core.tau, &core.frame, &core.plate, &self.series) {
            s.attached = core.bags.n_attached() as u64;
            obs.segment(&s);
        }
        Ok(())
    }

    #[inline]
    fn open_piece(&mut self, core: &mut Core<ArrayQueue>) {
        self.motion.open_piece(core.tau, &self.series, &core.frame);
    }

    #[inline]
    fn shifted(&mut self, _core: &Core<ArrayQueue>, dtau: f64, dy: f64) {
        self.series.shift(dy);
        self.error_stale = true;
        self.motion.rebase(dtau, dy);
    }

    #[inline]
    fn tension(&self, x: f64) -> f64 {
        self.law.tension(x)
    }

    /// The junction's handle in the series.
    #[inline]
    fn attached(&mut self, _core: &mut Core<ArrayQueue>, slot: usize, c: f64) {
        debug_assert_eq!(slot, self.handles.len());
        self.error_stale = true;
        self.handles.push(self.series.add(c));
    }

    #[inline]
    fn detached(&mut self, core: &mut Core<ArrayQueue>, slot: usize, _last: usize, a: &Attached) {
        let h = self.handles.swap_remove(slot);
        self.series.remove(a.c, h);
        if self.series.residue() > self.series.len() as u64 {
            self.refresh_series(core);
        }
        self.error_stale = true;
    }

    /// Weak bonds at large N: the next formation's pick, drawn ahead ([`Pick`]); otherwise
    /// from the generator now.
    #[inline]
    fn formation_slot(&mut self, rng: &mut Pcg64, n: usize) -> usize {
        match &mut self.next_formation {
            Some(p) => p.take(n, rng),
            None => below(rng, n),
        }
    }

    /// Weak bonds at large N: the records the next formations can pick.
    #[inline]
    fn prefetch(&self, core: &Core<ArrayQueue>) {
        if let Some(p) = &self.next_formation {
            p.prefetch(&core.bags.detached);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ExactSeries;
    use crate::engine::exact::core::junctions::rupture;
    use crate::engine::exact::rupture::StrongRupture;
    use crate::engine::exact::stepper::series::plate::DrivenPlate;
    use crate::engine::exact::stepper::series::sum::{DIRECT_MAX, SeriesSum};
    use crate::observe::Nothing;
    use crate::physics::{ForceLaw, Tilted};
    use crate::test_scenes::fig1_with;

    /// The engine's series for `n` junctions (all attached, kinematic plate at rest).
    fn engine(n: usize) -> ExactSeries<StrongRupture<false>, DrivenPlate> {
        let s = fig1_with(&[
            "run.engine=exact",
            "junctions.force_law=tilted",
            &format!("junctions.n={n}"),
            "junctions.initial=attached",
            "plate.kinematic=true",
        ]);
        let k0 = s.junctions.k0;
        ExactSeries::new(&s, Tilted::from_scene(&s), 0.0, |rng| Ok(StrongRupture::new(k0, rng)), DrivenPlate::new(0.0))
            .unwrap()
    }

    /// The series is in direct mode below `DIRECT_MAX` junctions, in bins mode from it on.
    #[test]
    fn series_mode_follows_the_junction_count() {
        for (n, direct) in [(1, true), (300, true), (DIRECT_MAX - 1, true), (DIRECT_MAX, false)] {
            assert_eq!(engine(n).stepper.series.is_direct(), direct, "N = {n}");
        }
    }

    /// A stick phase: every junction is counted in the series at a re-base, then all but
    /// one rupture with the plate at rest. Bins mode (the series rebuilt in bins mode, as
    /// at `N >= DIRECT_MAX`): each removal leaves a residue in the bound; the engine
    /// refreshes the series whenever the residue count passes the attached count, so the
    /// bound stays within `rtol / 2` of `kappa l0 N_att` (plus round-off), the refreshes are
    /// amortised (one per halving of the count), and the series still agrees with the direct
    /// sum within its bound. Direct mode (the engine's own choice at 4096): no residue, no
    /// refresh, the same bound and agreement.
    #[test]
    fn series_refreshed_in_a_stick_phase() {
        for bins in [true, false] {
            let mut e = engine(4096);
            let (core, k, r) = (&mut e.core, &mut e.stepper, &mut e.rupture);
            assert!(k.series.is_direct());
            if bins {
                k.series = SeriesSum::new(k.law, k.rtol);
                let n = core.bags.n_attached();
                for (h, a) in k.handles.iter_mut().zip(&core.bags.attached[..n]) {
                    *h = k.series.add(a.c);
                }
            }
            let base = k.series.base();
            k.series.rebase(base);
            let rebases0 = core.counters.series_rebases.unwrap();
            let (kl0, rtol) = (k.law.kappa * k.law.l0, k.rtol);
            let y = 0.05;
            while core.bags.n_attached() > 1 {
                rupture(core, k, r, core.bags.n_attached() - 1, &mut Nothing);
                let n = core.bags.n_attached();
                assert!(k.series.residue() <= n as u64, "residue {} above {n} attached", k.series.residue());
                let rel = k.series.error_bound() / (kl0 * n.max(1) as f64);
                assert!(rel <= 0.5 * rtol * (1.0 + 1e-3), "relative bound {rel} at {n} attached, rtol {rtol}");
                if n % 97 == 0 {
                    let direct: f64 = core.bags.attached[..n].iter().map(|a| k.law.force_x(y - a.c)).sum();
                    let err = (k.series.force(y) - direct).abs();
                    assert!(err <= k.series.error_bound() + 1e-12 * kl0, "series off by {err} at {n} attached");
                }
            }
            let refreshes = core.counters.series_rebases.unwrap() - rebases0;
            if bins {
                assert!((10..=14).contains(&refreshes), "{refreshes} refreshes for 4095 ruptures from 4096");
            } else {
                assert_eq!((refreshes, k.series.residue()), (0, 0), "direct mode");
            }
        }
    }
}
