//! The fixed-step engine's state and its step (docs/engines.md, "The fixed-step engine").
//!
//! State is stored as structure of arrays (`q: Vec<u8>`, `x: Vec<f64>`). Step `n`'s
//! junction update (4) is not applied at the end of step `n` but recorded as a pending
//! `(dX, 1 - lambda dt)` and applied, junction by junction, at the top of step `n + 1`'s
//! single pass over the junctions (flips, rates and `F_b` in the same pass). The values are
//! bit for bit those of the eager scheme; every read of `x_i` between steps
//! ([`FixedEngine::extension`], [`Engine::sample`]) applies the pending update on the fly.
//!
//! The pass goes chunk by chunk ([`super::chunk`]); with a `Team` of threads
//! ([`Engine::set_threads`]) the chunks are shared between them, with the same results.

use std::marker::PhantomData;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::chunk::{
    BLOCK, CHUNK, ChunkEvents, ChunkSums, Events, NoEvents, StepParams, mask, pack_attached, pass_chunk, select, total,
};
use super::flip::Flip;
use super::integrator::{Integrator, PlateState};
use super::stored;
use super::team::Team;
use crate::engine::alloc::{self, AllocError};
use crate::engine::{Counters, Engine, EngineError};
use crate::observe::{JunctionEvent, Observer, Sample, Segment};
use crate::physics::{Bond, ForceLaw, Formation, Plate};
use crate::rng::UniformSource;
use crate::scene::{EngineKind, Initial, Reattach, Scene};

/// Magnitude beyond which the plate is declared diverged: of `X`, `Xd`, or (with a plate
/// equation) a force the step reports (`F_b`, `eta Xd`, `F = K (V t - X)`).
pub const DIVERGENCE_LIMIT: f64 = 1e100;

/// The fixed-step engine, specialised to a force law `L`, bond kind `B`, generator `R`
/// and flip rule `F`. Stored (serde) as the map of its fields but the last two
/// (`src/engine/fixed/stored.rs`).
#[derive(Clone, Debug)]
pub struct FixedEngine<L, B, R, F> {
    law: L,
    bond: B,
    flip: PhantomData<F>,
    formation: Formation,
    plate: Plate,
    integrator: Integrator,
    rng: R,
    /// Time step `dt`.
    dt: f64,
    /// `1 - lambda dt`, the relaxation factor of a detached junction over one step.
    relax: f64,
    /// `reattach = "unstretched"`: a forming junction starts at `x_i = 0`.
    unstretched: bool,
    /// `F::threshold(k0 dt)`: the rupture threshold of strong bonds, the same every step.
    strong_off_threshold: f64,
    /// Steps taken, `n`; the time is `t_n = n dt`.
    steps: u64,
    /// Plate position `X_n`.
    plate_x: f64,
    /// Plate velocity `Xd_n`.
    plate_v: f64,
    /// Junction states `q_i` (0 or 1).
    q: Vec<u8>,
    /// Junction extensions `x_i`, up to the pending update below.
    x: Vec<f64>,
    /// Pending update (4) of the last step: attached `x_i += pending_dx`, detached
    /// `x_i *= pending_relax`. The identity `(0, 1)` before the first step.
    pending_dx: f64,
    pending_relax: f64,
    /// `sum_i q_i`.
    attached: u64,
    ruptures: u64,
    formations: u64,
    /// The threads that share the pass ([`Engine::set_threads`]); not part of the state.
    team: Option<Team>,
    /// The buffer of a chunk's events, kept from step to step; not part of the state.
    kept: Vec<JunctionEvent>,
}

/// The chunks' passes one after the other on this thread, the generator running through
/// them. A function of its own (never inlined): its loop is compiled once per engine type
/// and kind of events, not inside each caller.
#[inline(never)]
fn pass_in_order<L: ForceLaw, B: Bond, R: UniformSource, F: Flip, E: Events>(
    params: &StepParams<L, B>,
    rng: &mut R,
    q: &mut [u8],
    x: &mut [f64],
    events: &mut E,
) -> Vec<ChunkSums> {
    let mut sums = Vec::with_capacity(q.len().div_ceil(CHUNK));
    for (c, (qs, xs)) in q.chunks_mut(CHUNK).zip(x.chunks_mut(CHUNK)).enumerate() {
        sums.push(pass_chunk::<L, B, R, F, E>(params, rng, qs, xs, c * CHUNK, events));
    }
    sums
}

impl<L: Serialize, B: Serialize, R: Serialize, F> Serialize for FixedEngine<L, B, R, F> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        stored::Written {
            law: &self.law,
            bond: &self.bond,
            flip: PhantomData,
            formation: &self.formation,
            plate: &self.plate,
            integrator: &self.integrator,
            rng: &self.rng,
            dt: self.dt,
            relax: self.relax,
            unstretched: self.unstretched,
            strong_off_threshold: self.strong_off_threshold,
            steps: self.steps,
            plate_x: self.plate_x,
            plate_v: self.plate_v,
            q: &self.q,
            x: &self.x,
            pending_dx: self.pending_dx,
            pending_relax: self.pending_relax,
            attached: self.attached,
            ruptures: self.ruptures,
            formations: self.formations,
        }
        .serialize(s)
    }
}

impl<'de, L: Deserialize<'de>, B: Deserialize<'de>, R: Deserialize<'de>, F> Deserialize<'de>
    for FixedEngine<L, B, R, F>
{
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let (mut law, mut bond, mut rng) = (None, None, None);
        let u = stored::read(
            &mut <dyn erased_serde::Deserializer>::erase(d),
            &mut |d| stored::typed(&mut law, d),
            &mut |d| stored::typed(&mut bond, d),
            &mut |d| stored::typed(&mut rng, d),
        )
        .map_err(serde::de::Error::custom)?;
        // `read` refuses a map without them.
        let (Some(law), Some(bond), Some(rng)) = (law, bond, rng) else {
            return Err(serde::de::Error::custom("a fixed-step engine's law, bond or generator is missing"));
        };
        Ok(FixedEngine {
            law,
            bond,
            flip: PhantomData,
            formation: u.formation,
            plate: u.plate,
            integrator: u.integrator,
            rng,
            dt: u.dt,
            relax: u.relax,
            unstretched: u.unstretched,
            strong_off_threshold: u.strong_off_threshold,
            steps: u.steps,
            plate_x: u.plate_x,
            plate_v: u.plate_v,
            q: u.q,
            x: u.x,
            pending_dx: u.pending_dx,
            pending_relax: u.pending_relax,
            attached: u.attached,
            ruptures: u.ruptures,
            formations: u.formations,
            team: None,
            kept: Vec::new(),
        })
    }
}

/// What one pass over the junctions found.
#[derive(Clone, Copy, Debug)]
struct Pass {
    /// `F_b = sum_i q_i f^x(x_i)` with the new `q`.
    bond_force: f64,
    /// Linear law only: `sum_i q_i x_i` with the new `q` (`F_b = kappa * sum`).
    attached_extension: f64,
}

impl<L: ForceLaw, B: Bond, R, F: Flip> FixedEngine<L, B, R, F>
where
    R: UniformSource + Clone + std::fmt::Debug + Serialize + DeserializeOwned + Send + 'static,
{
    /// Builds the engine at `t = 0`: plate at rest at `X = 0`, junctions per
    /// `junctions.initial`, all with `x_i = 0`.
    ///
    /// `initial = "stationary"` draws one uniform `xi_i` per junction, in index order, from
    /// `rng` here (before the first step): junction `i` starts attached iff
    /// `xi_i < kon0 / (kon0 + k0)`.
    ///
    /// Panics if the junction arrays cannot be allocated; [`FixedEngine::try_new`] reports it.
    pub fn new(scene: &Scene, law: L, bond: B, rng: R, flip: F) -> Self {
        Self::try_new(scene, law, bond, rng, flip).unwrap_or_else(|e| panic!("{e}"))
    }

    /// [`FixedEngine::new`] with the junction arrays reserved fallibly.
    pub fn try_new(scene: &Scene, law: L, bond: B, mut rng: R, _flip: F) -> Result<Self, AllocError> {
        let j = &scene.junctions;
        let n = j.n;
        let q: Vec<u8> = match j.initial {
            Initial::Detached => alloc::filled(n, 0, "the junction states")?,
            Initial::Attached => alloc::filled(n, 1, "the junction states")?,
            Initial::Stationary => {
                let p = j.kon0 / (j.kon0 + j.k0);
                let mut q = alloc::with_capacity(n, "the junction states")?;
                q.extend((0..n).map(|_| u8::from(rng.uniform() < p)));
                q
            }
        };
        let x = alloc::filled(n, 0.0, "the junction extensions")?;
        let attached = q.iter().map(|&b| u64::from(b)).sum();
        let dt = scene.fixed.dt;
        Ok(FixedEngine {
            law,
            bond,
            flip: PhantomData,
            formation: Formation::from_scene(scene),
            plate: Plate::from_scene(scene),
            integrator: Integrator::of_scene(scene),
            rng,
            dt,
            relax: 1.0 - j.lambda * dt,
            unstretched: j.reattach == Reattach::Unstretched,
            strong_off_threshold: F::threshold(j.k0 * dt),
            steps: 0,
            plate_x: 0.0,
            // A kinematic plate moves at V from the start (formation sees g(V)).
            plate_v: if scene.plate.kinematic { scene.plate.v } else { 0.0 },
            q,
            x,
            pending_dx: 0.0,
            pending_relax: 1.0,
            attached,
            ruptures: 0,
            formations: 0,
            team: None,
            kept: Vec::new(),
        })
    }

    /// Number of junctions `N`.
    pub fn len(&self) -> usize {
        self.q.len()
    }

    /// Always `false` (a scene has `N >= 1`).
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// `q_i` at `t_n`.
    pub fn is_attached(&self, i: usize) -> bool {
        self.q[i] != 0
    }

    /// `x_i` at `t_n` (with the pending update applied).
    pub fn extension(&self, i: usize) -> f64 {
        if self.q[i] != 0 { self.x[i] + self.pending_dx } else { self.x[i] * self.pending_relax }
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The integrator in use (`Overdamped` when `M = 0`).
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }

    /// Steps 1 and 2 in one pass over the junctions, after applying the previous step's
    /// pending update (4) to each `x_i`: `xi_i ~ U(0,1)`, one per junction in index order;
    /// `k = q_i ? k_off(f(x_i)) : k_on`; flip per `F`; re-attachment rule;
    /// `F_b = sum_i q_i f^x(x_i)` with the new `q`, summed chunk by chunk ([`total`]).
    ///
    /// Each chunk is [`pass_chunk`] from the generator's state at its first draw. Alone, or
    /// when events are wanted (handed on chunk by chunk, in index order), the chunks go in
    /// order on this thread and the generator runs through them; with a team, chunk `c`
    /// starts from the step's state skipped by `c CHUNK` draws, the team's threads take the
    /// chunks, and the generator then skips the step's `N` draws. The thresholds shared by
    /// many junctions are moved to the raw scale once per step ([`Flip::raw_threshold`],
    /// exact), so a draw is compared without its division.
    #[inline(always)]
    fn junction_pass<E: Events>(&mut self, t: f64, on_threshold: f64, events: &mut E) -> Pass {
        let params = StepParams {
            law: self.law,
            bond: self.bond,
            dt: self.dt,
            t,
            dx: self.pending_dx,
            relax: self.pending_relax,
            off_cut: F::raw_threshold::<R>(self.strong_off_threshold),
            on_cut: F::raw_threshold::<R>(on_threshold),
            keep_formed: if self.unstretched { 0 } else { !0u64 },
        };
        let sums: Vec<ChunkSums> = match &self.team {
            Some(team) if !E::ON => {
                let mut start = self.rng.clone();
                let chunks = self.q.chunks_mut(CHUNK).zip(self.x.chunks_mut(CHUNK));
                let items = chunks.map(|(qs, xs)| {
                    let rng = start.clone();
                    start.skip(qs.len() as u64);
                    (rng, qs, xs)
                });
                let sums = team.map(items, |c, (mut rng, qs, xs)| {
                    pass_chunk::<L, B, R, F, NoEvents>(&params, &mut rng, qs, xs, c * CHUNK, &mut NoEvents)
                });
                self.rng = start;
                sums
            }
            _ => pass_in_order::<L, B, R, F, E>(&params, &mut self.rng, &mut self.q, &mut self.x, events),
        };
        let sum = total(sums.iter().map(|c| c.sum));
        let ruptures: u64 = sums.iter().map(|c| c.ruptures).sum();
        let formations: u64 = sums.iter().map(|c| c.formations).sum();
        self.pending_dx = 0.0;
        self.pending_relax = 1.0;
        self.ruptures += ruptures;
        self.formations += formations;
        self.attached = self.attached + formations - ruptures;
        if L::IS_LINEAR {
            // f^x(x) = kappa x is linear, so sum_i q_i f^x(x_i) = f^x(sum_i q_i x_i).
            Pass { bond_force: self.law.force_x(sum), attached_extension: sum }
        } else {
            Pass { bond_force: sum, attached_extension: f64::NAN }
        }
    }

    /// `F_b` with the current `q` and every attached junction moved by `dx` (the `F_b'` of
    /// velocity Verlet). Read-only: the move itself stays pending.
    fn bond_force_moved(&self, dx: f64, pass: Pass) -> f64 {
        if L::IS_LINEAR {
            self.law.force_x(pass.attached_extension + self.attached as f64 * dx)
        } else {
            self.attached_force(dx)
        }
    }

    /// `F_b` at `t_n` from `(q, x)` before step `n`'s flips, summed chunk by chunk as the
    /// pass sums it.
    fn bond_force_now(&self) -> f64 {
        let dx = self.pending_dx;
        if L::IS_LINEAR {
            // Detached junctions add +0.0: the sum of the attached `x_i + dX` in index order.
            let chunk_sum =
                |(qs, xs): (&[u8], &[f64])| qs.iter().zip(xs).fold(0.0, |s, (&q, &x)| s + select(mask(q), x + dx, 0.0));
            self.law.force_x(total(self.q.chunks(CHUNK).zip(self.x.chunks(CHUNK)).map(chunk_sum)))
        } else {
            self.attached_force(dx)
        }
    }

    /// `sum_i q_i f^x(x_i + dx)`, summed chunk by chunk as the pass sums it: the attached
    /// junctions' `x_i + dx` packed block by block and their forces evaluated together
    /// ([`ForceLaw::force_x_many`]); with a team, the chunks are shared between its threads.
    fn attached_force(&self, dx: f64) -> f64 {
        let law = self.law;
        let chunk_sum = move |(qs, xs): (&[u8], &[f64])| {
            let mut packed = [0.0; BLOCK];
            let mut sum = 0.0;
            for (qs, xs) in qs.chunks(BLOCK).zip(xs.chunks(BLOCK)) {
                let k = pack_attached(qs, xs, dx, &mut packed);
                law.force_x_many(&mut packed[..k]);
                for &f in &packed[..k] {
                    sum += f;
                }
            }
            sum
        };
        let chunks = self.q.chunks(CHUNK).zip(self.x.chunks(CHUNK));
        match &self.team {
            Some(team) => total(team.map(chunks, |_, chunk| chunk_sum(chunk))),
            None => total(chunks.map(chunk_sum)),
        }
    }

    /// The friction (driving-spring) force `F = K (V t_n - X_n)`.
    #[inline]
    fn friction(&self, t: f64) -> f64 {
        self.plate.k * (self.plate.v * t - self.plate_x)
    }

    /// A kinematic plate (`X = V t`): friction is reported as `F_b`.
    #[inline]
    fn kinematic(&self) -> bool {
        self.integrator == Integrator::Kinematic
    }

    /// One step from `t_n` to `t_{n+1}`: flips, `F_b`, plate, pending junction update; the
    /// observer gets the step's events (if it wants them) and then its segment.
    ///
    /// The step itself ([`FixedEngine::step_with`]) does not depend on the observer, so it
    /// is compiled twice per engine type (with and without events), not once per observer.
    #[inline]
    fn step<O: Observer>(&mut self, obs: &mut O) -> Result<(), EngineError> {
        let segment = if O::EVENTS {
            let mut to = |events: &[JunctionEvent]| {
                for e in events {
                    obs.event(e);
                }
            };
            let mut events = ChunkEvents { kept: std::mem::take(&mut self.kept), to: &mut to };
            let segment = self.step_with(&mut events);
            self.kept = events.kept;
            segment?
        } else {
            self.step_with(&mut NoEvents)?
        };
        obs.segment(&segment);
        Ok(())
    }

    /// One step, its events put in `events`; returns the step's segment.
    #[inline(never)]
    fn step_with<E: Events>(&mut self, events: &mut E) -> Result<Segment, EngineError> {
        let t = self.steps as f64 * self.dt;
        let t_next = (self.steps + 1) as f64 * self.dt;
        let on_threshold = F::threshold(self.formation.k_on(self.plate_v) * self.dt);
        let pass = self.junction_pass(t, on_threshold, events);
        let state = PlateState { t, t_next, x: self.plate_x, v: self.plate_v, bond_force: pass.bond_force };
        let next = self.integrator.step(&self.plate, self.dt, state, |dx| self.bond_force_moved(dx, pass));
        // The plate, and (with a plate equation) the forces the step's segment and the next
        // sample report; a kinematic plate follows its drive whatever the forces.
        let forces = [
            ("F_b", pass.bond_force),
            ("eta Xd", self.plate.eta * next.viscous_v),
            ("F", self.plate.k * (self.plate.v * t_next - next.x)),
        ];
        let forces = if self.kinematic() { &forces[..0] } else { &forces[..] };
        for &(quantity, value) in [("X", next.x), ("Xd", next.v)].iter().chain(forces) {
            if !value.is_finite() || value.abs() > DIVERGENCE_LIMIT {
                return Err(EngineError::Diverged { step: self.steps + 1, t: t_next, quantity, value });
            }
        }
        let kinematic = self.kinematic();
        let segment = Segment {
            t0: t,
            t1: t_next,
            friction: if kinematic { pass.bond_force } else { self.friction(t) },
            friction_m2: 0.0,
            bond_force: pass.bond_force,
            viscous: self.plate.eta * next.viscous_v,
            attached: self.attached,
        };
        // Kinematic: attached junctions move by exactly V dt per step.
        self.pending_dx = if kinematic { self.plate.v * self.dt } else { next.x - self.plate_x };
        self.pending_relax = self.relax;
        self.plate_x = next.x;
        self.plate_v = next.v;
        self.steps += 1;
        Ok(segment)
    }
}

impl<L: ForceLaw, B: Bond, R, F: Flip> Engine for FixedEngine<L, B, R, F>
where
    R: UniformSource + Clone + std::fmt::Debug + Serialize + DeserializeOwned + Send + 'static,
{
    const KIND: EngineKind = EngineKind::Fixed;
    const WEAK_BONDS: bool = B::IS_WEAK;

    /// `t_n = n dt`, from the integer step count.
    fn time(&self) -> f64 {
        self.steps as f64 * self.dt
    }

    fn time_step(&self) -> Option<f64> {
        Some(self.dt)
    }

    /// Takes steps while `n dt < t_stop - 1e-9 dt`.
    fn advance<O: Observer>(&mut self, t_stop: f64, obs: &mut O) -> Result<(), EngineError> {
        let limit = crate::scene::FixedParams::step_limit(self.dt, t_stop);
        while (self.steps as f64) * self.dt < limit {
            self.step(obs)?;
        }
        Ok(())
    }

    /// The state at `t_n`, before step `n`'s flips.
    fn sample(&self) -> Sample {
        let t = self.time();
        let bond_force = self.bond_force_now();
        Sample {
            t,
            x: self.plate_x,
            v: self.plate_v,
            friction: if self.kinematic() { bond_force } else { self.friction(t) },
            bond_force,
            attached: self.attached,
            n: self.q.len() as u64,
        }
    }

    /// A `Team` of `threads` threads shares each step's pass (and velocity Verlet's second
    /// sum of `F_b`) from now on, when `N` is large enough to gain from it
    /// ([`super::team::PARALLEL_MIN`]); a run that logs events keeps its pass on one thread.
    fn set_threads(&mut self, threads: usize) {
        if self.team.as_ref().map_or(1, Team::threads) != threads.max(1) {
            self.team = Team::for_junctions(threads, self.q.len());
        }
    }

    fn counters(&self) -> Counters {
        Counters {
            ruptures: self.ruptures,
            formations: self.formations,
            steps: Some(self.steps),
            ..Counters::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::fixed::flip::LinearFlip;
    use crate::observe::Recorder;
    use crate::physics::{Formation, Linear, Plate, Strong};
    use crate::rng::ParkMiller;
    use crate::test_scenes as testkit;

    #[test]
    fn pending_update_is_applied_on_every_read() {
        let s = testkit::fig1_with(&["run.engine=fixed", "junctions.force_law=linear", "fixed.dt=0.5"]);
        let (law, bond) = (Linear::from_scene(&s), Strong::from_scene(&s));
        let mut e = FixedEngine::new(&s, law, bond, ParkMiller::new(4).unwrap(), LinearFlip);
        e.advance(10.0, &mut crate::observe::Nothing).unwrap();
        let read = |e: &FixedEngine<_, _, _, _>| -> Vec<(bool, f64)> {
            (0..e.len()).map(|i| (e.is_attached(i), e.extension(i))).collect()
        };
        let before = read(&e);
        let x_before = e.sample().x;
        let sum: f64 = before.iter().filter(|j| j.0).fold(0.0, |a, j| a + j.1);
        assert_eq!(e.sample().bond_force, law.force_x(sum));
        let mut rec = Recorder::default();
        e.advance(10.5, &mut rec).unwrap();
        let dx = e.sample().x - x_before;
        let relax = 1.0 - s.junctions.lambda * s.fixed.dt;
        let flipped: Vec<u32> = rec.events.iter().map(|ev| ev.junction).collect();
        assert!(!flipped.is_empty());
        for (i, (now, old)) in read(&e).iter().zip(&before).enumerate() {
            if flipped.contains(&(i as u32)) {
                assert_ne!(now.0, old.0);
            } else {
                assert_eq!(now.0, old.0);
                let want = if old.0 { old.1 + dx } else { old.1 * relax };
                assert_eq!(now.1, want, "junction {i}");
            }
        }
    }

    /// The stored form is the map a derived serde implementation of the engine's fields
    /// writes (`Derived`, the fields in declaration order): the same bytes, read back by
    /// either; and a map with a field missing or repeated is refused.
    #[test]
    fn stored_form_is_the_derived_map() {
        #[derive(Serialize, Deserialize)]
        struct Derived<L, B, R> {
            law: L,
            bond: B,
            flip: PhantomData<()>,
            formation: Formation,
            plate: Plate,
            integrator: Integrator,
            rng: R,
            dt: f64,
            relax: f64,
            unstretched: bool,
            strong_off_threshold: f64,
            steps: u64,
            plate_x: f64,
            plate_v: f64,
            q: Vec<u8>,
            x: Vec<f64>,
            pending_dx: f64,
            pending_relax: f64,
            attached: u64,
            ruptures: u64,
            formations: u64,
        }
        use crate::output::state_codec::{decode, encode};
        use crate::physics::{Tilted, Weak};
        let s = testkit::fig1_with(&["run.engine=fixed", "junctions.force_law=tilted", "junctions.bond=weak"]);
        let (law, bond) = (Tilted::from_scene(&s), Weak::from_scene(&s));
        let mut e = FixedEngine::new(&s, law, bond, ParkMiller::new(9).unwrap(), LinearFlip);
        e.advance(40.0, &mut crate::observe::Nothing).unwrap();
        let d = Derived {
            law: e.law,
            bond: e.bond,
            flip: PhantomData,
            formation: e.formation,
            plate: e.plate,
            integrator: e.integrator,
            rng: e.rng.clone(),
            dt: e.dt,
            relax: e.relax,
            unstretched: e.unstretched,
            strong_off_threshold: e.strong_off_threshold,
            steps: e.steps,
            plate_x: e.plate_x,
            plate_v: e.plate_v,
            q: e.q.clone(),
            x: e.x.clone(),
            pending_dx: e.pending_dx,
            pending_relax: e.pending_relax,
            attached: e.attached,
            ruptures: e.ruptures,
            formations: e.formations,
        };
        let (mut ours, mut derived) = (Vec::new(), Vec::new());
        encode(&mut ours, &e).unwrap();
        encode(&mut derived, &d).unwrap();
        assert_eq!(ours, derived);
        type E = FixedEngine<Tilted, Weak, ParkMiller, LinearFlip>;
        let mut back: E = decode(&derived).unwrap();
        let again: Derived<Tilted, Weak, ParkMiller> = decode(&ours).unwrap();
        assert_eq!((again.steps, again.x.len()), (e.steps, e.x.len()));
        let mut both = Vec::new();
        encode(&mut both, &back).unwrap();
        assert_eq!(both, ours);
        // The restored engine goes on as the original does.
        e.advance(60.0, &mut crate::observe::Nothing).unwrap();
        back.advance(60.0, &mut crate::observe::Nothing).unwrap();
        let bits = |e: &E| (e.sample().x.to_bits(), e.x.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), e.q.clone());
        assert_eq!(bits(&back), bits(&e));

        // Without `plate_v`, or with `steps` twice, or without the generator: refused.
        let map = |drop: &str, twice: &str| -> Vec<u8> {
            let v: serde_json::Value = serde_json::to_value(&d).unwrap();
            let mut fields: Vec<(String, serde_json::Value)> = v
                .as_object()
                .unwrap()
                .iter()
                .filter(|(k, _)| k.as_str() != drop)
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect();
            if let Some(dup) = fields.iter().find(|(k, _)| k == twice).cloned() {
                fields.push(dup);
            }
            let mut bytes = Vec::new();
            let mut ser = rmp_serde::Serializer::new(&mut bytes).with_struct_map();
            use serde::ser::SerializeMap;
            let mut m = serde::Serializer::serialize_map(&mut ser, Some(fields.len())).unwrap();
            for (k, v) in &fields {
                m.serialize_entry(k, v).unwrap();
            }
            m.end().unwrap();
            bytes
        };
        assert!(decode::<E>(&map("", "")).is_ok());
        for (drop, twice) in [("plate_v", ""), ("", "steps"), ("rng", ""), ("", "law")] {
            assert!(decode::<E>(&map(drop, twice)).is_err(), "without {drop:?}, twice {twice:?}");
        }
    }

    /// Over several chunks, a step's events come before its segment, in index order, one
    /// per flip the counters count, each with the junction's state and extension after the
    /// step; and the step without events (the team's path) leaves the same state.
    #[test]
    fn events_of_many_chunks_come_in_index_order_before_the_segment() {
        use crate::observe::JunctionEvent;
        use crate::physics::Weak;
        struct Order(Vec<char>);
        impl Observer for Order {
            const EVENTS: bool = true;
            fn event(&mut self, _: &JunctionEvent) {
                self.0.push('e');
            }
            fn segment(&mut self, _: &Segment) {
                self.0.push('s');
            }
        }
        let n = 3 * CHUNK + 17;
        let s = testkit::fig1_with(&[
            "run.engine=fixed",
            "junctions.force_law=linear",
            "junctions.bond=weak",
            &format!("junctions.n={n}"),
            "junctions.initial=stationary",
        ]);
        let (law, bond) = (Linear::from_scene(&s), Weak::from_scene(&s));
        let mut e = FixedEngine::new(&s, law, bond, ParkMiller::new(5).unwrap(), LinearFlip);
        let mut quiet = e.clone();
        for step in 0..6 {
            let before = e.counters();
            let mut before_step = e.clone();
            let mut rec = Recorder::default();
            e.step(&mut rec).unwrap();
            quiet.step(&mut crate::observe::Nothing).unwrap();
            let after = e.counters();
            let flips = (after.ruptures - before.ruptures) + (after.formations - before.formations);
            assert_eq!(rec.events.len() as u64, flips, "step {step}");
            assert!(flips > 0 && rec.events.last().unwrap().junction as usize > CHUNK);
            assert!(rec.events.windows(2).all(|w| w[0].junction < w[1].junction));
            assert_eq!(rec.segments.len(), 1);
            // The same step's calls in the order they came: every event before the segment.
            let mut order = Order(Vec::new());
            before_step.step(&mut order).unwrap();
            assert_eq!(order.0.len() as u64, flips + 1);
            assert!(order.0[..flips as usize].iter().all(|&c| c == 'e') && order.0.last() == Some(&'s'));
            for ev in &rec.events {
                let i = ev.junction as usize;
                assert_eq!(ev.t, rec.segments[0].t0);
                assert_eq!(e.is_attached(i), ev.kind == crate::observe::EventKind::Formation);
                assert_eq!(ev.extension.to_bits(), e.x[i].to_bits());
                assert_eq!(ev.tension, law.tension(ev.extension));
            }
            assert_eq!(
                quiet.x.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                e.x.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
            assert_eq!((quiet.q.clone(), quiet.plate_x.to_bits()), (e.q.clone(), e.plate_x.to_bits()));
        }
    }
}
