//! Channel clocks and the queue of pending events.
//!
//! A *channel* is a Poisson stream whose rate is constant between events: all formation
//! candidates (rate `kon0 N_detached`), all ruptures or rupture candidates, and the
//! deterministic end of a thinning horizon. Each channel keeps the absolute (local) time
//! of its next firing. When an event changes a channel's rate from `R` to `R'`, the
//! pending time is rescaled, `t' = now + (t - now) R / R'` (Gibson & Bruck 2000): the
//! residual unit-exponential hazard is memoryless, so this is exact and needs no new
//! random number. A channel that fires draws a fresh `Exp(1) / R`.
//!
//! The queue orders the channels by next firing time (ties: lowest channel index). Two
//! interchangeable implementations exist so that a bench can compare them:
//! [`ArrayQueue`] (a linear scan of the few channels) and [`PqQueue`] (the
//! `priority-queue` crate). See `benches/exact.rs` and `docs/performance.md`.

use std::cmp::Reverse;

use ordered_float::OrderedFloat;
use priority_queue::PriorityQueue;
use rand_distr::{Distribution, Exp1};
use serde::{Deserialize, Serialize, de::DeserializeOwned};

use crate::rng::Pcg64;

/// A channel's rate and next firing time (local time; `+inf` when the rate is 0).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Clock {
    pub rate: f64,
    pub next: f64,
}

impl Default for Clock {
    fn default() -> Self {
        Clock { rate: 0.0, next: f64::INFINITY }
    }
}

impl Clock {
    /// Next firing after `now` with a fresh unit exponential `e`: `now + e / rate`.
    #[inline]
    pub fn fire(&mut self, now: f64, e: f64) {
        self.next = if self.rate > 0.0 { now + e / self.rate } else { f64::INFINITY };
    }
    /// Changes the rate at `now`, rescaling the pending time. Returns `true` when the
    /// clock had no pending time and needs a fresh draw (`fire`).
    #[inline]
    pub fn set_rate(&mut self, now: f64, rate: f64) -> bool {
        if rate == self.rate {
            return false;
        }
        let old = self.rate;
        self.rate = rate;
        if rate <= 0.0 {
            self.next = f64::INFINITY;
            false
        } else if old > 0.0 && self.next.is_finite() {
            self.next = if rate.is_finite() { now + (self.next - now) * (old / rate) } else { now };
            false
        } else {
            true
        }
    }
}

/// Most channels an engine has (formation, rupture, the end of a horizon).
pub const MAX_CHANNELS: usize = 3;

/// The channels of an engine: their clocks and the queue that orders them. The clocks sit
/// in a fixed array of [`MAX_CHANNELS`] (the unused ones at rate 0, never firing), so the
/// event loop indexes them with constants and no bounds check; they are written and read
/// as a list of the engine's `n` channels, as before.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "", into = "ChannelsRepr<Q>", try_from = "ChannelsRepr<Q>")]
pub struct Channels<Q: ChannelQueue> {
    clocks: [Clock; MAX_CHANNELS],
    n: usize,
    queue: Q,
}

/// How [`Channels`] is written: the clocks of its `n` channels, and the queue.
#[derive(Serialize, Deserialize)]
#[serde(bound = "")]
struct ChannelsRepr<Q: ChannelQueue> {
    clocks: Vec<Clock>,
    queue: Q,
}

impl<Q: ChannelQueue> From<Channels<Q>> for ChannelsRepr<Q> {
    fn from(c: Channels<Q>) -> Self {
        ChannelsRepr { clocks: c.clocks[..c.n].to_vec(), queue: c.queue }
    }
}

impl<Q: ChannelQueue> TryFrom<ChannelsRepr<Q>> for Channels<Q> {
    type Error = String;
    fn try_from(r: ChannelsRepr<Q>) -> Result<Self, String> {
        let n = r.clocks.len();
        if n > MAX_CHANNELS {
            return Err(format!("{n} channels (at most {MAX_CHANNELS})"));
        }
        let mut clocks = [Clock::default(); MAX_CHANNELS];
        clocks[..n].copy_from_slice(&r.clocks);
        Ok(Channels { clocks, n, queue: r.queue })
    }
}

impl<Q: ChannelQueue> Channels<Q> {
    /// `n` channels (at most [`MAX_CHANNELS`]), all at rate 0 (never firing).
    pub fn new(n: usize) -> Self {
        assert!(n <= MAX_CHANNELS, "Channels::new: {n} channels (at most {MAX_CHANNELS})");
        Channels { clocks: [Clock::default(); MAX_CHANNELS], n, queue: Q::new(n) }
    }
    /// Sets the rates of channels `0..R` at `now`. Pending times are rescaled; channel
    /// `fired`, and any channel coming back from rate 0, draws a fresh exponential.
    /// Always inlined: it runs after every event, and a call costs a tenth of it.
    #[inline(always)]
    pub fn set_rates<const R: usize>(&mut self, now: f64, rates: [f64; R], fired: Option<usize>, rng: &mut Pcg64) {
        const { assert!(R <= MAX_CHANNELS) };
        for (ch, rate) in rates.into_iter().enumerate() {
            let clock = &mut self.clocks[ch];
            let fresh = if fired == Some(ch) {
                clock.rate = rate;
                true
            } else {
                clock.set_rate(now, rate)
            };
            if fresh {
                clock.fire(now, Exp1.sample(rng));
            }
            self.queue.set(ch, clock.next);
        }
    }
    /// A fresh time after `now` for channel `ch` at its current rate (after a rejected
    /// candidate at `now`).
    #[inline]
    pub fn redraw(&mut self, ch: usize, now: f64, rng: &mut Pcg64) {
        self.clocks[ch].fire(now, Exp1.sample(rng));
        self.queue.set(ch, self.clocks[ch].next);
    }
    /// Sets the time of a deterministic channel (such as the end of a horizon).
    #[inline]
    pub fn set_time(&mut self, ch: usize, t: f64) {
        self.clocks[ch].next = t;
        self.queue.set(ch, t);
    }
    /// The pending time of channel `ch`.
    #[inline]
    pub fn time(&self, ch: usize) -> f64 {
        self.clocks[ch].next
    }
    /// The channel that fires first and its time.
    #[inline]
    pub fn first(&self) -> (usize, f64) {
        self.queue.first()
    }
    /// Subtracts `dt` from every pending time (re-basing).
    pub fn shift(&mut self, dt: f64) {
        self.clocks[..self.n].iter_mut().for_each(|c| c.next -= dt);
        self.queue.shift(dt);
    }
}

/// The queue of pending channel times.
pub trait ChannelQueue: Clone + std::fmt::Debug + Serialize + DeserializeOwned + Send + 'static {
    fn new(channels: usize) -> Self;
    /// Sets channel `ch`'s next time.
    fn set(&mut self, ch: usize, time: f64);
    /// The channel that fires first and its time.
    fn first(&self) -> (usize, f64);
    /// Subtracts `dt` from every pending time (re-basing).
    fn shift(&mut self, dt: f64);
}

/// A scan over a handful of channels, in a fixed array of [`MAX_CHANNELS`] (the unused
/// entries at `+inf`, which never come first: the scan is three comparisons, whatever the
/// engine's count); written and read as the list of its `n` times.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(into = "ArrayQueueRepr", try_from = "ArrayQueueRepr")]
pub struct ArrayQueue {
    times: [f64; MAX_CHANNELS],
    n: usize,
}

/// How [`ArrayQueue`] is written: the times of its `n` channels.
#[derive(Serialize, Deserialize)]
struct ArrayQueueRepr {
    times: Vec<f64>,
}

impl From<ArrayQueue> for ArrayQueueRepr {
    fn from(q: ArrayQueue) -> Self {
        ArrayQueueRepr { times: q.times[..q.n].to_vec() }
    }
}

impl TryFrom<ArrayQueueRepr> for ArrayQueue {
    type Error = String;
    fn try_from(r: ArrayQueueRepr) -> Result<Self, String> {
        let n = r.times.len();
        if n > MAX_CHANNELS {
            return Err(format!("{n} channel times (at most {MAX_CHANNELS})"));
        }
        let mut times = [f64::INFINITY; MAX_CHANNELS];
        times[..n].copy_from_slice(&r.times);
        Ok(ArrayQueue { times, n })
    }
}

impl ChannelQueue for ArrayQueue {
    fn new(channels: usize) -> Self {
        assert!(channels <= MAX_CHANNELS, "ArrayQueue: {channels} channels (at most {MAX_CHANNELS})");
        ArrayQueue { times: [f64::INFINITY; MAX_CHANNELS], n: channels }
    }
    #[inline]
    fn set(&mut self, ch: usize, time: f64) {
        self.times[ch] = time;
    }
    #[inline]
    fn first(&self) -> (usize, f64) {
        let [t0, t1, t2] = self.times;
        let mut best = (0, t0);
        if t1 < best.1 {
            best = (1, t1);
        }
        if t2 < best.1 {
            best = (2, t2);
        }
        best
    }
    fn shift(&mut self, dt: f64) {
        self.times[..self.n].iter_mut().for_each(|t| *t -= dt);
    }
}

/// The `priority-queue` crate's indexed heap, keyed by channel.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PqQueue {
    pq: PriorityQueue<usize, Reverse<(OrderedFloat<f64>, usize)>>,
}

impl ChannelQueue for PqQueue {
    fn new(channels: usize) -> Self {
        let mut pq = PriorityQueue::with_capacity(channels);
        for ch in 0..channels {
            pq.push(ch, Reverse((OrderedFloat(f64::INFINITY), ch)));
        }
        PqQueue { pq }
    }
    #[inline]
    fn set(&mut self, ch: usize, time: f64) {
        self.pq.change_priority(&ch, Reverse((OrderedFloat(time), ch)));
    }
    #[inline]
    fn first(&self) -> (usize, f64) {
        let (&ch, p) = self.pq.peek().expect("channels are never removed");
        (ch, (p.0).0.0)
    }
    fn shift(&mut self, dt: f64) {
        let items: Vec<(usize, f64)> = self.pq.iter().map(|(&c, p)| (c, (p.0).0.0)).collect();
        for (c, t) in items {
            self.set(c, t - dt);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check<Q: ChannelQueue>() {
        let mut q = Q::new(3);
        assert_eq!(q.first().1, f64::INFINITY);
        q.set(1, 2.0);
        q.set(2, 1.0);
        assert_eq!(q.first(), (2, 1.0));
        q.set(0, 1.0);
        assert_eq!(q.first(), (0, 1.0), "ties go to the lowest channel");
        q.set(0, 5.0);
        q.set(2, 7.0);
        assert_eq!(q.first(), (1, 2.0));
        q.shift(1.5);
        assert_eq!(q.first(), (1, 0.5));
    }

    #[test]
    fn both_queues_order_channels() {
        check::<ArrayQueue>();
        check::<PqQueue>();
    }

    #[test]
    fn rescaling_keeps_the_residual_hazard() {
        let mut c = Clock { rate: 2.0, next: 0.0 };
        c.fire(1.0, 1.0); // fires at 1.5: residual hazard at t=1.2 is 2*(0.3) = 0.6
        assert!(!c.set_rate(1.2, 4.0));
        assert!((c.next - (1.2 + 0.6 / 4.0)).abs() < 1e-15);
        assert!(!c.set_rate(1.2, 0.0));
        assert_eq!(c.next, f64::INFINITY);
        assert!(c.set_rate(1.3, 1.0), "a clock coming back from rate 0 needs a fresh draw");
    }
}
