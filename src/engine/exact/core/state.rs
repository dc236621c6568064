//! [`Core`]: the state every exact engine keeps, and its event channels.

use serde::{Deserialize, Serialize};

use super::bags::Bags;
use super::clocks::{ChannelQueue, Channels};
use super::frame::Frame;
use crate::engine::alloc::AllocError;
use crate::engine::{Counters, EngineError};
use crate::physics::{Formation, Plate};
use crate::rng::{Pcg64, UniformSource, pcg};
use crate::scene::{Reattach, Scene};

/// Channel of formation candidates.
pub const FORMATION: usize = 0;
/// Channel of ruptures (strong bonds) or rupture candidates (weak bonds, linear law).
pub const RUPTURE: usize = 1;
/// End of the current thinning horizon (weak bonds on a closed-form plate, [`WeakRuptures::Horizon`](crate::engine::exact::stepper::contract::WeakRuptures::Horizon)).
pub const HORIZON: usize = 2;

/// The state every exact engine keeps, in local coordinates ([`Frame`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct Core<Q: ChannelQueue> {
    pub n: usize,
    pub plate: Plate,
    /// Relaxation rate of a detached junction's extension (`junctions.lambda`).
    pub lambda: f64,
    pub reattach: Reattach,
    pub formation: Formation,
    pub frame: Frame,
    /// Local time.
    pub tau: f64,
    pub bags: Bags,
    pub channels: Channels<Q>,
    pub rng: Pcg64,
    pub counters: Counters,
    /// Events since the frame was last re-based ([`REBASE`](super::policy::REBASE)).
    pub events_since_rebase: u64,
}

impl<Q: ChannelQueue> Core<Q> {
    /// The core at `t = 0` for `scene` with `channels` channels: the generator seeded with
    /// `run.seed` and the initial junctions drawn from it; the counters of every exact
    /// engine at zero.
    pub fn new(scene: &Scene, channels: usize) -> Result<Self, AllocError> {
        let j = &scene.junctions;
        let mut rng = pcg(scene.run.seed);
        let bags = Bags::initial(j, &mut rng)?;
        let plate = Plate::from_scene(scene);
        Ok(Core {
            n: j.n,
            plate,
            lambda: j.lambda,
            reattach: j.reattach,
            formation: Formation::from_scene(scene),
            frame: Frame::new(plate.v),
            tau: 0.0,
            bags,
            channels: Channels::new(channels),
            rng,
            counters: Counters { events: Some(0), candidates: Some(0), rebases: Some(0), ..Default::default() },
            events_since_rebase: 0,
        })
    }

    /// Absolute time.
    #[inline]
    pub fn time(&self) -> f64 {
        self.frame.time(self.tau)
    }

    /// A non-finite plate quantity is an error, never an output.
    #[inline]
    pub fn finite(&self, quantity: &'static str, value: f64) -> Result<(), EngineError> {
        if value.is_finite() { Ok(()) } else { Err(EngineError::NonFinite { t: self.time(), quantity, value }) }
    }

    /// Formation thinning at plate velocity `v`: accepted with probability `g(|v|)` (one
    /// uniform drawn, only when `g < 1`).
    #[inline]
    pub fn accepts_formation(&mut self, v: f64) -> bool {
        let g = self.formation.g(v);
        g >= 1.0 || self.rng.uniform() < g
    }

    /// Counts a candidate (an event or a rejected one).
    #[inline]
    pub fn count_candidate(&mut self) {
        *self.counters.candidates.get_or_insert(0) += 1;
    }

    /// Moves the local origin by `dtau` in time and `dy` in position: frame, junctions and
    /// clocks; the engine's own coordinates are its stepper's ([`Stepper::shifted`](crate::engine::exact::stepper::contract::Stepper::shifted)).
    pub(super) fn shift(&mut self, dtau: f64, dy: f64) {
        self.frame.shift(dtau, dy);
        self.bags.rebase(dtau, dy);
        self.channels.shift(dtau);
        self.tau = 0.0;
        self.events_since_rebase = 0;
        *self.counters.rebases.get_or_insert(0) += 1;
    }
}
