//! The plate-stepper contract: [`Stepper`], the hooks the core calls, and what a step
//! reports ([`Target`], [`Moved`], [`Step`], [`WeakRuptures`]).

use serde::{Serialize, de::DeserializeOwned};

use crate::engine::EngineError;
use crate::engine::exact::core::bags::Attached;
use crate::engine::exact::core::clocks::ChannelQueue;
use crate::engine::exact::core::state::Core;
use crate::engine::exact::rupture::rate::RuptureRate;
use crate::observe::Observer;
use crate::rng::{Pcg64, below};

/// Where [`Stepper::step`] moves the plate: local time `tau` (the first of the next candidate
/// and the stop), and whether the candidate, on channel `ch`, is due by then.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    pub tau: f64,
    pub due: bool,
    pub ch: usize,
}

/// How far [`Stepper::step`] got towards its target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Moved {
    /// At the target (the plate state checked finite): the due candidate, or the stop, is next.
    There,
    /// Short of the target: the loop asks again (the clocks may have moved).
    Short,
    /// The junction in this slot ruptured inside the step (weak bonds, thinned or located
    /// inside the step; the state is at the rupture time and checked finite).
    Ruptured(usize),
    /// A plate step was taken (not yet ended): the core thins weak bonds' candidates over it
    /// and ends it ([`Stepper::finish`]).
    Stepped(Step),
    /// The rates change too fast for the local time's resolution: the core moves the origin
    /// here (a new piece) and asks again.
    Rebase,
}

/// One plate step `[s0, s1]` and proven bounds of `y` over it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    pub s0: f64,
    pub s1: f64,
    pub y_lo: f64,
    pub y_hi: f64,
    /// Bound on the bond force's error from evaluating a local cubic instead of the series
    /// over the step, relative to [`SeriesSum::scale`](super::series::sum::SeriesSum::scale) (0 when the series was evaluated).
    pub cubic_error: f64,
}

/// How a plate stepper finds the ruptures of weak bonds (strong bonds always rupture on the
/// channel clock at the rupture model's constant rate).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WeakRuptures {
    /// Closed form: candidates on the rupture channel at the model's rate over a thinning
    /// horizon ([`HORIZON`](crate::engine::exact::core::state::HORIZON)), bounded by [`Stepper::bounds`].
    Horizon,
    /// Candidates thinned over each plate step ([`Moved::Stepped`], [`crate::engine::exact::rupture::thin()`]).
    Steps,
    /// The stepper finds them itself ([`Moved::Ruptured`]).
    Own,
}

/// A plate stepper: how the plate moves between events and reports a piece. The core calls
/// these hooks at fixed points of its event loop and composes them with a rupture model
/// ([`RuptureModel`](crate::engine::exact::rupture::RuptureModel)); a hook that a stepper does
/// not need has a default that compiles to nothing.
pub trait Stepper: Clone + std::fmt::Debug + Serialize + DeserializeOwned + Send + 'static {
    /// The engine's event queue.
    type Queue: ChannelQueue;
    /// What the law supplies to a weak-bond rupture model's acceptance.
    type Rate: RuptureRate;
    /// `true` for a kinematic plate (the friction reported is the bond force).
    const KINEMATIC: bool;
    /// How weak bonds' ruptures are found.
    const WEAK_RUPTURES: WeakRuptures;

    /// Opens the first piece at `t = 0`, once the initial junctions are drawn and registered.
    fn start(&mut self, core: &mut Core<Self::Queue>);
    /// The plate's local position now.
    fn y(&self, core: &Core<Self::Queue>) -> f64;
    /// The plate's velocity now.
    fn velocity(&self, core: &Core<Self::Queue>) -> f64;
    /// The lag `X - V t` now.
    #[inline]
    fn lag(&self, core: &Core<Self::Queue>) -> f64 {
        core.frame.lag(self.y(core), core.tau)
    }
    /// The bond force `F_b` now.
    fn bond_force(&self, core: &Core<Self::Queue>) -> f64;
    /// The law's acceptance for weak-bond rupture candidates.
    fn rate(&self) -> Self::Rate;
    /// The plate's local position at local time `tau` of the current piece (or step).
    #[inline]
    fn position(&mut self, _tau: f64) -> Result<f64, EngineError> {
        Ok(f64::NAN)
    }
    /// Proven bounds `(y_lo, y_hi)` of the plate over the next `h` of the piece just opened
    /// ([`WeakRuptures::Horizon`]).
    #[inline]
    fn bounds(&self, _core: &Core<Self::Queue>, _h: f64) -> (f64, f64) {
        (f64::NEG_INFINITY, f64::INFINITY)
    }
    /// How far the event just past (the junction anchored at `c` attached or detached) can
    /// move the plate over the next `rest` of the piece just opened, away from the path it
    /// had before the event, if that path lay within `[lo, hi]` ever since the event:
    /// `sup |y_new - y_old|` bounded ([`WeakRuptures::Horizon`]). `+inf` (the default): not
    /// known.
    #[inline]
    fn reach(&self, _c: f64, _rest: f64, _lo: f64, _hi: f64) -> f64 {
        f64::INFINITY
    }
    /// Moves the plate towards its target. A closed form reaches any time in one piece:
    /// [`Moved::There`] at once, the default.
    #[inline]
    fn step<O: Observer>(
        &mut self,
        _core: &mut Core<Self::Queue>,
        _to: Target,
        _obs: &mut O,
    ) -> Result<Moved, EngineError> {
        Ok(Moved::There)
    }
    /// Ends the step just taken ([`Moved::Stepped`]) at the rupture `hit` inside it, or at its
    /// end: what [`Stepper::step`] would have returned. `upcoming` is the rupture model's
    /// hint of a slot a later candidate will likely pick ([`RuptureModel::upcoming`]), for
    /// prefetching what the stepper keeps by slot.
    ///
    /// [`RuptureModel::upcoming`]: crate::engine::exact::rupture::RuptureModel::upcoming
    #[inline]
    fn finish(
        &mut self,
        _core: &mut Core<Self::Queue>,
        _step: &Step,
        _hit: Option<(f64, usize)>,
        _upcoming: usize,
        _to: Target,
    ) -> Result<Moved, EngineError> {
        Ok(Moved::There)
    }
    /// A formation candidate at `t`: whether it is accepted (thinning by `g(|v|)`,
    /// [`Core::accepts_formation`]); accepted, the piece is closed at `t`.
    #[inline]
    fn formation<O: Observer>(
        &mut self,
        core: &mut Core<Self::Queue>,
        t: f64,
        obs: &mut O,
    ) -> Result<bool, EngineError> {
        let v = self.velocity(core);
        if core.accepts_formation(v) {
            self.close(core, t, obs)?;
            return Ok(true);
        }
        Ok(false)
    }
    /// An advance begins: a stepper reads what it needs of the observers' contract here,
    /// once per advance rather than once per event (their bounds do not change within one).
    #[inline]
    fn begin<O: Observer>(&mut self, _core: &Core<Self::Queue>, _obs: &O) {}
    /// Reports the current piece up to `t` as a segment and moves the plate there.
    fn close<O: Observer>(&mut self, core: &mut Core<Self::Queue>, t: f64, obs: &mut O) -> Result<(), EngineError>;
    /// The advance ends here (its last piece closed): a stepper that sums pieces for the
    /// observer ([`Observer::stretch`]) reports them.
    #[inline]
    fn stopped<O: Observer>(&mut self, _core: &Core<Self::Queue>, _obs: &mut O) {}
    /// Starts a new piece at the current time and state, after an event.
    fn open_piece(&mut self, core: &mut Core<Self::Queue>);
    /// The core moved the local origin by `dtau`, `dy` (at a piece boundary): the same for
    /// the stepper's coordinates.
    fn shifted(&mut self, core: &Core<Self::Queue>, dtau: f64, dy: f64);
    /// The law's tension `f(x)` (reported with events).
    fn tension(&self, x: f64) -> f64;
    /// The factor of the formation rate `kon0 N_det` (1: candidates thinned one by one).
    #[inline]
    fn formation_acceptance(&self, _core: &Core<Self::Queue>) -> f64 {
        1.0
    }
    /// The detached junction that forms, of `n`.
    #[inline]
    fn formation_slot(&mut self, rng: &mut Pcg64, n: usize) -> usize {
        below(rng, n)
    }
    /// A junction was attached into `slot` with anchor `c` (the stepper's own bookkeeping).
    #[inline]
    fn attached(&mut self, _core: &mut Core<Self::Queue>, _slot: usize, _c: f64) {}
    /// The junction `a` left `slot` by `swap_remove` (the one in `last` moved into it).
    #[inline]
    fn detached(&mut self, _core: &mut Core<Self::Queue>, _slot: usize, _last: usize, _a: &Attached) {}
    /// Prefetches the memory the next event will touch.
    #[inline]
    fn prefetch(&self, _core: &Core<Self::Queue>) {}
}
