//! A bounded, decimating record of a sampled signal: at most [`CAPACITY`] buckets of equal
//! width, each holding the mean, minimum and maximum of the samples it covers. When the
//! record is full, neighbouring buckets are merged pairwise and the bucket width doubles, so the
//! memory does not grow with the run's length while the record always spans the whole
//! signal with between `CAPACITY / 2` and `CAPACITY` buckets.
//!
//! Bucket means are box-filtered samples: an oscillation of period `P` keeps a fraction
//! `sin(pi w / P) / (pi w / P)` of its amplitude in buckets of width `w` (0.97 at `P = 8 w`),
//! while bucket minima and maxima keep the signal's envelope exactly.

use serde::{Deserialize, Serialize};

/// Most buckets kept (a power of two).
pub const CAPACITY: usize = 1 << 14;

/// The record.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Decimator {
    /// Samples per complete bucket (a power of two).
    stride: u64,
    /// Complete buckets: `(mean, min, max)`.
    #[serde(rename = "bins")]
    buckets: Vec<(f64, f64, f64)>,
    /// The bucket being filled: sum, count, min, max (min and max meaningful when
    /// `count > 0`; kept finite so that the record serialises to JSON too).
    sum: f64,
    count: u64,
    min: f64,
    max: f64,
}

impl Default for Decimator {
    fn default() -> Self {
        Decimator::new()
    }
}

impl Decimator {
    pub fn new() -> Self {
        Decimator { stride: 1, buckets: Vec::new(), sum: 0.0, count: 0, min: 0.0, max: 0.0 }
    }

    /// Appends one sample.
    pub fn push(&mut self, x: f64) {
        if self.count == 0 {
            (self.min, self.max) = (x, x);
        } else {
            (self.min, self.max) = (self.min.min(x), self.max.max(x));
        }
        self.sum += x;
        self.count += 1;
        if self.count == self.stride {
            self.buckets.push((self.sum / self.count as f64, self.min, self.max));
            (self.sum, self.count) = (0.0, 0);
            if self.buckets.len() == CAPACITY {
                self.halve();
            }
        }
    }

    /// Merges neighbouring buckets pairwise; the bucket being filled keeps collecting samples
    /// (it is empty here: this is called only when a bucket has just been completed).
    fn halve(&mut self) {
        let merged: Vec<(f64, f64, f64)> = self
            .buckets
            .chunks_exact(2)
            .map(|p| (0.5 * (p[0].0 + p[1].0), p[0].1.min(p[1].1), p[0].2.max(p[1].2)))
            .collect();
        self.buckets = merged;
        self.stride *= 2;
    }

    /// Samples per complete bucket.
    pub fn stride(&self) -> u64 {
        self.stride
    }

    /// Complete buckets `(mean, min, max)`, in time order. The samples of an incomplete last
    /// bucket (fewer than [`Self::stride`]) are not included.
    pub fn buckets(&self) -> &[(f64, f64, f64)] {
        &self.buckets
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_records_keep_every_sample() {
        let mut d = Decimator::new();
        (0..100).for_each(|i| d.push(i as f64));
        assert_eq!(d.stride(), 1);
        assert_eq!(d.buckets().len(), 100);
        assert!(d.buckets().iter().enumerate().all(|(i, b)| *b == (i as f64, i as f64, i as f64)));
    }

    #[test]
    fn long_records_stay_bounded_and_keep_means_and_extremes() {
        let mut d = Decimator::new();
        let total = 5 * CAPACITY as u64 + 3;
        for i in 0..total {
            // A spike at one sample, otherwise x = i.
            d.push(if i == 12_345 { 1e6 } else { i as f64 });
        }
        // 5 C samples: the stride is 8 (C/2 <= buckets < C), the last 3 samples pending.
        assert_eq!(d.stride(), 8);
        assert!(d.buckets().len() >= CAPACITY / 2 && d.buckets().len() < CAPACITY);
        assert_eq!(d.buckets().len() as u64 * d.stride(), (total / 8) * 8);
        for (k, &(mean, min, max)) in d.buckets().iter().enumerate() {
            let (lo, hi) = (8 * k as u64, 8 * k as u64 + 7);
            if (lo..=hi).contains(&12_345) {
                assert_eq!(max, 1e6);
            } else {
                assert_eq!((mean, min, max), (0.5 * (lo + hi) as f64, lo as f64, hi as f64));
            }
        }
    }

    #[test]
    fn the_record_round_trips_through_serde() {
        let mut d = Decimator::new();
        (0..1000).for_each(|i| d.push((i as f64).sin()));
        let json = serde_json::to_string(&d).unwrap();
        let back: Decimator = serde_json::from_str(&json).unwrap();
        assert_eq!(back, d);
    }
}
