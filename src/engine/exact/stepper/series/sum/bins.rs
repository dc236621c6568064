//! Bins mode's store: the anchors' bins (count and raw moments about the centre), the O(1)
//! grid-index cache of their sorted index, and one bin's double expansion about the base
//! (module doc of [`super`], "Two expansions of one junction").

use serde::{Deserialize, Serialize};

use super::coefficients::PMAX;

/// One bin of anchors: grid index, count, raw moments about the centre.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct Bin {
    /// Grid index `j`: centre `origin + (j + 1/2) w`.
    pub(super) j: i64,
    /// Number of anchors; 0 marks a free slab slot.
    pub(super) count: u64,
    /// `M_m = sum e_i^m`, `m = 0..=p`, double-double: high parts ...
    pub(super) m: [f64; PMAX],
    /// ... and low parts.
    pub(super) ml: [f64; PMAX],
}

/// No bin in a `Dense` entry.
pub(super) const NONE: u32 = u32::MAX;
/// Largest span of grid indices `Dense` covers (4 MB); beyond, lookups fall back to the
/// binary search of `index`.
pub(super) const DENSE_MAX: usize = 1 << 20;

/// Grid index `j` -> slot for `j` in `[j_lo, j_lo + slots.len())` (`NONE`: no bin there), a
/// cache of `index` for an O(1) lookup on `add`. Every live bin in that range is recorded,
/// so `NONE` in range means absent. Not part of the state: rebuilt on reading, ignored by `==`.
#[derive(Clone, Debug, Default)]
pub(super) struct Dense {
    pub(super) j_lo: i64,
    pub(super) slots: Vec<u32>,
}

impl PartialEq for Dense {
    fn eq(&self, _: &Dense) -> bool {
        true
    }
}

impl Dense {
    /// `Some(slot or NONE)` when `j` is in range.
    #[inline]
    pub(super) fn get(&self, j: i64) -> Option<u32> {
        self.slots.get(j.wrapping_sub(self.j_lo) as u64 as usize).copied()
    }

    /// Records `slot` (or `NONE`) at `j`; out of range, grows to cover `j` (rebuilding from
    /// `index`) unless the span would exceed `DENSE_MAX`.
    pub(super) fn set(&mut self, j: i64, slot: u32, index: &[(i64, u32)]) {
        let d = j.wrapping_sub(self.j_lo) as u64 as usize;
        if let Some(s) = self.slots.get_mut(d) {
            *s = slot;
            return;
        }
        if slot == NONE {
            return;
        }
        let (lo, hi) = match (index.first(), index.last()) {
            (Some(&(a, _)), Some(&(b, _))) => (a.min(j), b.max(j)),
            _ => (j, j),
        };
        let span = hi.saturating_sub(lo).saturating_add(1);
        let margin = (span / 2).clamp(16, 1024);
        let (lo, len) = (lo.saturating_sub(margin), span.saturating_add(2 * margin));
        if len as u64 > DENSE_MAX as u64 {
            // Too sparse: keep the old range (still exact for its own bins).
            return;
        }
        self.j_lo = lo;
        self.slots.clear();
        self.slots.resize(len as usize, NONE);
        for &(jj, ss) in index {
            self.slots[(jj - lo) as usize] = ss;
        }
        self.slots[(j - lo) as usize] = slot;
    }
}

/// `tb_k += sum_(m <= p-k) G[m][k] M_m`, `G[m][k] = (-1)^m C(m+k, k) phi_(m+k)`: one bin's
/// double expansion about the base (`phi = phi_taylor` at the bin's `x_b`). O(p^2).
#[inline]
pub(super) fn bin_terms(phi: &[f64], mom: &[f64], tb: &mut [f64]) {
    let p = phi.len() - 1;
    // Pascal's triangle by rows `m`: binom[k] = C(m+k, k).
    let mut binom = [1.0; PMAX];
    for (m, &mm) in mom.iter().enumerate().take(p + 1) {
        if m > 0 {
            // C(m+k, k) = C(m-1+k, k) + C(m+k-1, k-1).
            for k in 1..=p - m {
                binom[k] += binom[k - 1];
            }
        }
        let sm = if m % 2 == 0 { mm } else { -mm };
        for ((tk, b), ph) in tb[..=p - m].iter_mut().zip(&binom).zip(&phi[m..]) {
            *tk += b * ph * sm;
        }
    }
}
