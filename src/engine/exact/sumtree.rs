//! A sum tree over slots with two weight components, for weighted choice of a junction
//! in O(log N). Every update recomputes the path to the root from the children (no
//! running additions), so sums never drift and an emptied slot is exactly zero.

use serde::{Deserialize, Serialize};

/// Complete binary tree in heap layout: node `i` has children `2i`, `2i+1`; leaves are
/// nodes `cap..2cap` (slot `s` is node `cap + s`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SumTree2 {
    cap: usize,
    nodes: Vec<[f64; 2]>,
}

impl SumTree2 {
    /// A tree for `slots` slots, all zero.
    pub fn new(slots: usize) -> SumTree2 {
        let cap = slots.max(1).next_power_of_two();
        let nodes = vec![[0.0; 2]; 2 * cap];
        super::bags::advise_huge_pages(&nodes);
        SumTree2 { cap, nodes }
    }
    /// Number of slots.
    pub fn capacity(&self) -> usize {
        self.cap
    }
    /// Weight of `slot`.
    #[inline]
    pub fn get(&self, slot: usize) -> [f64; 2] {
        self.nodes[self.cap + slot]
    }
    /// Sets the weights of `slot` and updates its ancestors.
    #[inline]
    pub fn set(&mut self, slot: usize, w: [f64; 2]) {
        let mut i = self.cap + slot;
        self.nodes[i] = w;
        while i > 1 {
            i >>= 1;
            let (l, r) = (self.nodes[2 * i], self.nodes[2 * i + 1]);
            self.nodes[i] = [l[0] + r[0], l[1] + r[1]];
        }
    }
    /// Sum of all weights, per component.
    #[inline]
    pub fn total(&self) -> [f64; 2] {
        self.nodes[1]
    }
    /// The slot where the cumulative weight of component `k` first exceeds `u`
    /// (`0 <= u < total[k]`): slot `s` is chosen with probability `w_s[k] / total[k]` for
    /// uniform `u`. Never returns a slot of zero weight when the total is positive.
    #[inline]
    pub fn find(&self, k: usize, mut u: f64) -> usize {
        let mut i = 1;
        while i < self.cap {
            let l = self.nodes[2 * i][k];
            let r = self.nodes[2 * i + 1][k];
            if u < l || r == 0.0 {
                i *= 2;
            } else {
                u -= l;
                i = 2 * i + 1;
            }
        }
        i - self.cap
    }
    /// Rebuilds the tree from the first `weights.len()` slots (the rest are zero). O(N).
    pub fn rebuild(&mut self, weights: impl ExactSizeIterator<Item = [f64; 2]>) {
        assert!(weights.len() <= self.cap);
        self.nodes.iter_mut().for_each(|n| *n = [0.0; 2]);
        for (s, w) in weights.enumerate() {
            self.nodes[self.cap + s] = w;
        }
        for i in (1..self.cap).rev() {
            let (l, r) = (self.nodes[2 * i], self.nodes[2 * i + 1]);
            self.nodes[i] = [l[0] + r[0], l[1] + r[1]];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn find_follows_cumulative_weights() {
        let mut t = SumTree2::new(5);
        let w = [1.0, 0.0, 2.0, 0.5, 0.0];
        for (s, &x) in w.iter().enumerate() {
            t.set(s, [x, 1.0]);
        }
        assert_eq!(t.total(), [3.5, 5.0]);
        assert_eq!(t.find(0, 0.0), 0);
        assert_eq!(t.find(0, 0.999), 0);
        assert_eq!(t.find(0, 1.0), 2);
        assert_eq!(t.find(0, 2.999), 2);
        assert_eq!(t.find(0, 3.0), 3);
        assert_eq!(t.find(0, 3.4999), 3);
        // u at the total (round-off) still lands on a non-empty slot.
        assert_eq!(t.find(0, 3.5), 3);
        assert_eq!(t.find(1, 4.5), 4);
        t.set(3, [0.0, 0.0]);
        assert_eq!(t.total(), [3.0, 4.0]);
        assert_eq!(t.find(0, 3.0), 2);
    }

    #[test]
    fn rebuild_equals_sets() {
        let mut a = SumTree2::new(7);
        let mut b = SumTree2::new(7);
        let w: Vec<[f64; 2]> = (0..6).map(|i| [i as f64 * 0.3, 1.0 / (1.0 + i as f64)]).collect();
        for (s, x) in w.iter().enumerate() {
            a.set(s, *x);
        }
        b.rebuild(w.into_iter());
        assert_eq!(a, b);
    }

    /// Deep trees: every slot is found at the middle of its own weight interval, and the
    /// choice frequencies follow the weights (chi-square, 0.999 quantile for 99 df = 148.2).
    #[test]
    fn deep_tree_choices_follow_the_weights() {
        let n = 100;
        let mut t = SumTree2::new(5000);
        let w: Vec<f64> = (0..n).map(|i| 0.5 + (i % 7) as f64).collect();
        // Occupy scattered slots so that several levels are exercised.
        let slot = |i: usize| i * 47;
        for (i, &x) in w.iter().enumerate() {
            t.set(slot(i), [x, 0.0]);
        }
        let total: f64 = w.iter().sum();
        assert!((t.total()[0] - total).abs() < 1e-12);
        let mut cum = 0.0;
        for (i, &x) in w.iter().enumerate() {
            assert_eq!(t.find(0, cum + 0.5 * x), slot(i));
            cum += x;
        }
        let mut rng = crate::rng::pcg(9);
        let mut counts = vec![0.0; n];
        let draws = 200_000;
        for _ in 0..draws {
            use crate::rng::UniformSource;
            let s = t.find(0, rng.uniform() * total);
            counts[s / 47] += 1.0;
        }
        let chi2: f64 = (0..n)
            .map(|i| {
                let e = draws as f64 * w[i] / total;
                (counts[i] - e).powi(2) / e
            })
            .sum();
        assert!(chi2 < 148.2, "chi2 = {chi2}");
    }
}
