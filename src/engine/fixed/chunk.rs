//! One step's pass over one chunk of junctions (docs/engines.md, "The fixed-step engine"):
//! the pending update (4), the flips and the chunk's part of `F_b`.
//!
//! The junctions are cut into chunks of [`CHUNK`] (the last one shorter), the same for any
//! thread count. A chunk's pass depends on nothing outside the chunk but the generator's
//! state at its first junction, which is the step's state skipped by `c CHUNK` draws
//! ([`UniformSource::skip`]): so the chunks may run in any order, on any thread, and give
//! the same numbers. `F_b` is summed in that order too: each chunk's terms one by one in
//! index order from `+0.0`, then the chunk sums one by one in chunk order from `+0.0`
//! (`total`). A scene with `N <= CHUNK` has one chunk, whose sum is the plain index-order
//! sum.

use super::flip::Flip;
use crate::observe::{EventKind, JunctionEvent};
use crate::physics::{Bond, ForceLaw};
use crate::rng::UniformSource;

/// Junctions per chunk: the unit of work of the threads, and of the summation of `F_b`.
pub const CHUNK: usize = 4096;

/// Junctions per block within a chunk: the block's draws and terms of `F_b` (4 KiB) stay in
/// the L1 cache.
pub(super) const BLOCK: usize = 256;

const _: () = assert!(CHUNK % BLOCK == 0);

/// What a step's pass needs besides the junctions and the generator: the same for every
/// chunk.
#[derive(Clone, Copy, Debug)]
pub(super) struct StepParams<L, B> {
    pub law: L,
    pub bond: B,
    pub dt: f64,
    /// `t_n`, the time of the step's events.
    pub t: f64,
    /// The pending update (4) of the previous step: attached `x_i += dx`, detached
    /// `x_i *= relax`.
    pub dx: f64,
    pub relax: f64,
    /// The strong-bond rupture and the formation thresholds on the generator's raw scale
    /// ([`Flip::raw_threshold`]).
    pub off_cut: f64,
    pub on_cut: f64,
    /// `!0` to keep a forming junction's extension (`reattach = "residual"`), `0` to zero it.
    pub keep_formed: u64,
}

/// Where a pass puts its junctions' events. The pass is compiled once for each of the two
/// kinds below, whatever observes the run: without events its update stays branch-free (and
/// vectorised); with them, a chunk's events are kept in order and handed on after the chunk.
pub(super) trait Events {
    /// Whether events are built at all.
    const ON: bool;
    /// Junction `junction` flipped at `t` (a rupture if `rupture`), its extension now `x`.
    fn flipped<L: ForceLaw>(&mut self, law: &L, t: f64, junction: usize, rupture: bool, x: f64);
    /// Hands on the events of the chunk just passed, in index order.
    fn chunk_done(&mut self);
}

/// No observer wants events.
pub(super) struct NoEvents;

impl Events for NoEvents {
    const ON: bool = false;
    #[inline(always)]
    fn flipped<L: ForceLaw>(&mut self, _: &L, _: f64, _: usize, _: bool, _: f64) {}
    #[inline(always)]
    fn chunk_done(&mut self) {}
}

/// A chunk's events, handed to `to` after the chunk.
pub(super) struct ChunkEvents<'a> {
    pub kept: Vec<JunctionEvent>,
    pub to: &'a mut dyn FnMut(&[JunctionEvent]),
}

impl Events for ChunkEvents<'_> {
    const ON: bool = true;
    /// Out of line: a junction flips in a few per cent of its steps, and the pass's loop
    /// stays tighter without the event's code in it.
    #[cold]
    #[inline(never)]
    fn flipped<L: ForceLaw>(&mut self, law: &L, t: f64, junction: usize, rupture: bool, x: f64) {
        self.kept.push(JunctionEvent {
            t,
            junction: junction as u32,
            kind: if rupture { EventKind::Rupture } else { EventKind::Formation },
            extension: x,
            tension: law.tension(x),
        });
    }
    fn chunk_done(&mut self) {
        (self.to)(&self.kept);
        self.kept.clear();
    }
}

/// What one chunk's pass found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct ChunkSums {
    /// The chunk's attached junctions' terms, summed in index order from `+0.0`: `x_i`
    /// for the linear law (`F_b = kappa * sum`), `f^x(x_i)` for the others.
    pub sum: f64,
    pub ruptures: u64,
    pub formations: u64,
}

/// The mask of a junction state byte: `!0` for `q = 1`, `0` for `q = 0`.
#[inline(always)]
pub(super) fn mask(q: u8) -> u64 {
    u64::from(q).wrapping_neg()
}

/// `if mask == !0 { a } else { b }` on the bits, for a mask from [`mask`]: branch-free.
#[inline(always)]
pub(super) fn select(mask: u64, a: f64, b: f64) -> f64 {
    f64::from_bits((a.to_bits() & mask) | (b.to_bits() & !mask))
}

/// The sum of per-chunk sums in chunk order, from `+0.0`.
#[inline]
pub(super) fn total(chunk_sums: impl IntoIterator<Item = f64>) -> f64 {
    chunk_sums.into_iter().fold(0.0, |s, c| s + c)
}

/// Copies the attached junctions' `x_i + dx` of a block to the front of `packed`, in index
/// order, and returns how many there are.
#[inline(always)]
pub(super) fn pack_attached(qs: &[u8], xs: &[f64], dx: f64, packed: &mut [f64; BLOCK]) -> usize {
    let mut k = 0;
    for (&q, &x) in qs.iter().zip(xs) {
        packed[k] = x + dx;
        k += usize::from(q);
    }
    k
}

/// The step's pass over one chunk (`qs`, `xs`; its first junction has index `first`), the
/// generator `rng` at the chunk's first draw: per junction, in index order, the pending
/// update (4), `xi_i ~ U(0,1)`, `k = q_i ? k_off(f(x_i)) : k_on`, the flip per `F`, the
/// re-attachment rule, and last the term of `F_b` with the new `q`.
///
/// The junctions go in blocks of [`BLOCK`]: the block's draws are made at once on the
/// generator's raw scale ([`UniformSource::raws`]: Park-Miller's states, several lanes at
/// once, the same numbers in the same order); each junction is updated with no dependence
/// on its neighbours (the compiler vectorises it); then the block's terms are added one by
/// one in index order. The linear law's terms are `q_i x_i`, written by the update (a
/// detached junction's `+0.0` leaves a sum that starts at `+0.0` unchanged bit for bit);
/// the other laws' are `f^x(x_i)` of the attached junctions alone, packed in index order
/// after the update ([`pack_attached`], a loop of its own, so that the update stays
/// vectorised) and evaluated together ([`ForceLaw::force_x_many`]).
#[inline(always)]
pub(super) fn pass_chunk<L: ForceLaw, B: Bond, R: UniformSource, F: Flip, E: Events>(
    s: &StepParams<L, B>,
    rng: &mut R,
    qs: &mut [u8],
    xs: &mut [f64],
    first: usize,
    events: &mut E,
) -> ChunkSums {
    let mut draws = [0.0; BLOCK];
    let mut terms = [0.0; BLOCK];
    let mut out = ChunkSums::default();
    for (block, (qs, xs)) in qs.chunks_mut(BLOCK).zip(xs.chunks_mut(BLOCK)).enumerate() {
        let draws = &mut draws[..qs.len()];
        rng.raws(draws);
        let (ruptures, formations) =
            update_block::<L, B, R, F, E>(s, draws, qs, xs, &mut terms, first + block * BLOCK, events);
        out.ruptures += ruptures;
        out.formations += formations;
        let terms = if L::IS_LINEAR {
            &terms[..qs.len()]
        } else {
            let k = pack_attached(qs, xs, 0.0, &mut terms);
            s.law.force_x_many(&mut terms[..k]);
            &terms[..k]
        };
        for &term in terms {
            out.sum += term;
        }
    }
    events.chunk_done();
    out
}

/// The pending update, the flip and the re-attachment of one block (and for the linear law
/// the terms `q_i x_i`); returns its ruptures and formations. `q_i` is random, so a branch on it would be mispredicted about half the
/// time: every choice that depends on it is a bitwise select under a mask computed from the
/// stored byte (`0` or `!0`), which the compiler cannot turn back into a branch.
#[inline(always)]
fn update_block<L: ForceLaw, B: Bond, R: UniformSource, F: Flip, E: Events>(
    s: &StepParams<L, B>,
    draws: &[f64],
    qs: &mut [u8],
    xs: &mut [f64],
    terms: &mut [f64; BLOCK],
    first: usize,
    events: &mut E,
) -> (u64, u64) {
    let (mut ruptures, mut formations) = (0u64, 0u64);
    // Weak bonds: the attached junctions' flips first, packed, so that the loop below has no
    // branch on the random `q_i` (which would be mispredicted about half the time).
    let mut weak_flips = [0u8; BLOCK + 1];
    if B::IS_WEAK {
        weak_attached_flips::<L, B, R, F>(s, draws, qs, xs, &mut weak_flips);
    }
    let mut next_weak = 0usize;
    for (j, ((qi, xi), &r)) in qs.iter_mut().zip(xs.iter_mut()).zip(draws).enumerate() {
        let q_old = *qi;
        let was = mask(q_old);
        // Step n-1's update (4): x_i(t_n).
        let x_n = select(was, *xi + s.dx, *xi * s.relax);
        // Rates from the state at t_n; strong-bond thresholds are hoisted.
        let flip = if B::IS_WEAK {
            let attached_flip = weak_flips[next_weak] != 0;
            next_weak += usize::from(q_old);
            (attached_flip & (q_old != 0)) | (F::flips(r, s.on_cut) & (q_old == 0))
        } else {
            F::flips(r, select(was, s.off_cut, s.on_cut))
        };
        let q_new = q_old ^ u8::from(flip);
        let formed = mask(q_new) & !was;
        // Re-attachment: `x_i = 0` for a formation when `reattach = "unstretched"`.
        let x_new = f64::from_bits(x_n.to_bits() & (s.keep_formed | !formed));
        *xi = x_new;
        *qi = q_new;
        ruptures += u64::from(q_old & !q_new);
        formations += u64::from(q_new & !q_old);
        if L::IS_LINEAR {
            terms[j] = select(mask(q_new), x_new, 0.0);
        }
        if E::ON && flip {
            events.flipped(&s.law, s.t, first + j, q_old != 0, x_new);
        }
    }
    (ruptures, formations)
}

/// Weak bonds: whether each attached junction of a block flips, in index order of the
/// attached, into `flips` (`1` or `0`): `xi_i < min(1, k_off(f(x_i(t_n))) dt)` (per the flip
/// rule). The attached junctions' `x_i(t_n)` and draws are packed first (no branch on
/// `q_i`), then their tensions computed together ([`ForceLaw::tension_many`]) and their rates
/// in a loop of their own.
#[inline(always)]
fn weak_attached_flips<L: ForceLaw, B: Bond, R: UniformSource, F: Flip>(
    s: &StepParams<L, B>,
    draws: &[f64],
    qs: &[u8],
    xs: &[f64],
    flips: &mut [u8; BLOCK + 1],
) {
    let mut x_at = [0.0; BLOCK];
    let mut r_at = [0.0; BLOCK];
    let mut k = 0;
    for ((&q, &x), &r) in qs.iter().zip(xs).zip(draws) {
        x_at[k] = x + s.dx;
        r_at[k] = r;
        k += usize::from(q);
    }
    let tensions = &mut x_at[..k];
    s.law.tension_many(tensions);
    for ((f, &tension), &r) in flips.iter_mut().zip(&*tensions).zip(&r_at[..k]) {
        *f = u8::from(F::flips(R::to_uniform(r), F::threshold(s.bond.k_off(tension) * s.dt)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masks_select_bit_exactly() {
        assert_eq!((mask(1), mask(0)), (!0, 0));
        assert_eq!(select(mask(1), -0.0, 1.0).to_bits(), (-0.0f64).to_bits());
        assert_eq!(select(mask(0), f64::NAN, 2.5), 2.5);
        assert!(select(mask(1), f64::NAN, 2.5).is_nan());
    }

    #[test]
    fn packing_keeps_the_attached_in_order() {
        let qs = [1u8, 0, 0, 1, 1, 0];
        let xs = [1.0, 2.0, 3.0, 4.0, -5.0, 6.0];
        let mut packed = [0.0; BLOCK];
        let k = pack_attached(&qs, &xs, 0.5, &mut packed);
        assert_eq!(&packed[..k], &[1.5, 4.5, -4.5]);
    }

    /// Leaving the detached junctions' `+0.0` out of an index-order sum changes no bit,
    /// whatever the attached terms (signed zeros included); [`total`] starts at `+0.0`.
    #[test]
    fn zero_terms_leave_the_sum_unchanged() {
        let mut g = crate::rng::ParkMiller::new(11).unwrap();
        let mut all = 0.0f64;
        let mut attached = 0.0f64;
        for i in 0..10_000 {
            let u = g.uniform();
            let term = match i % 7 {
                0 => -0.0,
                1 => 0.0,
                _ => (u - 0.5) * 1e3f64.powf(u),
            };
            let on = g.uniform() < 0.5;
            all += if on { term } else { 0.0 };
            if on {
                attached += term;
            }
        }
        assert_eq!(all.to_bits(), attached.to_bits());
        assert_eq!(total([-0.0]).to_bits(), 0.0f64.to_bits());
        assert_eq!(total([0.1, 0.2, 0.3]), (0.1 + 0.2) + 0.3);
    }

    /// The weak-bond block update (attached junctions' flips packed and computed apart)
    /// makes the decisions and extensions of the one-junction-at-a-time rule, bit for bit:
    /// blocks full and partial, all attached, none attached, both laws and all flip rules,
    /// rates from none to certain, with events reported for exactly the flips.
    #[test]
    fn weak_blocks_match_the_junction_by_junction_rule() {
        use super::super::flip::{AsPrintedFlip, ExponentialFlip, LinearFlip};
        use crate::physics::{Linear, Tilted, Weak};
        use crate::rng::ParkMiller;
        struct Seen(Vec<(usize, bool, u64)>);
        impl Events for Seen {
            const ON: bool = true;
            fn flipped<L: ForceLaw>(&mut self, _: &L, _: f64, j: usize, rupture: bool, x: f64) {
                self.0.push((j, rupture, x.to_bits()));
            }
            fn chunk_done(&mut self) {}
        }
        fn check<L: ForceLaw, F: Flip>(law: L, seed: u64) {
            let mut g = ParkMiller::new(seed).unwrap();
            for (len, p_attached, k0) in
                [(BLOCK, 0.5, 0.3), (BLOCK, 1.0, 2.0), (BLOCK, 0.0, 0.3), (77, 0.4, 40.0), (1, 1.0, 0.01)]
            {
                let bond = Weak { k0, beta_dx: 0.7 };
                let s = StepParams {
                    law,
                    bond,
                    dt: 0.1,
                    t: 3.0,
                    dx: 0.05,
                    relax: 0.9,
                    off_cut: 0.0,
                    on_cut: 1.0e9 * g.uniform(),
                    keep_formed: !0,
                };
                let qs: Vec<u8> = (0..len).map(|_| u8::from(g.uniform() < p_attached)).collect();
                let xs: Vec<f64> = (0..len).map(|_| 4.0 * g.uniform() - 1.0).collect();
                let mut draws = vec![0.0; len];
                g.raws(&mut draws);
                let (mut q, mut x, mut terms, mut seen) = (qs.clone(), xs.clone(), [0.0; BLOCK], Seen(Vec::new()));
                let counts =
                    update_block::<L, Weak, ParkMiller, F, Seen>(&s, &draws, &mut q, &mut x, &mut terms, 0, &mut seen);
                let (mut want_events, mut want_counts) = (Vec::new(), (0, 0));
                for j in 0..len {
                    let x_n = if qs[j] != 0 { xs[j] + s.dx } else { xs[j] * s.relax };
                    let flip = if qs[j] != 0 {
                        F::flips(ParkMiller::to_uniform(draws[j]), F::threshold(bond.k_off(law.tension(x_n)) * s.dt))
                    } else {
                        F::flips(draws[j], s.on_cut)
                    };
                    assert_eq!(q[j], qs[j] ^ u8::from(flip), "junction {j} of {len}");
                    assert_eq!(x[j].to_bits(), x_n.to_bits());
                    if flip {
                        want_events.push((j, qs[j] != 0, x_n.to_bits()));
                        if qs[j] != 0 { want_counts.0 += 1 } else { want_counts.1 += 1 }
                    }
                }
                assert_eq!(seen.0, want_events);
                assert_eq!(counts, want_counts);
            }
        }
        check::<Linear, LinearFlip>(Linear { kappa: 1.3 }, 3);
        check::<Linear, ExponentialFlip>(Linear { kappa: 1.3 }, 4);
        check::<Linear, AsPrintedFlip>(Linear { kappa: 1.3 }, 5);
        check::<Tilted, LinearFlip>(Tilted { kappa: 1.3, l0: 0.5 }, 6);
        check::<Tilted, AsPrintedFlip>(Tilted { kappa: 1.3, l0: 0.5 }, 7);
    }
}
