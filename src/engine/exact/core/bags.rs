//! Junction storage of the exact engine: two unordered bags. Junctions of one state are
//! exchangeable for every rate that is shared (strong rupture, formation), so picking a
//! uniformly random member and removing it by `swap_remove` is O(1) and touches one
//! random memory location per event.
//!
//! An attached junction stores its anchor `c` (local coordinates): its extension is
//! `x = y - c` and it moves with the plate for free. A detached junction stores its
//! extension `x_d` at detachment and the local detachment time `t_d`: it relaxes as
//! `x(tau) = x_d exp(-lambda (tau - t_d))`.

use serde::{Deserialize, Serialize};

use crate::engine::alloc::{self, AllocError};
use crate::rng::{Pcg64, UniformSource};
use crate::scene::{Initial, JunctionParams};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Attached {
    /// Anchor: the junction's extension is `y - c`.
    pub c: f64,
    pub id: u32,
    /// The engine's handle of the junction: in the series engine, in its `SeriesSum` (the
    /// bin it was counted in, or in direct mode its slot in the offsets' table:
    /// [`crate::engine::exact::stepper::series::SeriesSum::add`]); with weak bonds in the linear
    /// engine, its position in its rupture bin ([`crate::engine::exact::rupture::binned`]); 0
    /// otherwise. It fills what would be padding (the struct stays 16 bytes), so a rupture
    /// reads it with the anchor in one random memory access.
    #[serde(default)]
    pub bin: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Detached {
    /// Extension at detachment.
    pub x: f64,
    /// Local time of detachment.
    pub t: f64,
    pub id: u32,
}

/// A count (a bag's length) as `f64`, the same number as `n as f64`: a length is below
/// `isize::MAX`, so it converts as a signed integer (one instruction on x86-64, where an
/// unsigned 64-bit conversion takes several).
#[inline(always)]
pub fn count(n: usize) -> f64 {
    debug_assert!(n <= isize::MAX as usize);
    n as i64 as f64
}

/// Neumaier-compensated running sum (the sum of anchors changes by +-c at every event).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CompensatedSum {
    sum: f64,
    comp: f64,
}

impl CompensatedSum {
    #[inline]
    pub fn add(&mut self, v: f64) {
        let t = self.sum + v;
        if self.sum.abs() >= v.abs() {
            self.comp += (self.sum - t) + v;
        } else {
            self.comp += (v - t) + self.sum;
        }
        self.sum = t;
    }
    #[inline]
    pub fn value(&self) -> f64 {
        self.sum + self.comp
    }
    pub fn of(values: impl Iterator<Item = f64>) -> Self {
        let mut s = CompensatedSum::default();
        values.for_each(|v| s.add(v));
        s
    }
}

/// Attached and detached junctions, and the anchor sum `C = sum_attached c`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Bags {
    pub attached: Vec<Attached>,
    pub detached: Vec<Detached>,
    pub anchor_sum: CompensatedSum,
}

impl Bags {
    pub fn with_capacity(n: usize) -> Bags {
        Self::try_with_capacity(n).unwrap_or_else(|e| panic!("{e}"))
    }
    /// Bags with room for `n` junctions each, reserved fallibly.
    pub fn try_with_capacity(n: usize) -> Result<Bags, AllocError> {
        let b = Bags {
            attached: alloc::with_capacity(n, "the attached junctions")?,
            detached: alloc::with_capacity(n, "the detached junctions")?,
            anchor_sum: CompensatedSum::default(),
        };
        advise_huge_pages(&b.attached);
        advise_huge_pages(&b.detached);
        Ok(b)
    }
    /// The initial state of `j.n` junctions, all at zero extension: detached, attached, or
    /// each attached with probability `kon0/(kon0+k0)` (one uniform per junction, in index
    /// order).
    /// An allocation that fails is the error.
    pub fn initial(j: &JunctionParams, rng: &mut Pcg64) -> Result<Bags, AllocError> {
        let mut bags = Bags::try_with_capacity(j.n)?;
        let p_att = j.kon0 / (j.kon0 + j.k0);
        for id in 0..j.n as u32 {
            let attached = match j.initial {
                Initial::Detached => false,
                Initial::Attached => true,
                Initial::Stationary => rng.uniform() < p_att,
            };
            if attached {
                bags.attach(0.0, id);
            } else {
                bags.detached.push(Detached { x: 0.0, t: 0.0, id });
            }
        }
        Ok(bags)
    }
    #[inline]
    pub fn n_attached(&self) -> usize {
        self.attached.len()
    }
    #[inline]
    pub fn n_detached(&self) -> usize {
        self.detached.len()
    }
    /// `C = sum c`.
    #[inline]
    pub fn anchor_sum(&self) -> f64 {
        self.anchor_sum.value()
    }
    /// Attaches a junction with anchor `c`.
    #[inline]
    pub fn attach(&mut self, c: f64, id: u32) {
        self.attach_in_bin(c, id, 0);
    }
    /// Attaches a junction with anchor `c` and the series engine's handle `bin`.
    #[inline]
    pub fn attach_in_bin(&mut self, c: f64, id: u32, bin: u32) {
        self.attached.push(Attached { c, id, bin });
        self.anchor_sum.add(c);
    }
    /// Removes the attached junction in `slot` (the last one moves into it).
    #[inline]
    pub fn take_attached(&mut self, slot: usize) -> Attached {
        let a = self.attached.swap_remove(slot);
        self.anchor_sum.add(-a.c);
        a
    }
    /// Removes the detached junction in `slot` (the last one moves into it).
    #[inline]
    pub fn take_detached(&mut self, slot: usize) -> Detached {
        self.detached.swap_remove(slot)
    }
    /// Shifts the local origin: anchors by `-dy`, detachment times by `-dtau`; the anchor
    /// sum is recomputed from scratch.
    pub fn rebase(&mut self, dtau: f64, dy: f64) {
        self.attached.iter_mut().for_each(|a| a.c -= dy);
        self.detached.iter_mut().for_each(|d| d.t -= dtau);
        self.anchor_sum = CompensatedSum::of(self.attached.iter().map(|a| a.c));
    }
}

/// Asks the kernel to back a large buffer with transparent huge pages: uniform picks touch
/// random pages of the bags, and with 4 KiB pages most of them also miss the TLB.
/// Linux only; a no-op elsewhere and for small buffers; failure is harmless.
pub fn advise_huge_pages<T>(v: &Vec<T>) {
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let bytes = v.capacity() * std::mem::size_of::<T>();
        if bytes < 2 * HUGE {
            return;
        }
        let start = (v.as_ptr() as usize).div_ceil(HUGE) * HUGE;
        let end = (v.as_ptr() as usize + bytes) / HUGE * HUGE;
        if end > start {
            // SAFETY: madvise only changes how the kernel backs this range of our own
            // allocation; it never invalidates memory under MADV_HUGEPAGE.
            unsafe {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = v;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compensated_sum_survives_cancellation() {
        let mut s = CompensatedSum::default();
        s.add(1e16);
        for _ in 0..1000 {
            s.add(1.0);
        }
        s.add(-1e16);
        assert_eq!(s.value(), 1000.0);
    }

    #[test]
    fn bags_keep_the_anchor_sum() {
        let mut b = Bags::with_capacity(4);
        b.attach(1.5, 0);
        b.attach(2.5, 1);
        b.attach(-1.0, 2);
        let a = b.take_attached(0);
        assert_eq!(a.id, 0);
        assert_eq!(b.attached[0].id, 2);
        assert_eq!(b.anchor_sum(), 1.5);
        b.rebase(1.0, 0.5);
        assert_eq!(b.anchor_sum(), 0.5);
    }

    /// The series engine's handle lives in the padding of `Attached`: a rupture reads one
    /// 16-byte record (`ExactSeries` has no parallel array of handles).
    #[test]
    fn the_bin_handle_costs_no_memory() {
        assert_eq!(std::mem::size_of::<Attached>(), 16);
    }
}
