//! The series engine: event loop, junction bookkeeping, frame re-basing.

use rand::RngExt;
use serde::{Deserialize, Serialize};

use super::SeriesSum;
use super::kinetics::Kinetics;
use super::motion::{Motion, Step, StepCtx};
use crate::engine::exact::bags::{Bags, Detached, prefetch};
use crate::engine::exact::clocks::{ArrayQueue, Channels};
use crate::engine::exact::core::{REBASE, emit, reattached_extension};
use crate::engine::exact::frame::Frame;
use crate::engine::{Counters, Engine, EngineError};
use crate::observe::{EventKind, Observer, Sample};
use crate::physics::{ForceLaw, Formation, Plate, Tilted};
use crate::rng::{Pcg64, UniformSource, pcg};
use crate::scene::{EngineKind, Reattach, Scene};

const FORMATION: usize = 0;
const RUPTURE: usize = 1;

/// Exact engine for the tilted law with the bond force kept as a [`SeriesSum`]: rupture
/// kinetics `K`, plate motion `P`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct ExactSeries<K: Kinetics, P: Motion> {
    n: usize,
    plate: Plate,
    law: Tilted,
    lambda: f64,
    reattach: Reattach,
    formation: Formation,
    frame: Frame,
    /// Local time.
    tau: f64,
    /// The junctions; each attached one carries its `SeriesSum` handle (`Attached::bin`).
    bags: Bags,
    series: SeriesSum,
    kinetics: K,
    motion: P,
    channels: Channels<ArrayQueue>,
    rng: Pcg64,
    counters: Counters,
    events_since_rebase: u64,
    /// `exact.rtol`: the series' stated tolerance, relative to `kappa l0 max(N_att, 1)`.
    rtol: f64,
    /// The relative error bound just after the engine last refreshed the series (see
    /// [`ExactSeries::track_error`]); a refresh is taken only when the bound has doubled since.
    error_floor: f64,
    /// The series changed (attach, rupture, shift) since its error bound was last recorded.
    /// Not serialised: a resumed run records it again at its first plate step.
    #[serde(skip, default = "yes")]
    error_stale: bool,
    /// The series' relative error bound as last recorded by [`ExactSeries::track_error`]; a
    /// step that evaluated the local cubic records it plus the cubic's remainder. Not
    /// serialised: recorded again at a resumed run's first plate step (`error_stale`).
    #[serde(skip)]
    last_rel: f64,
}

fn yes() -> bool {
    true
}

impl<K: Kinetics, P: Motion> ExactSeries<K, P> {
    /// The engine at `t = 0` for `scene` under the tilted-form law `law`; `kinetics` and
    /// `motion` are built by the caller.
    pub fn new(scene: &Scene, law: Tilted, kinetics: K, motion: P) -> Result<Self, EngineError> {
        let j = &scene.junctions;
        let mut rng = pcg(scene.run.seed);
        let bags = Bags::initial(j, &mut rng)?;
        let plate = Plate::from_scene(scene);
        let series = SeriesSum::new(law, scene.exact.rtol);
        let mut e = ExactSeries {
            n: j.n,
            plate,
            law,
            lambda: j.lambda,
            reattach: j.reattach,
            formation: Formation::from_scene(scene),
            frame: Frame::new(plate.v),
            tau: 0.0,
            bags,
            series,
            kinetics,
            motion,
            channels: Channels::new(2),
            rng,
            counters: Counters {
                events: Some(0),
                candidates: Some(0),
                rebases: Some(0),
                series_rebases: Some(0),
                series_error: Some(0.0),
                ..Default::default()
            },
            events_since_rebase: 0,
            rtol: scene.exact.rtol,
            error_floor: 0.0,
            error_stale: true,
            last_rel: 0.0,
        };
        if !P::KINEMATIC {
            e.counters.ode_steps = Some(0);
            e.counters.ode_rejected = Some(0);
        }
        for slot in 0..e.bags.n_attached() {
            let c = e.bags.attached[slot].c;
            e.bags.attached[slot].bin = e.series.add(c);
            // Every initial junction is unstretched (x = 0): its rate cannot overflow.
            e.kinetics.attached(slot, c, 0.0);
        }
        e.track_error();
        e.motion.open_piece(0.0, &e.series, &e.frame);
        e.refresh_clocks(None);
        Ok(e)
    }

    #[inline]
    fn y(&self) -> f64 {
        self.motion.y(self.tau)
    }

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
    /// [`ExactSeries::refresh_series`], which resets both): at a removal that takes the
    /// residue count above the attached count (so the truncation part stays `<= rtol/2`;
    /// amortised, once each time the count halves), and here, once the whole bound passes
    /// `rtol / 2`, unless that did not halve it the last time.
    /// Returns the bound recorded (before a refresh); `last_rel` is the bound after it.
    #[inline]
    fn track_error(&mut self) -> f64 {
        self.error_stale = false;
        let scale = self.series.scale();
        let rel = self.series.error_bound() / scale;
        self.last_rel = rel;
        if rel > 0.5 * self.rtol && rel > 2.0 * self.error_floor {
            self.refresh_series();
            self.error_floor = self.series.error_bound() / scale;
            self.last_rel = self.error_floor;
        }
        self.record_error(rel);
        rel
    }

    /// `series_error = max(series_error, rel)`.
    #[inline]
    fn record_error(&mut self, rel: f64) {
        let e = self.counters.series_error.get_or_insert(0.0);
        if rel > *e {
            *e = rel;
        }
    }

    /// Re-bases the series at its own base point: the residue and the round-off allowance
    /// start again from zero. O(bins p^2).
    fn refresh_series(&mut self) {
        let base = self.series.base();
        self.series.rebase(base);
        *self.counters.series_rebases.get_or_insert(0) += 1;
    }

    fn refresh_clocks(&mut self, fired: Option<usize>) {
        let rates =
            [self.formation.kon0 * self.bags.n_detached() as f64, self.kinetics.channel_rate(self.bags.n_attached())];
        self.channels.set_rates(self.tau, rates, fired, &mut self.rng);
    }

    /// Reports the piece up to now.
    fn close_piece<O: Observer>(&mut self, obs: &mut O) {
        if let Some(mut s) = self.motion.segment(self.tau, &self.frame, &self.plate, &self.series) {
            s.attached = self.bags.n_attached() as u64;
            obs.segment(&s);
        }
    }

    #[inline]
    fn emit<O: Observer>(&self, obs: &mut O, kind: EventKind, id: u32, x: f64) {
        emit(obs, self.frame.time(self.tau), kind, id, x, |x| self.law.tension(x));
    }

    fn rupture_slot<O: Observer>(&mut self, slot: usize, obs: &mut O) {
        let last = self.bags.n_attached() - 1;
        let a = self.bags.take_attached(slot);
        self.series.remove(a.c, a.bin);
        if self.series.residue() > self.series.len() as u64 {
            self.refresh_series();
        }
        self.error_stale = true;
        self.kinetics.detached(slot, last);
        let x = self.y() - a.c;
        self.bags.detached.push(Detached { x, t: self.tau, id: a.id });
        self.counters.ruptures += 1;
        self.emit(obs, EventKind::Rupture, a.id, x);
    }

    fn form_one<O: Observer>(&mut self, obs: &mut O) {
        if self.kinetics.needs_rebase(self.y()) {
            self.rebase(obs);
        }
        let slot = self.rng.random_range(0..self.bags.n_detached());
        let d = self.bags.take_detached(slot);
        let x = reattached_extension(self.reattach, self.lambda, &d, self.tau);
        let y = self.y();
        let c = y - x;
        let bin = self.series.add(c);
        self.bags.attach_in_bin(c, d.id, bin);
        self.error_stale = true;
        self.counters.formations += 1;
        self.emit(obs, EventKind::Formation, d.id, x);
        let slot = self.bags.n_attached() - 1;
        if !self.kinetics.attached(slot, c, y) {
            self.rupture_slot(slot, obs);
        }
    }

    fn maybe_rebase<O: Observer>(&mut self, obs: &mut O) {
        let y = self.y();
        if REBASE.due(y, self.tau, self.events_since_rebase, self.n, self.kinetics.needs_rebase(y)) {
            self.rebase(obs);
        }
    }

    /// Moves the local origin to the current time and position (at a piece boundary: the
    /// piece's own origin moves with it).
    fn rebase<O: Observer>(&mut self, obs: &mut O) {
        let (dtau, dy) = (self.tau, self.y());
        self.frame.shift(dtau, dy);
        self.bags.rebase(dtau, dy);
        self.channels.shift(dtau);
        self.series.shift(dy);
        self.error_stale = true;
        self.motion.rebase(dtau, dy);
        self.tau = 0.0;
        self.events_since_rebase = 0;
        *self.counters.rebases.get_or_insert(0) += 1;
        let mut over = self.kinetics.rebuild(&self.bags.attached);
        over.sort_unstable_by(|a, b| b.cmp(a));
        for slot in over {
            self.rupture_slot(slot, obs);
        }
    }

    fn after_event<O: Observer>(&mut self, fired: Option<usize>, obs: &mut O) {
        self.events_since_rebase += 1;
        *self.counters.events.get_or_insert(0) = self.counters.ruptures + self.counters.formations;
        self.maybe_rebase(obs);
        self.motion.open_piece(self.tau, &self.series, &self.frame);
        self.refresh_clocks(fired);
    }

    fn check(&self) -> Result<(), EngineError> {
        let y = self.y();
        if !y.is_finite() {
            return Err(EngineError::NonFinite { t: self.time(), quantity: "X", value: y });
        }
        Ok(())
    }

    /// Strong bonds: the plate step draws no random numbers, so the junction the due event
    /// on channel `ch` will pick is already known; asking for its record now lets the memory
    /// access (a random one among millions at large N) overlap the step. The picks are
    /// drawn on a copy of the generator, exactly as the event will draw them (formation:
    /// after the thinning's uniform when `g < 1`, so both candidates), and the run's
    /// stream is untouched.
    #[inline]
    fn prefetch_pick(&self, ch: usize) {
        match ch {
            FORMATION => {
                let n = self.bags.n_detached();
                if n > 0 {
                    let mut rng = self.rng.clone();
                    prefetch(&self.bags.detached[rng.clone().random_range(0..n)]);
                    rng.uniform();
                    prefetch(&self.bags.detached[rng.random_range(0..n)]);
                }
            }
            _ => {
                let n = self.bags.n_attached();
                if n > 0 {
                    prefetch(&self.bags.attached[self.rng.clone().random_range(0..n)]);
                }
            }
        }
    }

    /// One plate step towards `target`; weak bonds thin their rupture candidates over it.
    /// Returns the slot that ruptured inside the step, if one did (the state is then at
    /// the rupture time).
    fn plate_step(&mut self, target: f64) -> Result<Option<usize>, EngineError> {
        let rebases = self.counters.series_rebases;
        let mut ctx = StepCtx {
            series: &mut self.series,
            frame: &self.frame,
            counters: &mut self.counters,
            max_spread: self.kinetics.max_spread(),
        };
        let step: Step = self.motion.step(&mut ctx, self.tau, target)?;
        let mut hit = None;
        if K::IS_WEAK {
            let mut cands = 0;
            let motion = &mut self.motion;
            hit = self.kinetics.thin(
                &mut self.rng,
                (step.s0, step.s1),
                (step.y_lo, step.y_hi),
                &self.bags.attached,
                &self.law,
                |s| motion.y_at(s),
                &mut cands,
            )?;
            *self.counters.candidates.get_or_insert(0) += cands;
        }
        let end = hit.map_or(step.s1, |(s, _)| s);
        self.motion.finish(&step, end, &self.series)?;
        self.tau = end;
        self.motion.sync_counters(&mut self.counters);
        // The series' bound over the step: as it was when the step took its cubic.
        let series_rel = if self.error_stale || self.counters.series_rebases != rebases {
            self.track_error()
        } else {
            self.last_rel
        };
        if step.cubic_error > 0.0 {
            self.record_error(series_rel + step.cubic_error);
        }
        Ok(hit.map(|(_, slot)| slot))
    }
}

impl<K: Kinetics, P: Motion> Engine for ExactSeries<K, P> {
    const KIND: EngineKind = EngineKind::Exact;
    const WEAK_BONDS: bool = K::IS_WEAK;

    fn time(&self) -> f64 {
        self.frame.time(self.tau)
    }

    fn time_step(&self) -> Option<f64> {
        None
    }

    fn advance<O: Observer>(&mut self, t_stop: f64, obs: &mut O) -> Result<(), EngineError> {
        loop {
            // In the local frame, which a re-basing inside this loop moves.
            let tau_stop = self.frame.local(t_stop).max(self.tau);
            let (ch, t_next) = self.channels.first();
            let target = t_next.min(tau_stop);
            // A NaN time is never due (it would stop the loop, not spin it).
            let due = t_next <= tau_stop;
            if self.tau < target {
                if !K::IS_WEAK && due {
                    self.prefetch_pick(ch);
                }
                if let Some(slot) = self.plate_step(target)? {
                    self.check()?;
                    self.close_piece(obs);
                    self.rupture_slot(slot, obs);
                    self.after_event(None, obs);
                    continue;
                }
                if self.tau < target {
                    continue;
                }
            }
            self.check()?;
            if !due {
                self.close_piece(obs);
                self.maybe_rebase(obs);
                self.motion.open_piece(self.tau, &self.series, &self.frame);
                return Ok(());
            }
            *self.counters.candidates.get_or_insert(0) += 1;
            match ch {
                FORMATION => {
                    let g = self.formation.g(self.motion.velocity(&self.series, &self.frame, self.tau));
                    if g >= 1.0 || self.rng.uniform() < g {
                        self.close_piece(obs);
                        self.form_one(obs);
                        self.after_event(Some(FORMATION), obs);
                    } else {
                        self.channels.redraw(FORMATION, self.tau, &mut self.rng);
                    }
                }
                _ => {
                    self.close_piece(obs);
                    let slot = self.rng.random_range(0..self.bags.n_attached());
                    self.rupture_slot(slot, obs);
                    self.after_event(Some(RUPTURE), obs);
                }
            }
        }
    }

    fn sample(&self) -> Sample {
        let y = self.y();
        let fb = self.series.force(y);
        let friction = if P::KINEMATIC { fb } else { -self.plate.k * self.motion.lag(self.tau, &self.frame) };
        Sample {
            t: self.time(),
            x: self.frame.position(y),
            v: self.motion.velocity(&self.series, &self.frame, self.tau),
            friction,
            bond_force: fb,
            attached: self.bags.n_attached() as u64,
            n: self.n as u64,
        }
    }

    fn counters(&self) -> Counters {
        self.counters.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::ExactSeries;
    use crate::engine::exact::series::{DrivenPlate, StrongKinetics};
    use crate::observe::Nothing;
    use crate::physics::{ForceLaw, Tilted};
    use crate::test_scenes::fig1_with;

    /// A stick phase: every junction is counted through the bins at a re-base, then all but
    /// one rupture with the plate at rest. Each removal leaves a residue in the bound; the
    /// engine refreshes the series whenever the residue count passes the attached count, so
    /// the bound stays within `rtol / 2` of `kappa l0 N_att` (plus round-off), the refreshes
    /// are amortised (one per halving of the count), and the series still agrees with the
    /// direct sum within its bound.
    #[test]
    fn series_refreshed_in_a_stick_phase() {
        let s = fig1_with(&[
            "run.engine=exact",
            "junctions.force_law=tilted",
            "junctions.n=4096",
            "junctions.initial=attached",
            "plate.kinematic=true",
        ]);
        let mut e =
            ExactSeries::new(&s, Tilted::from_scene(&s), StrongKinetics { k0: s.junctions.k0 }, DrivenPlate::new(0.0))
                .unwrap();
        let base = e.series.base();
        e.series.rebase(base);
        let rebases0 = e.counters.series_rebases.unwrap();
        let (kl0, rtol) = (e.law.kappa * e.law.l0, e.rtol);
        // Spread the anchors over several bins, as a moving plate would have.
        let y = 0.05;
        while e.bags.n_attached() > 1 {
            e.rupture_slot(e.bags.n_attached() - 1, &mut Nothing);
            let n = e.bags.n_attached();
            assert!(e.series.residue() <= n as u64, "residue {} above {n} attached", e.series.residue());
            let rel = e.series.error_bound() / (kl0 * n.max(1) as f64);
            assert!(rel <= 0.5 * rtol * (1.0 + 1e-3), "relative bound {rel} at {n} attached, rtol {rtol}");
            if n % 97 == 0 {
                let direct: f64 = e.bags.attached[..n].iter().map(|a| e.law.force_x(y - a.c)).sum();
                let err = (e.series.force(y) - direct).abs();
                assert!(err <= e.series.error_bound() + 1e-12 * kl0, "series off by {err} at {n} attached");
            }
        }
        let refreshes = e.counters.series_rebases.unwrap() - rebases0;
        assert!((10..=14).contains(&refreshes), "{refreshes} refreshes for 4095 ruptures from 4096");
    }
}
