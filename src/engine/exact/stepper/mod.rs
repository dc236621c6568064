//! What an exact engine supplies to the [`Core`]: its [`Kernel`], the plate between events
//! (how it moves, reports a piece, restarts) and its rupture kinetics (the rupture channel's
//! rate, the choice of the junction, what a rupture or a formation changes in its own
//! state). The core does the rest ([`super::core::junctions`], [`super::core::engine`]).

pub mod direct;
pub mod linear;
pub mod series;

use rand::RngExt;
use serde::{Serialize, de::DeserializeOwned};

use super::core::Core;
use crate::engine::EngineError;
use crate::engine::exact::core::bags::Attached;
use crate::engine::exact::core::clocks::ChannelQueue;
use crate::observe::Observer;
use crate::rng::Pcg64;

/// Where [`Kernel::step`] moves the plate: local time `tau` (the first of the next candidate
/// and the stop), and whether the candidate, on channel `ch`, is due by then.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    pub tau: f64,
    pub due: bool,
    pub ch: usize,
}

/// How far [`Kernel::step`] got towards its target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Moved {
    /// At the target (the plate state checked finite): the due candidate, or the stop, is next.
    There,
    /// Short of the target: the loop asks again (the clocks may have moved).
    Short,
    /// The junction in this slot ruptured inside the step (weak bonds, thinned or located
    /// inside the step; the state is at the rupture time and checked finite).
    Ruptured(usize),
}

/// An exact engine's own part. The core calls these hooks at fixed points of its event
/// loop; a hook that an engine does not need has a default that compiles to nothing.
pub trait Kernel: Clone + std::fmt::Debug + Serialize + DeserializeOwned + Send + 'static {
    /// The engine's event queue.
    type Queue: ChannelQueue;
    /// `true` for force-dependent rupture rates (weak bonds).
    const IS_WEAK: bool;
    /// `true` for a kinematic plate (the friction reported is the bond force).
    const KINEMATIC: bool;
    /// The engine has a third channel, [`super::core::HORIZON`]: the end of a thinning horizon,
    /// where the plate's piece restarts and the rupture bound is renewed.
    const HORIZON: bool = false;

    // The plate.

    /// Opens the first piece at `t = 0`, once the initial junctions are drawn (and
    /// registers them with the rupture kinetics).
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
    /// Reports the current piece up to `t` as a segment and moves the plate there.
    fn close<O: Observer>(&mut self, core: &mut Core<Self::Queue>, t: f64, obs: &mut O) -> Result<(), EngineError>;
    /// Starts a new piece at the current time and state, after an event.
    fn open_piece(&mut self, core: &mut Core<Self::Queue>);
    /// Starts a new piece where no event happened (a stop, the end of a horizon).
    #[inline]
    fn restart(&mut self, core: &mut Core<Self::Queue>) {
        self.open_piece(core);
    }
    /// The core moved the local origin by `dtau`, `dy` (at a piece boundary): the same for
    /// the kernel's coordinates.
    fn shifted(&mut self, core: &Core<Self::Queue>, dtau: f64, dy: f64);

    // The junctions.

    /// The law's tension `f(x)` (reported with events).
    fn tension(&self, x: f64) -> f64;
    /// The rupture channel's rate from now on, and the absolute local time its bound holds
    /// until ([`Kernel::HORIZON`]; `+inf` otherwise).
    fn rupture_plan(&mut self, core: &Core<Self::Queue>) -> (f64, f64);
    /// The factor of the formation rate `kon0 N_det` (1: candidates thinned one by one).
    #[inline]
    fn formation_acceptance(&self, _core: &Core<Self::Queue>) -> f64 {
        1.0
    }
    /// The detached junction that forms, of `n`.
    #[inline]
    fn formation_slot(&mut self, rng: &mut Pcg64, n: usize) -> usize {
        rng.random_range(0..n)
    }
    /// A rupture candidate at `t`: the slot that ruptures, or `None` if rejected. Default:
    /// a uniform pick (strong bonds).
    #[inline]
    fn pick_rupture(&mut self, core: &mut Core<Self::Queue>, _t: f64) -> Option<usize> {
        let n = core.bags.n_attached();
        Some(core.rng.random_range(0..n))
    }
    /// The bond-force handle of a junction about to attach with anchor `c` (0 if the engine
    /// keeps none).
    #[inline]
    fn bin(&mut self, _core: &mut Core<Self::Queue>, _c: f64) -> u32 {
        0
    }
    /// A junction attached into `slot` with anchor `c`, extension `x`, the plate at `y`.
    /// Returns `false` if its rupture rate overflows (it ruptures at once).
    fn attached(&mut self, core: &mut Core<Self::Queue>, slot: usize, c: f64, x: f64, y: f64) -> bool;
    /// The junction `a` left `slot` by `swap_remove` (the one in `last` moved into it).
    #[inline]
    fn detached(&mut self, _core: &mut Core<Self::Queue>, _slot: usize, _last: usize, _a: &Attached) {}
    /// The kernel's own reason to re-base now (its weights about to overflow).
    #[inline]
    fn forced_rebase(&self, _core: &Core<Self::Queue>) -> bool {
        false
    }
    /// After a re-base: everything recomputed from `attached`; the slots whose rate overflows.
    #[inline]
    fn rebuild(&mut self, _attached: &mut [Attached]) -> Vec<usize> {
        Vec::new()
    }
    /// Prefetches the memory the next picks will touch.
    #[inline]
    fn prefetch(&self, _core: &Core<Self::Queue>) {}
}
