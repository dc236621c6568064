//! The output grid: the times at which the loop stops the engine, and where a walk along
//! it has got to.

use serde::{Deserialize, Serialize};

use crate::scene::Scene;

/// One stop of the output grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stop {
    pub t: f64,
    /// Whether the state is sampled here.
    pub sample: bool,
}

/// The output grid: samples at `k * sample_dt` up to `t_end` (the fixed engine's grid is
/// rounded to whole steps), a final sample at `t_end`, and a silent stop at `t_warmup` so
/// that no segment straddles the start of the averaging window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputGrid {
    pub sample_dt: f64,
    pub t_warmup: f64,
    pub t_end: f64,
}

impl OutputGrid {
    /// The scene's grid, for an engine with step `time_step` (if it has one).
    pub fn new(scene: &Scene, time_step: Option<f64>) -> Self {
        let mut sample_dt = scene.output.sample_dt;
        if let Some(dt) = time_step {
            sample_dt = dt * (sample_dt / dt).round().max(1.0);
        }
        OutputGrid { sample_dt, t_warmup: scene.run.t_warmup, t_end: scene.run.t_end }
    }

    /// The stops after `t = t_from`, in increasing order.
    pub fn stops_after(&self, t_from: f64) -> Stops {
        let mut k = (t_from / self.sample_dt).floor().max(0.0) as u64;
        while k as f64 * self.sample_dt <= t_from {
            k += 1;
        }
        // A grid point within round-off of t_end is t_end itself (sampled once, as the final
        // stop). The slack is relative to t_end *and* to sample_dt: at t_end = 1e12 a slack
        // of 1e-12 t_end alone (one time unit) dropped every sample in the last time unit.
        let last = (self.t_end * (1.0 - 1e-12)).max(self.t_end - 1e-6 * self.sample_dt);
        let warmup = (self.t_warmup > t_from).then_some(self.t_warmup);
        Stops { grid: *self, last, k, warmup, done: false }
    }

    /// A walk from a run's start or from a checkpoint's position (`stops_done` stops of
    /// `stops_after(0.0)` done).
    pub fn walk_from(&self, position: GridPosition) -> Walk {
        let mut stops = self.stops_after(0.0);
        if position.stops_done > 0 {
            stops.nth(position.stops_done as usize - 1);
        }
        Walk::new(stops, position)
    }

    /// A walk from wherever an engine is: the stops after `t` (with a sample at `t = 0`
    /// first when `t` is 0). Its position counts stops from `t`.
    pub fn walk_after(&self, t: f64) -> Walk {
        Walk::new(self.stops_after(t), GridPosition::default())
    }
}

/// The stops of an [`OutputGrid`] after some time (see [`OutputGrid::stops_after`]).
#[derive(Clone, Debug)]
pub struct Stops {
    grid: OutputGrid,
    /// Grid points at or beyond this are the final stop.
    last: f64,
    /// Index of the next sample point `k * sample_dt`.
    k: u64,
    /// The warm-up stop, while it is still ahead.
    warmup: Option<f64>,
    done: bool,
}

impl Iterator for Stops {
    type Item = Stop;

    fn next(&mut self) -> Option<Stop> {
        if self.done {
            return None;
        }
        let ts = self.k as f64 * self.grid.sample_dt;
        let sample = (ts < self.last).then_some(ts);
        if let Some(w) = self.warmup {
            match sample {
                Some(ts) if ts < w => {}
                Some(ts) if ts == w => self.warmup = None,
                _ => {
                    self.warmup = None;
                    return Some(Stop { t: w, sample: false });
                }
            }
        }
        if let Some(ts) = sample {
            self.k += 1;
            return Some(Stop { t: ts, sample: true });
        }
        self.done = true;
        Some(Stop { t: self.grid.t_end, sample: true })
    }
}

/// Where a run is on its output grid: what a checkpoint records, and what the loop needs
/// to continue it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridPosition {
    /// Stops of the walk done (for a run, of `grid.stops_after(0.0)`).
    pub stops_done: u64,
    /// Time of the last sample fed to the observers (NaN before the first).
    pub last_sample_t: f64,
}

impl Default for GridPosition {
    fn default() -> Self {
        GridPosition { stops_done: 0, last_sample_t: f64::NAN }
    }
}

/// A walk along the grid: the stops ahead and the position reached. It owns a copy of its
/// grid, so it can be kept between two drives (a run stopped on request goes on from it).
#[derive(Clone, Debug)]
pub struct Walk {
    stops: Stops,
    /// The next stop, once looked at.
    next: Option<Option<Stop>>,
    position: GridPosition,
}

impl Walk {
    fn new(stops: Stops, position: GridPosition) -> Self {
        Walk { stops, next: None, position }
    }

    /// The position reached.
    pub fn position(&self) -> GridPosition {
        self.position
    }

    /// The next stop, without moving.
    pub fn peek(&mut self) -> Option<Stop> {
        *self.next.get_or_insert_with(|| self.stops.next())
    }

    /// Moves to the next stop (counted as done once the caller has reached it).
    pub(super) fn take(&mut self) -> Option<Stop> {
        self.next.take().unwrap_or_else(|| self.stops.next())
    }

    pub(super) fn position_mut(&mut self) -> &mut GridPosition {
        &mut self.position
    }

    /// Whether the walk has reached its end.
    pub fn finished(&mut self) -> bool {
        self.peek().is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(sample_dt: f64, t_warmup: f64, t_end: f64) -> OutputGrid {
        OutputGrid { sample_dt, t_warmup, t_end }
    }

    #[test]
    fn stops_cover_samples_warmup_and_end() {
        let g = grid(1.0, 2.5, 4.0);
        let s: Vec<Stop> = g.stops_after(0.0).collect();
        let t: Vec<(f64, bool)> = s.iter().map(|s| (s.t, s.sample)).collect();
        assert_eq!(t, vec![(1.0, true), (2.0, true), (2.5, false), (3.0, true), (4.0, true)]);
    }

    #[test]
    fn warmup_on_a_sample_is_one_stop() {
        let t: Vec<f64> = grid(0.5, 1.0, 2.0).stops_after(0.0).map(|s| s.t).collect();
        assert_eq!(t, vec![0.5, 1.0, 1.5, 2.0]);
    }

    #[test]
    fn resuming_mid_grid_continues_it() {
        let t: Vec<f64> = grid(1.0, 0.0, 3.5).stops_after(1.0).map(|s| s.t).collect();
        assert_eq!(t, vec![2.0, 3.0, 3.5]);
        let t: Vec<f64> = grid(1.0, 0.0, 3.5).stops_after(1.25).map(|s| s.t).collect();
        assert_eq!(t, vec![2.0, 3.0, 3.5]);
    }

    #[test]
    fn end_not_on_grid_and_grid_coarser_than_run() {
        let t: Vec<f64> = grid(10.0, 0.0, 3.0).stops_after(0.0).map(|s| s.t).collect();
        assert_eq!(t, vec![3.0]);
    }

    /// Regression: at t_end = 1e12 the end slack was 1e-12 t_end = 1 time unit, and the
    /// samples at t_end - 0.5 (and any in the last time unit) were dropped.
    #[test]
    fn late_samples_are_kept_at_large_times() {
        let t0 = 1e12;
        let t: Vec<f64> = grid(0.25, 0.0, t0 + 1.0).stops_after(t0).map(|s| s.t).collect();
        assert_eq!(t, vec![t0 + 0.25, t0 + 0.5, t0 + 0.75, t0 + 1.0]);
    }

    #[test]
    fn a_walk_from_a_position_continues_the_whole_walk() {
        let g = grid(0.75, 2.5, 12.0);
        let all: Vec<Stop> = g.stops_after(0.0).collect();
        for done in 0..=all.len() {
            let mut w = g.walk_from(GridPosition { stops_done: done as u64, last_sample_t: 0.0 });
            let mut rest = Vec::new();
            while let Some(s) = w.peek() {
                assert_eq!(w.take(), Some(s), "take gives what peek showed");
                rest.push(s);
            }
            assert_eq!(rest, all[done..], "from {done} stops done");
            assert!(w.finished());
        }
    }
}
