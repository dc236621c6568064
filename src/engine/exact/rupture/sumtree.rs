//! A sum tree over slots with two weight components, for weighted choice of a junction
//! in O(log N). Every update recomputes the path to the root from the children (no
//! running additions), so sums never drift and an emptied slot is exactly zero.
//!
//! The tree is 4-ary and each node is one 64-byte cache line holding the sums of its four
//! children (both components): a descent touches `log4 N` lines instead of the `log2 N`
//! of a binary tree, and at large N the lower levels are cache misses, so the number of
//! lines is what a choice costs (docs/performance.md has the measurements).

use serde::{Deserialize, Serialize};

use crate::engine::alloc::{self, AllocError};

/// Children per node.
const ARITY: usize = 4;

/// The sums `[component 0, component 1]` of a node's four children, in one cache line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[repr(C, align(64))]
struct Line([[f64; 2]; ARITY]);

impl Line {
    #[inline]
    fn sum(&self) -> [f64; 2] {
        let c = &self.0;
        [(c[0][0] + c[1][0]) + (c[2][0] + c[3][0]), (c[0][1] + c[1][1]) + (c[2][1] + c[3][1])]
    }
}

/// Complete 4-ary tree in heap layout: node `i` has children `4i + 1 ..= 4i + 4`; node
/// `i`'s line holds its children's sums. The `cap = 4^depth` slots are the children of the
/// bottom level: slot `s` is child `s % 4` of node `first_bottom + s / 4`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SumTree2 {
    cap: usize,
    /// Index of the first node of the bottom level, `(4^(depth-1) - 1) / 3`.
    first_bottom: usize,
    lines: Vec<Line>,
}

impl SumTree2 {
    /// A tree for `slots` slots, all zero.
    pub fn new(slots: usize) -> SumTree2 {
        Self::try_new(slots).unwrap_or_else(|e| panic!("{e}"))
    }
    /// [`SumTree2::new`], with its nodes reserved fallibly.
    pub fn try_new(slots: usize) -> Result<SumTree2, AllocError> {
        let (cap, nodes) = Self::shape(slots);
        // Huge pages are asked for before the tree is written: pages touched first are
        // backed by 4 KiB ones (with the kernel's `madvise` setting, the common default).
        let mut lines = alloc::with_capacity(nodes, "the rupture sum tree")?;
        crate::engine::exact::core::bags::advise_huge_pages(&lines);
        lines.resize(nodes, Line::default());
        Ok(SumTree2 { cap, first_bottom: nodes - cap / ARITY, lines })
    }
    /// `(slots of the bottom level, nodes)` of the tree for `slots` slots.
    fn shape(slots: usize) -> (usize, usize) {
        let mut cap = ARITY;
        let mut nodes = 1;
        while cap < slots {
            cap *= ARITY;
            nodes = nodes * ARITY + 1;
        }
        (cap, nodes)
    }
    /// Bytes of the tree for `slots` slots (what [`SumTree2::new`] allocates).
    pub fn bytes_for(slots: usize) -> u64 {
        Self::shape(slots).1 as u64 * std::mem::size_of::<Line>() as u64
    }
    /// Number of slots.
    pub fn capacity(&self) -> usize {
        self.cap
    }
    /// Weight of `slot`.
    #[inline]
    pub fn get(&self, slot: usize) -> [f64; 2] {
        self.lines[self.first_bottom + slot / ARITY].0[slot % ARITY]
    }
    /// The line of `node`, unchecked.
    ///
    /// # Safety
    /// `node < self.lines.len()`.
    #[inline(always)]
    unsafe fn line(&self, node: usize) -> &Line {
        debug_assert!(node < self.lines.len());
        // SAFETY: the caller's contract.
        unsafe { self.lines.get_unchecked(node) }
    }
    /// Sets the weights of `slot` and updates its ancestors.
    #[inline]
    pub fn set(&mut self, slot: usize, w: [f64; 2]) {
        assert!(slot < self.cap, "SumTree2::set: slot {slot} beyond capacity {}", self.cap);
        let mut node = self.first_bottom + slot / ARITY;
        self.lines[node].0[slot % ARITY] = w;
        // Every ancestor of a node below the end is below it too (parents have smaller
        // indices), so after the checked write above the walk needs no checks (a tenth of
        // a weak-bond event's instructions went to them).
        let lines = self.lines.as_mut_ptr();
        while node > 0 {
            let child = (node - 1) % ARITY;
            let parent = (node - 1) / ARITY;
            // SAFETY: parent < node < lines.len(), both inside the buffer.
            unsafe {
                let sum = (*lines.add(node)).sum();
                (*lines.add(parent)).0[child] = sum;
            }
            node = parent;
        }
    }
    /// Moves the weights of slot `last` into `slot` and empties `last` (the tree's side of
    /// a `swap_remove`): the same tree, bit for bit, as `set(slot, get(last))` then
    /// `set(last, [0; 2])`, with the two paths to the root walked together level by level
    /// (both leaves are at the same depth), and once from where they meet.
    #[inline]
    pub fn swap_remove(&mut self, slot: usize, last: usize) {
        assert!(
            slot < self.cap && last < self.cap,
            "SumTree2::swap_remove: slots {slot}, {last} beyond capacity {}",
            self.cap
        );
        let mut a = self.first_bottom + slot / ARITY;
        let mut b = self.first_bottom + last / ARITY;
        let w = self.lines[b].0[last % ARITY];
        self.lines[a].0[slot % ARITY] = w;
        self.lines[b].0[last % ARITY] = [0.0; 2];
        let lines = self.lines.as_mut_ptr();
        // Each node is summed after its children are final (a level at a time), so every
        // ancestor gets the same sums as from the two walks one after the other.
        while a > 0 {
            let (pa, pb) = ((a - 1) / ARITY, (b - 1) / ARITY);
            // SAFETY: parents have smaller indices than their children, and `a`, `b` start
            // inside the buffer (the checked accesses above).
            unsafe {
                let sum = (*lines.add(a)).sum();
                (*lines.add(pa)).0[(a - 1) % ARITY] = sum;
                if b != a {
                    let sum = (*lines.add(b)).sum();
                    (*lines.add(pb)).0[(b - 1) % ARITY] = sum;
                }
            }
            a = pa;
            b = pb;
        }
    }
    /// Sum of all weights, per component.
    #[inline]
    pub fn total(&self) -> [f64; 2] {
        self.lines[0].sum()
    }
    /// The slot where the cumulative weight of component `k` first exceeds `u`
    /// (`0 <= u < total[k]`): slot `s` is chosen with probability `w_s[k] / total[k]` for
    /// uniform `u`. Never returns a slot of zero weight when the total is positive (a `u`
    /// at or beyond the total by round-off lands on the last non-empty child).
    #[inline]
    pub fn find(&self, k: usize, u: f64) -> usize {
        self.find_prefetching::<()>(k, u, &[])
    }
    /// [`SumTree2::find`], which also requests the entries of `records` (one per slot) of the
    /// sixteen slots under the node a level above the bottom, when it gets there: the
    /// chosen slot's entry then loads while the bottom line does.
    #[inline]
    pub fn find_prefetching<T>(&self, k: usize, mut u: f64, records: &[T]) -> usize {
        // Every child of a node above the bottom level is in the tree (true by construction;
        // checked once here so that a tree read from a damaged checkpoint cannot make the
        // unchecked reads below leave the buffer).
        assert!(ARITY * self.first_bottom < self.lines.len(), "SumTree2: inconsistent shape");
        // The first node of the level above the bottom (`first_bottom = 4 f + 1`); a tree of
        // one level has none (`usize::MAX`: no node reaches it).
        let above_bottom = if self.first_bottom > 0 { (self.first_bottom - 1) / ARITY } else { usize::MAX };
        let mut node = 0;
        loop {
            // The next line is one of this node's four children (256 contiguous bytes):
            // requesting all four now starts the next miss before this node's choice is
            // known (whole runs at N = 1e6 with weak bonds: 14% faster, docs/performance.md).
            if node < self.first_bottom {
                // SAFETY: a node above the bottom level has its four children in the tree.
                unsafe { self.prefetch_children(node) };
                // A node whose children are at the bottom: the records of its sixteen slots,
                // from `(4 node + 1 - first_bottom) 4` on, a line (64 bytes) at a time.
                if node >= above_bottom && size_of::<T>() > 0 {
                    let first_slot = (ARITY * node + 1 - self.first_bottom) * ARITY;
                    if first_slot < records.len() {
                        let base = records.as_ptr().wrapping_add(first_slot).cast::<u8>();
                        for offset in (0..ARITY * ARITY * size_of::<T>()).step_by(64) {
                            crate::engine::exact::core::pick::prefetch_ptr(base.wrapping_add(offset));
                        }
                    }
                }
            }
            // SAFETY: the descent starts at the root and goes to a child only from a node
            // above the bottom level (checked below), whose children are in the tree (the
            // assertion above), so `node` is always in the tree.
            let c = unsafe { &self.line(node).0 };
            let (w0, w1, w2, w3) = (c[0][k], c[1][k], c[2][k], c[3][k]);
            // Move past child j when u reaches its sum and a later child has weight.
            let mut j = 0;
            if u >= w0 && (w1 + w2) + w3 > 0.0 {
                u -= w0;
                j = 1;
                if u >= w1 && w2 + w3 > 0.0 {
                    u -= w1;
                    j = 2;
                    if u >= w2 && w3 > 0.0 {
                        u -= w2;
                        j = 3;
                    }
                }
            }
            if node >= self.first_bottom {
                return (node - self.first_bottom) * ARITY + j;
            }
            node = ARITY * node + 1 + j;
        }
    }
    /// Requests the lines of the four children of `node` (256 contiguous bytes).
    ///
    /// # Safety
    /// `node` is above the bottom level (`node < first_bottom`), and the tree's shape is
    /// consistent (`ARITY * first_bottom < lines.len()`).
    #[inline(always)]
    unsafe fn prefetch_children(&self, node: usize) {
        let first = ARITY * node + 1;
        for i in 0..ARITY {
            // SAFETY: the caller's contract: `first + i <= ARITY * first_bottom < lines.len()`.
            unsafe { crate::engine::exact::core::pick::prefetch(self.line(first + i)) };
        }
    }
    /// Rebuilds the tree from the first `weights.len()` slots (the rest are zero). O(N).
    pub fn rebuild(&mut self, weights: impl ExactSizeIterator<Item = [f64; 2]>) {
        assert!(weights.len() <= self.cap);
        self.lines.iter_mut().for_each(|l| *l = Line::default());
        for (s, w) in weights.enumerate() {
            self.lines[self.first_bottom + s / ARITY].0[s % ARITY] = w;
        }
        for node in (1..self.lines.len()).rev() {
            let sum = self.lines[node].sum();
            self.lines[(node - 1) / ARITY].0[(node - 1) % ARITY] = sum;
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

    /// The prefetching descent chooses what `find` chooses, whatever the records' length
    /// (shorter than the tree, equal, longer, empty).
    #[test]
    fn prefetching_find_equals_find() {
        use crate::rng::UniformSource;
        let mut rng = crate::rng::pcg(12);
        let mut t = SumTree2::new(300);
        for s in 0..250 {
            let e = (4.0 * rng.uniform() - 2.0).exp();
            t.set(s, [1.0 / e, e]);
        }
        let total = t.total();
        for len in [0, 7, 250, 300, 1000] {
            let records = vec![0u64; len];
            for _ in 0..2000 {
                let k = usize::from(rng.uniform() < 0.5);
                let u = rng.uniform() * total[k];
                assert_eq!(t.find_prefetching(k, u, &records), t.find(k, u));
            }
        }
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

    /// `swap_remove` against its definition, two `set`s, over random removals and
    /// insertions of a compact prefix of slots (the engine's use), on several depths.
    #[test]
    fn swap_remove_equals_two_sets() {
        use crate::rng::UniformSource;
        let mut rng = crate::rng::pcg(5);
        for cap in [3, 16, 70, 1000] {
            let mut a = SumTree2::new(cap);
            let mut b = SumTree2::new(cap);
            let mut n = 0;
            for _ in 0..4000 {
                if n > 0 && (n == cap || rng.uniform() < 0.5) {
                    let slot = ((rng.uniform() * n as f64) as usize).min(n - 1);
                    let last = n - 1;
                    a.swap_remove(slot, last);
                    if slot != last {
                        let w = b.get(last);
                        b.set(slot, w);
                    }
                    b.set(last, [0.0; 2]);
                    n -= 1;
                } else {
                    let e = (4.0 * rng.uniform() - 2.0).exp();
                    a.set(n, [1.0 / e, e]);
                    b.set(n, [1.0 / e, e]);
                    n += 1;
                }
                assert_eq!(a, b, "cap {cap}, n {n}");
            }
        }
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
