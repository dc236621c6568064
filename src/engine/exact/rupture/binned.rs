//! Weak-bond rupture for the `linear` force law by *binned* thinning: the attached junctions
//! are kept in bins of their anchor's exponent `a c`, a bin of width `h` in `a c`, so that
//! every member `i` of bin `j` has `exp(-a c_i) <= U0_j = exp(-j h)` and
//! `exp(a c_i) <= U1_j = exp((j + 1) h)` (each with a relative margin far above round-off).
//! Over a horizon with bounds `y_lo <= y <= y_hi` ([`Horizon`]) junction `i` of bin `j`
//! ruptures at `r_i = k0 exp(a |y - c_i|) <= b_j = k0 (exp(a y_hi) U0_j + exp(-a y_lo) U1_j)`,
//! so candidates arrive at `B = k0 (exp(a y_hi) sum_j n_j U0_j + exp(-a y_lo) sum_j n_j U1_j)`
//! (`n_j` the bin's count); a candidate picks a term, then a bin `j` with probability
//! `n_j Uk_j / sum`, then a *uniform* member of the bin, and is accepted with probability
//! `r_i / b_j` (the test of `accept`, from the member's own weights). The accepted
//! candidates are exactly the ruptures (Lewis & Shedler 1979), as with the sum tree of
//! [`super::TreeRupture`]; the bins' bound is at most `exp(h)` looser, so
//! a candidate is accepted a little less often.
//!
//! A bin whose anchors all lie below `y_lo` keeps term 0 alone, and one whose anchors all
//! lie above `y_hi` term 1 alone (`Sides`): its members are stretched one way over the
//! whole horizon, where `exp(a |y - c|)` is that term, so `b_j` drops the other one. Only
//! the bins between the bounds (one or two over a short horizon) keep both, where a member
//! near the plate is accepted about half the time.
//!
//! What this buys: the member is a uniform pick from a bag, like a strong bond's, so a
//! candidate's uniforms are drawn a few candidates ahead (`Ticket`) and the memory it will
//! read is requested while earlier candidates run: its member, then the member's record in
//! the attached bag. A candidate touches one random memory location (the member) instead of
//! a descent of `log4 N` lines, and the bins' sums are recomputed from their integer counts
//! after every event (no running additions that drift). The occupied bins are few (the
//! anchors of attached junctions span a few units of `a c`: a junction stretched far
//! ruptures at once) and are scanned in a small table.
//!
//! A member stores `exp(a c)` relative to its bin's bound, rounded to `f32`, and its slot
//! in the attached bag: 8 bytes. The weights it decodes to are known within a relative
//! `2^-22`, so the acceptance's squeeze uses them widened by that much, and a candidate the
//! squeeze leaves undecided recomputes `exp(a c)` from the junction's anchor, as its
//! insertion did: the decisions are those of the exact weights. The junction's record
//! stores its position in its bin ([`Attached::bin`]), so a rupture, which has read the
//! record, finds and removes the member in O(1); the bin is a function of `c`. The bins'
//! buffers grow by doubling and shrink by half when a quarter full; the buffers a bin
//! outgrows or gives up, and those of emptied bins, are kept for reuse (`SPARES`), so that
//! the bins filling ahead of the plate take the memory of those draining behind it: about
//! a member's bytes per junction in runs ([`BinnedRupture::bytes_for`]).

use std::ops::RangeInclusive;

use rand::Rng;
use serde::{Deserialize, Serialize};

use super::accept::{EXPONENT_CAP, anchor_overflows, overflows};
use super::contract::{Plan, RuptureModel};
use super::horizon::Horizon;
use super::rate::RuptureRate;
use crate::engine::alloc::{self, AllocError};
use crate::engine::exact::core::bags::{Attached, count};
use crate::engine::exact::core::pick::{index, prefetch_ptr};
use crate::rng::{Pcg64, UniformSource};

/// The number of junctions from which a run draws weak bonds' rupture candidates from bins
/// (below it, from the sum tree of [`super::TreeRupture`]). Below it the tree stays
/// in the processor's caches (2 MB at `1e5`), bounds each junction by its own weight, and
/// needs no pass over the occupied bins after every event, so it is the cheaper one where
/// the anchors spread over many bins: `scenarios/creep.toml` (`N = 300`, about 50 occupied
/// bins) runs 1.2x faster with it. On the bench's narrow spread the bins gain 1.03x at
/// `N = 1e3`, 1.15x at `1e4`, 1.3x at `1e5`, and 1.5x and 2x at `1e6` and `1e7`, where the
/// tree waits on memory (docs/performance.md).
pub const BINNED_FROM: usize = 100_000;

/// Whether a run of `n` junctions draws weak bonds' rupture candidates from bins
/// ([`BINNED_FROM`]): the engine's dispatch and the memory estimate ask this one question.
#[inline]
pub fn uses_bins(n: usize) -> bool {
    n >= BINNED_FROM
}
/// Bin width in the exponent `a c`: the bound is at most `2^(1/4)` (19%) above a member's own.
const H: f64 = std::f64::consts::LN_2 / 4.0;
/// Relative margin of the bins' bounds over their members' weights (the bin of `c` is
/// `floor(c a / h)`, whose round-off moves `a c` by far less).
const MARGIN: f64 = 1.0 + 1e-9;
/// Bins on either side of zero: `|a c| <= EXPONENT_CAP` for every binned junction.
const HALF: usize = (EXPONENT_CAP / H) as usize + 2;
/// The position of a junction in no bin (its rate overflows: it ruptures at once).
pub const UNBINNED: u32 = u32::MAX;

/// A binned junction in 8 bytes: its weight `e = exp(a c)` relative to its bin's bound
/// `U1_j`, `r = e / U1_j` rounded to `f32` (in `(e^-h / MARGIN, 1]`), and its slot in the
/// attached bag. The weights decoded from `r` ([`Member::bounds`]) serve the acceptance's
/// squeeze; the exact test recomputes `e` from the junction's anchor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[repr(C)]
struct Member {
    r: f32,
    slot: u32,
}

/// A bound on the relative error of a member's decoded weights: `r`'s rounding to `f32`
/// (`2^-24`) and the few roundings of `f64` operations, four times over.
const WEIGHT_ERROR: f64 = 1.0 / 4_194_304.0; // 2^-22

impl Member {
    /// The member of weight `e = exp(a c)` in a bin of bound `u1 = U1_j`, in `slot`.
    #[inline(always)]
    fn new(e: f64, u1: f64, slot: usize) -> Member {
        Member { r: (e / u1) as f32, slot: slot as u32 }
    }
    /// `[w_lo, w_hi]`, bounds of its weights `w = [exp(-a c), exp(a c)]` (each component)
    /// in a bin of bound `u1`: the decoded `w1 = r u1` and `w0 = 1 / w1`, each moved out by
    /// [`WEIGHT_ERROR`].
    #[inline(always)]
    fn bounds(self, u1: f64) -> [[f64; 2]; 2] {
        let w1 = f64::from(self.r) * u1;
        let w0 = 1.0 / w1;
        let (lo, hi) = (1.0 - WEIGHT_ERROR, 1.0 + WEIGHT_ERROR);
        [[w0 * lo, w1 * lo], [w0 * hi, w1 * hi]]
    }
}

/// The members of one bin and its bounds `[U0_j, U1_j]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "StoredBin")]
struct Bin {
    members: Vec<Member>,
    bound: [f64; 2],
}

/// A bin as a checkpoint holds it: its members as [`Member`], or as the earlier form that
/// stored each member's `e = exp(a c)` itself (read into `r` as [`Member::new`] computes it).
#[derive(Deserialize)]
struct StoredBin {
    members: Vec<StoredMember>,
    bound: [f64; 2],
}

#[derive(Deserialize)]
struct StoredMember {
    #[serde(default)]
    r: Option<f32>,
    #[serde(default)]
    e: Option<f64>,
    slot: u32,
}

impl TryFrom<StoredBin> for Bin {
    type Error = &'static str;
    fn try_from(b: StoredBin) -> Result<Bin, &'static str> {
        let members = b
            .members
            .into_iter()
            .map(|m| match (m.r, m.e) {
                (Some(r), None) => Ok(Member { r, slot: m.slot }),
                (None, Some(e)) => Ok(Member::new(e, b.bound[1], m.slot as usize)),
                _ => Err("a bin member needs exactly one of `r` and `e`"),
            })
            .collect::<Result<_, _>>()?;
        Ok(Bin { members, bound: b.bound })
    }
}

/// Candidates drawn ahead (a power of two, taken modulo with a mask).
const AHEAD: usize = 4;
/// The number of junctions from which a candidate requests its record at the three sizes
/// its bin may have by then, and a rupture's writes elsewhere ahead (`BinnedRupture::request`):
/// at `N = 1e6` the weak command of docs/performance.md "CLI runs" takes about 0.89x the
/// time with them, at `N = 3e5` as long, and at `N = 1e5`, where the lines stay in the
/// caches, 1.02x as long.
const WIDE_FROM: usize = 300_000;
/// How far a bin's count may drift before the back ticket is used.
const DRIFT: usize = 4;

/// A candidate's two uniforms, drawn [`AHEAD`] candidates before its use: `u` chooses the
/// term and the bin, `pick` the member (`floor(pick n / 2^64)` of the bin's `n` at the
/// time of use). Both are independent of everything before their use, so the bin their
/// candidate will choose, and its member, can be prefetched while earlier candidates run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
struct Ticket {
    u: f64,
    pick: u64,
    /// The bin the ticket chose when its member was prefetched (a hint for the second
    /// prefetch only: the candidate chooses afresh).
    #[serde(skip)]
    hint: u32,
}

impl Ticket {
    fn draw(rng: &mut Pcg64) -> Ticket {
        let u = rng.uniform();
        Ticket { u, pick: rng.next_u64(), hint: u32::MAX }
    }
}

/// Buffers kept for reuse, at most (those of emptied bins, and those a bin outgrew or gave
/// up: a bin that grows or shrinks takes one instead of new memory, which the system would
/// have to clear), and together at most a member per junction. Sixteen hold a buffer of
/// the sizes a bin passes through at `N = 1e6` (about fifteen powers of two).
const SPARES: usize = 16;

/// Weak bonds with the linear law: thinning against a bound per bin of anchors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BinnedRupture {
    pub k0: f64,
    /// `a = beta dx kappa`.
    pub a: f64,
    /// `a / h`: the bin of anchor `c` is `floor(c a / h)`.
    scale: f64,
    /// Bin `j` at index `j + HALF`.
    bins: Vec<Bin>,
    /// The occupied bins lie in `lo..hi` (indices).
    lo: usize,
    hi: usize,
    /// Running sums `sum_{lo <= i <= j} n_i Uk_i` over `lo..hi`, of the bins where term `k`
    /// is in force (`Sides`), recomputed from the counts by [`BinnedRupture::plan`] and
    /// [`RuptureModel::bound`] (never accumulated across events); their last entry is `[W0, W1]`.
    cumulative: Vec<[f64; 2]>,
    /// The bounds `[U0_i, U1_i]` over `lo..hi` with a term not in force (`Sides`) set to
    /// zero: a bin adds `n_i` times these to the running sums.
    #[serde(default)]
    weights: Vec<[f64; 2]>,
    /// The bins where each term is in force over the current bounds.
    #[serde(default)]
    sides: Sides,
    /// The occupied range `lo..hi` when `cumulative` was last summed (another range: sum
    /// it all again).
    #[serde(default)]
    summed: [usize; 2],
    /// The first bin (index) whose count changed since then: `cumulative` holds from there
    /// on (`usize::MAX`: none changed; 0, as a checkpoint restores it: all).
    #[serde(default)]
    dirty: usize,
    /// The next [`AHEAD`] candidates' tickets; `head` is the next one's.
    tickets: [Ticket; AHEAD],
    head: u8,
    /// The slot of the member the second ticket would pick ([`RuptureModel::upcoming`]; a
    /// prefetch hint, not state).
    #[serde(skip)]
    upcoming: u32,
    /// Emptied buffers for reuse (capacity only: no state), at most `n` members together.
    spare: Spares,
    /// The current horizon's bounds and their factors.
    h: Horizon,
}

impl BinnedRupture {
    /// The model for `n` junctions with rate `k0 exp(a |x|)`, none binned; draws the first
    /// tickets.
    pub fn try_new(k0: f64, a: f64, n: usize, rng: &mut Pcg64) -> Result<BinnedRupture, AllocError> {
        let mut bins: Vec<Bin> = alloc::with_capacity(2 * HALF + 1, "the rupture bins")?;
        bins.extend((0..2 * HALF + 1).map(|i| {
            let j = i as f64 - HALF as f64;
            Bin { members: Vec::new(), bound: [(-j * H).exp() * MARGIN, ((j + 1.0) * H).exp() * MARGIN] }
        }));
        let tickets = std::array::from_fn(|_| Ticket::draw(rng));
        Ok(BinnedRupture {
            k0,
            a,
            scale: a / H,
            bins,
            lo: HALF,
            hi: HALF,
            cumulative: Vec::new(),
            weights: Vec::new(),
            sides: Sides::default(),
            summed: [HALF, HALF],
            dirty: usize::MAX,
            tickets,
            head: 0,
            upcoming: 0,
            spare: Spares { buffers: Vec::new(), limit: n },
            h: Horizon::default(),
        })
    }
    /// Bytes for `n` junctions: the bin table, and a member and a quarter per junction (10
    /// bytes; the buffers grow by doubling and shrink by half when a quarter full, and the
    /// spares hold at most a member per junction; docs/runs.md gives what runs hold).
    pub fn bytes_for(n: usize) -> u64 {
        ((2 * HALF + 1) * (size_of::<Bin>() + size_of::<[f64; 2]>())) as u64 + (n * size_of::<Member>() * 5 / 4) as u64
    }
    /// Bytes of the model in a checkpoint (MessagePack, structs as maps) for `n` junctions at
    /// most: a member with its field names (18 bytes) per junction, and at most 96 bytes
    /// per bin of the table (its bounds, 35 bytes, and when occupied its running sums and
    /// weights, 19 bytes each).
    pub fn encoded_bytes_for(n: usize) -> u64 {
        18 * n as u64 + 96 * (2 * HALF + 1) as u64
    }
    /// The bin index of anchor `c` (`|a c| <= EXPONENT_CAP`).
    #[inline]
    fn bin_of(&self, c: f64) -> usize {
        floor_index(c * self.scale)
    }
    /// The terms in force for the plate within `[y_lo, y_hi]` ([`Sides::over`]), and the
    /// running sums over the occupied bins from their counts.
    fn sum_up(&mut self, y_lo: f64, y_hi: f64) {
        self.sides = Sides::over(self.scale, y_lo, y_hi);
        sum_up(&self.bins[self.lo..self.hi], self.lo, self.sides, &mut self.cumulative, &mut self.weights);
        (self.summed, self.dirty) = ([self.lo, self.hi], usize::MAX);
    }
    /// Bin `j`'s bound `b_j / k0`: the sum of its terms in force under the factors `e_hi`,
    /// `e_lo`.
    #[inline(always)]
    fn bin_bound(&self, j: usize, e_hi: f64, e_lo: f64) -> f64 {
        let [u0, u1] = self.bins[j].bound;
        let [t0, t1] = self.sides.terms(j);
        (if t0 { e_hi * u0 } else { 0.0 }) + (if t1 { e_lo * u1 } else { 0.0 })
    }
    /// `[W0, W1]`, the bins' bound sums.
    #[inline]
    fn totals(&self) -> [f64; 2] {
        self.cumulative.last().copied().unwrap_or([0.0; 2])
    }
    /// The bin (index) of term `k` where the running sum first exceeds `v` (`0 <= v <
    /// total`); an empty bin is never chosen (its sum equals its predecessor's), and a `v`
    /// at the total by round-off lands on the last occupied bin.
    #[inline]
    fn find(&self, k: usize, v: f64) -> usize {
        let c = &self.cumulative;
        // The first entry above v: counted without branches over a few bins (the common
        // case), by bisection over many.
        let i = if c.len() <= 32 {
            c.iter().map(|c| usize::from(c[k] <= v)).sum()
        } else {
            c.partition_point(|c| c[k] <= v)
        };
        if i < c.len() {
            return self.lo + i;
        }
        // Round-off: the last bin of positive weight.
        let mut i = c.len() - 1;
        while i > 0 && c[i - 1][k] == c[i][k] {
            i -= 1;
        }
        self.lo + i
    }
    /// The bin a candidate with uniform `u` would choose now, if any junction is binned.
    #[inline(always)]
    fn bin_for(&self, u: f64) -> Option<usize> {
        let (m, p) = self.h.terms(self.totals());
        // Also `None` for a NaN total.
        if (m + p).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let u = u * (m + p);
        Some(if u < m { self.find(0, u / self.h.e_hi) } else { self.find(1, (u - m) / self.h.e_lo) })
    }
    /// Adds the junction in `slot` with anchor `c` to its bin, and records its position.
    #[inline(always)]
    fn insert(&mut self, attached: &mut [Attached], slot: usize, c: f64) {
        let j = self.bin_of(c);
        self.dirty = self.dirty.min(j);
        let bin = &mut self.bins[j];
        attached[slot].bin = bin.members.len() as u32;
        let m = Member::new((self.a * c).exp(), bin.bound[1], slot);
        if bin.members.len() == bin.members.capacity() {
            grow(&mut bin.members, &mut self.spare);
        }
        bin.members.push(m);
        if self.lo == self.hi {
            (self.lo, self.hi) = (j, j + 1);
        } else {
            self.lo = self.lo.min(j);
            self.hi = self.hi.max(j + 1);
        }
    }
    /// The anchor's bin and the members' slots agree with the attached bag (tests).
    #[cfg(test)]
    fn check(&self, attached: &[Attached]) {
        let mut members = 0;
        for (i, bin) in self.bins.iter().enumerate() {
            assert!(
                bin.members.is_empty() || (self.lo <= i && i < self.hi),
                "bin {i} outside {}..{}",
                self.lo,
                self.hi
            );
            for (p, m) in bin.members.iter().enumerate() {
                let a = &attached[m.slot as usize];
                assert_eq!(a.bin as usize, p);
                assert_eq!(self.bin_of(a.c), i);
                assert_eq!(*m, Member::new((self.a * a.c).exp(), bin.bound[1], m.slot as usize));
                members += 1;
            }
        }
        let unbinned = attached.iter().filter(|a| a.bin == UNBINNED).count();
        assert_eq!(members + unbinned, attached.len());
    }
}

/// Buffers kept for reuse: at most [`SPARES`], of at most `limit` members together (a
/// checkpoint keeps the limit, not the buffers).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
struct Spares {
    #[serde(skip)]
    buffers: Vec<Vec<Member>>,
    limit: usize,
}

impl Spares {
    /// Keeps the buffer `v` (emptied) if it fits, in place of a smaller one if need be.
    fn keep(&mut self, mut v: Vec<Member>) {
        v.clear();
        let held: usize = self.buffers.iter().map(Vec::capacity).sum();
        if v.capacity() == 0 || v.capacity() > self.limit {
            return;
        }
        if self.buffers.len() < SPARES && held + v.capacity() <= self.limit {
            self.buffers.push(v);
        } else if let Some(i) = (0..self.buffers.len()).min_by_key(|&i| self.buffers[i].capacity()) {
            let small = self.buffers[i].capacity();
            if small < v.capacity() && held - small + v.capacity() <= self.limit {
                self.buffers[i] = v;
            }
        }
    }
    /// The smallest kept buffer for `sizes` members, if there is one.
    fn take(&mut self, sizes: RangeInclusive<usize>) -> Option<Vec<Member>> {
        take_best(&mut self.buffers, sizes)
    }
}

/// The smallest buffer of `pool` whose capacity lies in `sizes`, taken out of it.
fn take_best(pool: &mut Vec<Vec<Member>>, sizes: RangeInclusive<usize>) -> Option<Vec<Member>> {
    let i = (0..pool.len()).filter(|&i| sizes.contains(&pool[i].capacity())).min_by_key(|&i| pool[i].capacity())?;
    Some(pool.swap_remove(i))
}

/// An empty buffer for `capacity` members, advised onto huge pages before it is written (a
/// large bin is read at random, as a bag is).
fn new_buffer(capacity: usize) -> Vec<Member> {
    #[cfg(test)]
    tests::NEW_BUFFERS.with(|n| n.set(n.get() + 1));
    let v = Vec::with_capacity(capacity);
    crate::engine::exact::core::bags::advise_huge_pages(&v);
    v
}

/// Makes room in the full `members`: a spare buffer at least twice as large if there is one,
/// else a new one. The old buffer becomes a spare (a bin that shrinks takes it).
#[cold]
#[inline(never)]
fn grow(members: &mut Vec<Member>, spare: &mut Spares) {
    let need = (2 * members.capacity()).max(8);
    let grown = spare.take(need..=usize::MAX).unwrap_or_else(|| new_buffer(need));
    move_into(members, grown, spare);
}

/// Moves `members` into `buffer` (which holds them); their old buffer becomes a spare.
fn move_into(members: &mut Vec<Member>, mut buffer: Vec<Member>, spare: &mut Spares) {
    buffer.extend_from_slice(members);
    spare.keep(std::mem::replace(members, buffer));
}

/// Halves the buffer of `members` once they fill less than a quarter of it (amortised O(1)
/// per removal; a bin of more than 16 members keeps at most four times their memory): into
/// a spare of that size if there is one, and the old buffer becomes a spare (a bin that
/// grows takes it), so that the bins drifting through the table reuse each other's memory
/// instead of the system clearing new memory for them.
#[inline]
fn shrink(members: &mut Vec<Member>, spare: &mut Spares) {
    let cap = members.capacity();
    if cap >= 64 && 4 * members.len() < cap {
        match spare.take(2 * members.len()..=cap / 2) {
            Some(smaller) => move_into(members, smaller, spare),
            None => members.shrink_to(cap / 2),
        }
    }
}

impl RuptureModel for BinnedRupture {
    const IS_WEAK: bool = true;
    #[inline]
    fn attached(&mut self, attached: &mut [Attached], slot: usize, c: f64, y: f64) -> bool {
        if overflows(self.a, c, y) {
            attached[slot].bin = UNBINNED;
            return false;
        }
        self.insert(attached, slot, c);
        true
    }
    #[inline(always)]
    fn detached(&mut self, attached: &mut [Attached], slot: usize, last: usize, a: &Attached) {
        // The junction that moved from `last` into `slot`: its member now points at `slot`.
        if slot != last {
            let moved = attached[slot];
            if moved.bin != UNBINNED {
                let j = self.bin_of(moved.c);
                self.bins[j].members[moved.bin as usize].slot = slot as u32;
            }
        }
        if a.bin == UNBINNED {
            return;
        }
        let j = self.bin_of(a.c);
        self.dirty = self.dirty.min(j);
        let bin = &mut self.bins[j];
        let p = a.bin as usize;
        bin.members.swap_remove(p);
        if let Some(m) = bin.members.get(p) {
            attached[m.slot as usize].bin = p as u32;
        }
        if !bin.members.is_empty() {
            shrink(&mut bin.members, &mut self.spare);
        } else {
            // An emptied bin's buffer becomes a spare (the anchors drift through the bins).
            self.spare.keep(std::mem::take(&mut bin.members));
            while self.lo < self.hi && self.bins[self.lo].members.is_empty() {
                self.lo += 1;
            }
            while self.hi > self.lo && self.bins[self.hi - 1].members.is_empty() {
                self.hi -= 1;
            }
        }
    }
    /// The bins' sums are recomputed over the horizon's bounds once they are chosen.
    fn plan(&mut self, bounds: impl FnMut(f64) -> (f64, f64), n_att: usize) -> Plan {
        let BinnedRupture { h, bins, lo, hi, cumulative, weights, sides, summed, dirty, scale, k0, a, .. } = self;
        h.plan_with(bounds, n_att, *k0, *a, |y_lo, y_hi| {
            *sides = Sides::over(*scale, y_lo, y_hi);
            sum_up(&bins[*lo..*hi], *lo, *sides, cumulative, weights);
            (*summed, *dirty) = ([*lo, *hi], usize::MAX);
            (cumulative.last().copied().unwrap_or([0.0; 2]), sides.limits(*scale))
        })
    }
    /// The plan is kept while the plate's path stays within its factors' and its sides'
    /// limits; the sums are brought up to date from the bins whose counts changed.
    #[inline]
    fn replan(&mut self, reach: impl FnOnce(f64, f64) -> f64, n_att: usize) -> Option<f64> {
        let BinnedRupture { h, bins, lo, hi, cumulative, weights, sides, summed, dirty, k0, .. } = self;
        h.replan(reach, n_att, *k0, || {
            resum(&bins[*lo..*hi], [*lo, *hi], *sides, [cumulative, weights], summed, dirty);
            cumulative.last().copied().unwrap_or([0.0; 2])
        })
    }
    /// The bins' sums are recomputed here (the attached junctions may have changed since the
    /// last step).
    #[inline]
    fn bound(&mut self, y_lo: f64, y_hi: f64) -> f64 {
        self.sum_up(y_lo, y_hi);
        self.h.set_grid_bounds(self.a, y_lo, y_hi);
        let (m, p) = self.h.terms(self.totals());
        self.k0 * (m + p)
    }
    #[inline]
    fn pick<L: RuptureRate>(
        &mut self,
        rng: &mut Pcg64,
        attached: &[Attached],
        law: &L,
        y: impl FnOnce() -> f64,
    ) -> Option<usize> {
        if self.h.immediate {
            return Some(attached.len() - 1);
        }
        let h = self.head as usize & (AHEAD - 1);
        let t = self.tickets[h];
        self.tickets[h] = Ticket::draw(rng);
        self.head = ((h + 1) & (AHEAD - 1)) as u8;
        let j = self.bin_for(t.u).expect("a rupture candidate with no binned junction");
        let bin = &self.bins[j];
        let m = bin.members[index(t.pick, bin.members.len())];
        let (e_hi, e_lo) = (self.h.e_hi, self.h.e_lo);
        let b = self.bin_bound(j, e_hi, e_lo);
        let bounds = m.bounds(bin.bound[1]);
        self.request(attached);
        let ub = rng.uniform() * b;
        let (slot, a) = (m.slot as usize, self.a);
        // The exact weights as the junction's insertion computed them (`exp(a c)`, its
        // reciprocal), from its anchor: only for a candidate the bounds do not decide.
        let exact = || {
            let e = (a * attached[slot].c).exp();
            [1.0 / e, e]
        };
        law.accept_within(ub, bounds, e_hi, e_lo, a, y, || attached[slot].c, exact).then_some(slot)
    }
    /// Re-bins every junction. The old bins' buffers are reused for the new ones (the
    /// smallest that holds a new bin's count), so a re-base holds no second copy of the
    /// bins; what is left becomes spares. Only the bins occupied before and after are
    /// visited (a re-base every `N / 4` events must not visit the whole table).
    fn rebuild(&mut self, attached: &mut [Attached]) -> Vec<usize> {
        let mut pool: Vec<Vec<Member>> = std::mem::take(&mut self.spare.buffers);
        for i in self.lo..self.hi {
            let mut v = std::mem::take(&mut self.bins[i].members);
            v.clear();
            if v.capacity() > 0 {
                pool.push(v);
            }
        }
        (self.lo, self.hi) = (HALF, HALF);
        self.h.forget();
        // The new bins' counts over the range they span (not the whole table), then a buffer
        // for each that holds its count.
        let a = self.a;
        let bins: Vec<usize> =
            attached.iter().filter(|j| !anchor_overflows(a, j.c)).map(|j| self.bin_of(j.c)).collect();
        let first = bins.iter().copied().min().unwrap_or(HALF);
        let mut counts = vec![0usize; bins.iter().copied().max().map_or(0, |last| last + 1 - first)];
        for j in bins {
            counts[j - first] += 1;
        }
        for (i, &n) in counts.iter().enumerate().filter(|(_, n)| **n > 0) {
            self.bins[first + i].members =
                take_best(&mut pool, n..=usize::MAX).unwrap_or_else(|| new_buffer(n.next_power_of_two().max(8)));
        }
        let mut over = Vec::new();
        for slot in 0..attached.len() {
            let c = attached[slot].c;
            if !anchor_overflows(a, c) {
                self.insert(attached, slot, c);
            } else {
                attached[slot].bin = UNBINNED;
                over.push(slot);
            }
        }
        for v in pool {
            self.spare.keep(v);
        }
        over
    }
    #[inline]
    fn needs_rebase(&self, y: f64, tau: f64) -> bool {
        self.h.needs_rebase(self.a, y, tau)
    }
    /// Nothing: [`BinnedRupture::pick`] requests its memory at every candidate (a rejected
    /// candidate is no event).
    #[inline(always)]
    fn prefetch(&self, _attached: &[Attached]) {}
    #[inline(always)]
    fn upcoming(&self) -> usize {
        self.upcoming as usize
    }
}

/// Where each term of the bins' bound is in force: for the plate within `[y_lo, y_hi]`,
/// every member of a bin below `from` has its anchor below `y_lo` (`x = y - c > 0`, rate
/// `e^{a x} <= e^{a y_hi} U0`: term 0 alone), and every member of a bin at or above `upto`
/// has its anchor above `y_hi` (`x < 0`: term 1 alone); the bins between (one or two when
/// the bounds are close) keep both. Bins are compared by the same rounded `floor(c a / h)`
/// as their members' anchors, which is monotone in `c`, so the sides are exact.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct Sides {
    /// Term 0 (`e^{a y_hi} U0`) in force in bins `..upto`, term 1 (`e^{-a y_lo} U1`) in
    /// bins `from..` (table indices).
    upto: usize,
    from: usize,
}

impl Default for Sides {
    /// Both terms in every bin.
    fn default() -> Sides {
        Sides { upto: usize::MAX, from: 0 }
    }
}

impl Sides {
    /// The sides for the plate within `[y_lo, y_hi]` under the bins' `scale = a / h`; both
    /// terms everywhere for bounds that are not numbers.
    #[inline]
    fn over(scale: f64, y_lo: f64, y_hi: f64) -> Sides {
        let (lo, hi) = (y_lo * scale, y_hi * scale);
        if lo.is_nan() || hi.is_nan() {
            return Sides::default();
        }
        Sides { upto: table_index(hi) + 1, from: table_index(lo) }
    }
    /// The plate positions `[lo, hi]` for which these sides hold: every bin at or above
    /// `upto` keeps its anchors above the plate while `y scale < upto - HALF` (the rounded
    /// products `floor_index` compares are monotone in `y`), and every bin below `from` its
    /// anchors below while `y scale >= from - HALF`; unbounded where a side reaches the
    /// table's end. The caller moves them inwards for round-off.
    #[inline]
    fn limits(&self, scale: f64) -> [f64; 2] {
        let lo = if self.from == 0 { f64::NEG_INFINITY } else { (self.from as f64 - HALF as f64) / scale };
        let hi = if self.upto > 2 * HALF { f64::INFINITY } else { (self.upto as f64 - HALF as f64) / scale };
        [lo, hi]
    }
    /// Whether terms 0 and 1 are in force in bin `j`.
    #[inline(always)]
    fn terms(&self, j: usize) -> [bool; 2] {
        [j < self.upto, j >= self.from]
    }
    /// Bin `j`'s bounds `u` with those of a term not in force set to zero.
    #[inline]
    fn weights(&self, j: usize, u: [f64; 2]) -> [f64; 2] {
        let [t0, t1] = self.terms(j);
        [if t0 { u[0] } else { 0.0 }, if t1 { u[1] } else { 0.0 }]
    }
}

/// The table index `floor(t) + HALF` of a scaled position `t` (not NaN), clamped to the
/// table (`0 ..= 2 HALF`): the plate bounds' ([`Sides::over`]), by the rounding that places a
/// member ([`floor_index`]), so the two compare exactly.
#[inline]
fn table_index(t: f64) -> usize {
    floor_index(t.clamp(-(HALF as f64), HALF as f64))
}

/// `floor(t) + HALF` for `|t| <= HALF`: a member's bin ([`BinnedRupture::bin_of`]).
#[inline(always)]
fn floor_index(t: f64) -> usize {
    // One rounding instruction where the processor has it (x86-64-v3 builds); else by
    // truncation (the same value: floor(NaN) as i64 is 0 in both).
    #[cfg(any(target_feature = "sse4.1", not(target_arch = "x86_64")))]
    let j = t.floor() as i64;
    #[cfg(not(any(target_feature = "sse4.1", not(target_arch = "x86_64"))))]
    let j = floor_by_truncation(t);
    (j + HALF as i64) as usize
}

/// `floor(t)` as an integer by truncation and correction, for `t` of either sign: no
/// rounding instruction (`f64::floor` is a library call without SSE4.1).
#[cfg_attr(any(target_feature = "sse4.1", not(target_arch = "x86_64")), allow(dead_code))]
#[inline(always)]
fn floor_by_truncation(t: f64) -> i64 {
    let mut j = t as i64;
    if (j as f64) > t {
        j -= 1;
    }
    j
}

/// Running sums over `bins` (table indices from `first`) of each term where it is in force,
/// and the bins' `weights` under these sides. Out of line: it runs once per plan, and
/// inlined into the event loop it cost the loop instructions on every event.
fn sum_up(bins: &[Bin], first: usize, sides: Sides, cumulative: &mut Vec<[f64; 2]>, weights: &mut Vec<[f64; 2]>) {
    weights.clear();
    for (i, bin) in bins.iter().enumerate() {
        weights.push(sides.weights(first + i, bin.bound));
    }
    cumulative.clear();
    cumulative.resize(bins.len(), [0.0; 2]);
    resum_from(bins, weights, 0, cumulative);
}

/// The running sums over `bins` (the occupied range `[lo, hi]`) brought up to date under
/// the current sides: from the first bin whose count changed, `dirty`, on (the same
/// additions, in the same order, as summing all of them: [`resum_from`]), or all of them
/// when the range is not the one `summed` records; both then record the sums as current.
#[inline(always)]
fn resum(
    bins: &[Bin],
    [lo, hi]: [usize; 2],
    sides: Sides,
    [cumulative, weights]: [&mut Vec<[f64; 2]>; 2],
    summed: &mut [usize; 2],
    dirty: &mut usize,
) {
    if *summed != [lo, hi] || cumulative.len() != hi - lo || weights.len() != hi - lo {
        sum_up(bins, lo, sides, cumulative, weights);
    } else if *dirty < hi {
        resum_from(bins, weights, (*dirty).max(lo) - lo, cumulative);
    }
    (*summed, *dirty) = ([lo, hi], usize::MAX);
}

/// [`sum_up`]'s running sums recomputed from position `from` on (those before it hold):
/// each bin adds its count `n` times its `weights` (`n U_k`, or zero where term `k` is not
/// in force: adding `+0` leaves a sum's bits as they are).
#[inline(always)]
fn resum_from(bins: &[Bin], weights: &[[f64; 2]], from: usize, cumulative: &mut [[f64; 2]]) {
    let len = bins.len().min(weights.len()).min(cumulative.len());
    let mut acc = if from > 0 { cumulative[from - 1] } else { [0.0; 2] };
    for i in from..len {
        let (n, w) = (count(bins[i].members.len()), weights[i]);
        acc = [acc[0] + n * w[0], acc[1] + n * w[1]];
        cumulative[i] = acc;
    }
}

impl BinnedRupture {
    /// Requests the memory of later candidates, in two stages a few candidates apart: the
    /// member the back ticket (used [`AHEAD`] candidates from now) would pick, in the bin it
    /// would choose now, at the bin's sizes `n - DRIFT ..= n + DRIFT` (both ends and the
    /// middle of the range: a line or two); and the attached records of the members the
    /// second ticket would pick in the bin it chose then, at the bin's sizes `n - 1 ..= n + 1`
    /// (an event in between moves the pick to a neighbour; the members, requested two
    /// candidates ago, are read now), the one at `n` kept as [`RuptureModel::upcoming`].
    /// Beside them, the lines a rupture writes elsewhere ([`RuptureModel::detached`]): the
    /// record of that bin's last member, which fills the removed member's place, and the
    /// member of the attached bag's last junction, which fills the removed record's. Below
    /// [`WIDE_FROM`] junctions, where these lines stay in the caches, the records are
    /// requested at `n` alone and the writes' lines not at all. The addresses need not be
    /// valid (a prefetch never faults).
    #[inline(always)]
    fn request(&mut self, attached: &[Attached]) {
        let b = (self.head as usize + AHEAD - 1) & (AHEAD - 1);
        let back = self.tickets[b];
        if let Some(j) = self.bin_for(back.u) {
            self.tickets[b].hint = j as u32;
            let bin = &self.bins[j];
            let n = bin.members.len();
            let base = bin.members.as_ptr();
            let (lo, hi) = (index(back.pick, n.saturating_sub(DRIFT)), index(back.pick, n + DRIFT));
            prefetch_ptr(base.wrapping_add(lo));
            prefetch_ptr(base.wrapping_add((lo + hi) / 2));
            prefetch_ptr(base.wrapping_add(hi));
        }
        let second = self.tickets[(self.head as usize + 1) & (AHEAD - 1)];
        let record = |m: &Member| prefetch_ptr(attached.as_ptr().wrapping_add(m.slot as usize));
        // The spares' limit is the run's number of junctions.
        let wide = self.spare.limit >= WIDE_FROM;
        if let Some(bin) = self.bins.get(second.hint as usize) {
            let n = bin.members.len();
            let (lo, hi) = if wide { (n.saturating_sub(1), n + 1) } else { (n, n) };
            for i in index(second.pick, lo)..=index(second.pick, hi) {
                if let Some(m) = bin.members.get(i) {
                    record(m);
                }
            }
            if let Some(m) = bin.members.get(index(second.pick, n)) {
                self.upcoming = m.slot;
            }
            if let Some(m) = bin.members.last().filter(|_| wide) {
                record(m);
            }
        }
        if let Some(last) = attached.last().filter(|a| wide && a.bin != UNBINNED) {
            if let Some(bin) = self.bins.get(self.bin_of(last.c)) {
                prefetch_ptr(bin.members.as_ptr().wrapping_add(last.bin as usize));
            }
        }
    }
}

#[cfg(test)]
#[path = "binned_tests.rs"]
mod tests;
