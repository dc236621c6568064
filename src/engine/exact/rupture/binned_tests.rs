//! Tests of the rupture bins ([`super`]): their bounds, bookkeeping, buffers, stored form
//! and decisions.

use super::*;
use crate::engine::exact::rupture::rate::LinearRate;
use crate::engine::exact::stepper::linear::Drive;
use crate::rng::pcg;

fn record(c: f64, id: u32) -> Attached {
    Attached { c, id, bin: 0 }
}

/// Attaches junction `id` with anchor `c` (the plate at `y`) at the end of the bag, as the
/// core does; whether it was binned.
fn attach(r: &mut BinnedRupture, attached: &mut Vec<Attached>, c: f64, id: u32, y: f64) -> bool {
    attached.push(record(c, id));
    let slot = attached.len() - 1;
    r.attached(attached, slot, c, y)
}

/// Detaches a uniform junction by `swap_remove`, as the core does.
fn detach_any(r: &mut BinnedRupture, attached: &mut Vec<Attached>, rng: &mut Pcg64) {
    let slot = index(rng.next_u64(), attached.len());
    let last = attached.len() - 1;
    let gone = attached.swap_remove(slot);
    r.detached(attached, slot, last, &gone);
}

/// The running sums over the occupied bins, summed afresh in order, each bin adding
/// `n U_k` for the terms in force and nothing for the others.
fn oracle_sums(r: &BinnedRupture) -> Vec<[f64; 2]> {
    let mut acc = [0.0f64; 2];
    (r.lo..r.hi)
        .map(|j| {
            let (n, u, [t0, t1]) = (r.bins[j].members.len() as f64, r.bins[j].bound, r.sides.terms(j));
            acc = [acc[0] + if t0 { n * u[0] } else { 0.0 }, acc[1] + if t1 { n * u[1] } else { 0.0 }];
            acc
        })
        .collect()
}

/// Every member's weights lie under its bin's bounds, and within `exp(h)` of them, and
/// within its decoded bounds ([`Member::bounds`]), which lie within a few
/// [`WEIGHT_ERROR`] of them, for anchors across the whole range and on either side of
/// every bin's edges.
#[test]
fn bins_bound_their_members_tightly() {
    let mut rng = pcg(1);
    for a in [1e-3, 0.1, 1.0, 37.0] {
        let r = BinnedRupture::try_new(1.0, a, 64, &mut rng).unwrap();
        let mut anchors: Vec<f64> = (0..20_000).map(|_| (rng.uniform() - 0.5) * 2.0 * EXPONENT_CAP / a).collect();
        for j in -50i32..50 {
            let edge = f64::from(j) * H / a;
            anchors.extend([edge, edge.next_up(), edge.next_down()]);
        }
        for c in anchors {
            let u = r.bins[r.bin_of(c)].bound;
            let e = (a * c).exp();
            let w = [1.0 / e, e];
            assert!(w[0] <= u[0] && w[1] <= u[1], "a {a} c {c}: {w:?} above {u:?}");
            let loose = H.exp() * MARGIN * (1.0 + 1e-12);
            assert!(u[0] <= w[0] * loose && u[1] <= w[1] * loose, "a {a} c {c}: {u:?} loose over {w:?}");
            let [lo, hi] = Member::new(e, u[1], 7).bounds(u[1]);
            for k in 0..2 {
                assert!(lo[k] <= w[k] && w[k] <= hi[k], "a {a} c {c}: {w:?} outside [{lo:?}, {hi:?}]");
                assert!(hi[k] <= w[k] * (1.0 + 3.0 * WEIGHT_ERROR) && lo[k] >= w[k] * (1.0 - 3.0 * WEIGHT_ERROR));
            }
        }
    }
}

/// A candidate decided from its member's bounds gets the decision of its exact weights,
/// with either law, for uniforms spread over the rate's bracket and crowded at its ends
/// and at the rate itself (horizons of one position included, where the bracket is the
/// rate).
#[test]
fn bounds_decide_as_the_exact_weights() {
    use crate::engine::exact::rupture::accept::bracket;
    use crate::engine::exact::rupture::rate::TiltedRate;
    use crate::physics::{ForceLaw, Tilted};
    let mut rng = pcg(6);
    let a = 0.7;
    let r = BinnedRupture::try_new(1.0, a, 64, &mut rng).unwrap();
    let tilted = TiltedRate::new(Tilted { kappa: a, l0: 0.5 }, 1.0);
    for i in 0..40_000 {
        let c = (rng.uniform() - 0.5) * 40.0;
        let u1 = r.bins[r.bin_of(c)].bound[1];
        let e = (a * c).exp();
        let (w, bounds) = ([1.0 / e, e], Member::new(e, u1, 0).bounds(u1));
        let y_lo = c + (rng.uniform() - 0.5) * 8.0;
        let y_hi = if i % 4 == 0 { y_lo } else { y_lo + rng.uniform() / a };
        let y = y_lo + (y_hi - y_lo) * rng.uniform();
        let (e_hi, e_lo) = ((a * y_hi).exp(), (-a * y_lo).exp());
        let (lo, hi) = bracket(w, w, e_hi, e_lo);
        let rates = [(a * (y - c).abs()).exp(), tilted.law.tension(y - c).exp()];
        let mut ubs = vec![rng.uniform() * hi * 1.2];
        for x in [lo, hi, rates[0], rates[1]] {
            ubs.extend([-1e-7, -1e-8, -1e-15, 0.0, 1e-15, 1e-8, 1e-7].map(|d| x * (1.0 + d)));
        }
        for ub in ubs {
            let exact = LinearRate.accept(ub, w, e_hi, e_lo, a, || y, || c);
            assert_eq!(
                exact,
                LinearRate.accept_within(ub, bounds, e_hi, e_lo, a, || y, || c, || w),
                "c {c} y {y} ub {ub}"
            );
            let exact = tilted.accept(ub, w, e_hi, e_lo, a, || y, || c);
            assert_eq!(exact, tilted.accept_within(ub, bounds, e_hi, e_lo, a, || y, || c, || w), "c {c} y {y} ub {ub}");
        }
    }
}

/// A checkpoint's bin in the earlier form (each member's `e = exp(a c)`) reads as the
/// members the current form holds; the current form reads back as written; a member
/// with both weights or neither is refused.
#[test]
fn stored_bins_read_in_either_form() {
    #[derive(Serialize)]
    struct Old {
        #[serde(skip_serializing_if = "Option::is_none")]
        e: Option<f64>,
        #[serde(skip_serializing_if = "Option::is_none")]
        r: Option<f32>,
        slot: u32,
    }
    #[derive(Serialize)]
    struct OldBin {
        members: Vec<Old>,
        bound: [f64; 2],
    }
    let bound = [(-3.0 * H).exp() * MARGIN, (4.0 * H).exp() * MARGIN];
    let es = [(3.0 * H).exp(), (3.5 * H).exp(), (4.0 * H).exp().next_down()];
    let encode = |members: Vec<Old>| rmp_serde::to_vec_named(&OldBin { members, bound }).unwrap();
    let old = encode(es.iter().zip(0..).map(|(&e, slot)| Old { e: Some(e), r: None, slot }).collect());
    let bin: Bin = rmp_serde::from_slice(&old).unwrap();
    let want: Vec<Member> = es.iter().enumerate().map(|(slot, &e)| Member::new(e, bound[1], slot)).collect();
    assert_eq!(bin, Bin { members: want, bound });
    let back: Bin = rmp_serde::from_slice(&rmp_serde::to_vec_named(&bin).unwrap()).unwrap();
    assert_eq!(back, bin);
    for (e, r) in [(Some(1.0), Some(1.0)), (None, None)] {
        let bad = encode(vec![Old { e, r, slot: 0 }]);
        assert!(rmp_serde::from_slice::<Bin>(&bad).is_err());
    }
}

/// The bookkeeping of bins, members and the records' positions stays consistent through
/// random attachments and `swap_remove` detachments (as the core makes them), junctions
/// whose rate overflows (in no bin), and re-bases.
#[test]
fn bookkeeping_survives_attachments_detachments_and_rebuilds() {
    let mut rng = pcg(2);
    let a = 0.7;
    let mut r = BinnedRupture::try_new(1.0, a, 64, &mut rng).unwrap();
    let mut attached: Vec<Attached> = Vec::new();
    for step in 0..20_000u32 {
        let x = rng.uniform();
        if attached.is_empty() || x < 0.5 {
            // Mostly near the plate; one in fifty beyond the rate's cap.
            let c = if rng.uniform() < 0.02 { 2.0 * EXPONENT_CAP / a } else { (rng.uniform() - 0.5) * 40.0 };
            let binned = attach(&mut r, &mut attached, c, step, 0.0);
            assert_eq!(binned, a * c.abs() <= EXPONENT_CAP);
        } else if x < 0.995 {
            detach_any(&mut r, &mut attached, &mut rng);
        } else {
            let dy = (rng.uniform() - 0.5) * 10.0;
            attached.iter_mut().for_each(|j| j.c -= dy);
            let over = r.rebuild(&mut attached);
            assert!(over.iter().all(|&s| a * attached[s].c.abs() > EXPONENT_CAP));
        }
        r.check(&attached);
    }
    assert!(r.spare.buffers.len() <= SPARES);
    assert!(r.spare.buffers.iter().map(Vec::capacity).sum::<usize>() <= 64);
}

/// The bin index by rounding is the truncation and correction that builds without
/// SSE4.1 use, at integers, a step of a few ulps either side of them, and halves, of
/// either sign, across the table (and for NaN).
#[test]
fn floor_index_is_the_truncation_form() {
    let by_truncation = |t: f64| (floor_by_truncation(t) + HALF as i64) as usize;
    let mut ts = vec![0.0, -0.0, f64::NAN];
    for k in -(HALF as i64) + 1..HALF as i64 {
        let k = k as f64;
        let (mut lo, mut hi) = (k, k);
        for _ in 0..3 {
            (lo, hi) = (lo.next_down(), hi.next_up());
            ts.extend([lo, hi]);
        }
        ts.extend([k, k + 0.5, k - 0.5]);
    }
    for t in ts {
        assert_eq!(floor_index(t), by_truncation(t), "t = {t}");
    }
}

thread_local! {
    /// Buffers [`new_buffer`] made on this thread.
    pub(super) static NEW_BUFFERS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Anchors drifting through the table, as the plate's motion makes them: bins fill at
/// the front and drain behind (uniform detachments). Once the first bins have filled
/// and drained, the buffers outgrown at the front and those given up behind are reused
/// for each other: after the warm-up, fewer new buffers are made than one per bin
/// crossed (36 for 432 bins), where growing each bin from scratch makes about five.
/// The spares stay within their limit, and the bookkeeping stays consistent.
#[test]
fn drifting_bins_reuse_each_others_buffers() {
    let mut rng = pcg(5);
    let (a, n) = (1.0, 6000);
    let mut r = BinnedRupture::try_new(1.0, a, n, &mut rng).unwrap();
    let mut attached: Vec<Attached> = Vec::new();
    let (steps, warm, drift) = (200_000u32, 50_000, 5e-4);
    let mut made = 0;
    for step in 0..steps {
        if step == warm {
            made = NEW_BUFFERS.with(std::cell::Cell::get);
        }
        let c = f64::from(step) * drift + 0.1 * rng.uniform();
        attach(&mut r, &mut attached, c, step, c);
        if attached.len() > n {
            detach_any(&mut r, &mut attached, &mut rng);
        }
        if step % 20_000 == 0 {
            r.check(&attached);
        }
    }
    r.check(&attached);
    let after = NEW_BUFFERS.with(std::cell::Cell::get) - made;
    let crossed = (f64::from(steps - warm) * drift * a / H) as usize;
    assert!(after < crossed, "{after} new buffers after the warm-up, {crossed} bins crossed");
    assert!(r.spare.buffers.len() <= SPARES);
    assert!(r.spare.buffers.iter().map(Vec::capacity).sum::<usize>() <= n);
}

/// Plate bounds `[y_lo, y_hi]` for the bins' tests: equal, close, across bin edges or
/// far apart, the lower one on a bin's edge, just below it, or anywhere.
fn plate_range(rng: &mut crate::rng::Pcg64, a: f64) -> (f64, f64) {
    let edge = |j: f64| j * H / a;
    let y_lo = match rng.next_u64() % 3 {
        0 => edge((rng.next_u64() % 40) as f64 - 20.0),
        1 => edge((rng.next_u64() % 40) as f64 - 20.0).next_down(),
        _ => (rng.uniform() - 0.5) * 40.0 * H / a,
    };
    (y_lo, y_lo + [0.0, 1e-9, 0.3, 3.0][(rng.next_u64() % 4) as usize] * H / a)
}

/// Over plate bounds `[y_lo, y_hi]` (equal, close, across bin edges, far apart), every
/// member's rate `exp(a |y - c|)` at every `y` within stays under its bin's bound from
/// the terms in force; the bins outside the bounds keep one term only.
#[test]
fn one_sided_bins_bound_their_members_over_the_plate_range() {
    let mut rng = pcg(4);
    let mut one_sided = 0;
    for a in [1e-3, 0.1, 1.0, 37.0] {
        let mut r = BinnedRupture::try_new(1.0, a, 64, &mut rng).unwrap();
        let edge = |j: f64| j * H / a;
        for _ in 0..400 {
            let (y_lo, y_hi) = plate_range(&mut rng, a);
            r.sides = Sides::over(r.scale, y_lo, y_hi);
            let (e_hi, e_lo) = ((a * y_hi).exp(), (-a * y_lo).exp());
            for j in -24i32..24 {
                for c in
                    [edge(j as f64), edge(j as f64).next_up(), edge(j as f64 + 0.5), edge(j as f64 + 1.0).next_down()]
                {
                    let b = r.bin_bound(r.bin_of(c), e_hi, e_lo);
                    for k in 0..=8 {
                        let y = if k == 8 { y_hi } else { y_lo + (y_hi - y_lo) * k as f64 / 8.0 };
                        let rate = (a * (y - c).abs()).exp();
                        assert!(rate <= b * (1.0 + 1e-12), "a {a} [{y_lo}, {y_hi}] y {y} c {c}: {rate} > {b}");
                    }
                    let [t0, t1] = r.sides.terms(r.bin_of(c));
                    assert!(t0 || t1);
                    one_sided += usize::from(!(t0 && t1));
                }
            }
        }
    }
    assert!(one_sided > 100_000, "{one_sided} one-sided bins");
}

/// The sides of bounds `[y_lo, y_hi]` hold over their limits (moved inwards as a plan
/// moves them): at every position within, every member's rate stays under its bin's
/// bound from the terms in force, with the factors of that position.
#[test]
fn sides_hold_within_their_limits() {
    let mut rng = pcg(6);
    let mut bounded = 0;
    for a in [1e-3, 0.1, 1.0, 37.0] {
        let r = BinnedRupture::try_new(1.0, a, 64, &mut rng).unwrap();
        let edge = |j: f64| j * H / a;
        for _ in 0..400 {
            let (y_lo, y_hi) = plate_range(&mut rng, a);
            let sides = Sides::over(r.scale, y_lo, y_hi);
            let [lo, hi] = sides.limits(r.scale);
            let guard = 1e-12 * (lo.abs().max(hi.abs()) + 1.0 / a);
            let (lo, hi) = (lo + guard, hi - guard);
            for j in -24i32..24 {
                for c in [edge(j as f64), edge(j as f64).next_up(), edge(j as f64 + 1.0).next_down()] {
                    let [u0, u1] = r.bins[r.bin_of(c)].bound;
                    let [t0, t1] = sides.terms(r.bin_of(c));
                    for y in [lo, hi, 0.5 * (lo + hi)] {
                        if !y.is_finite() {
                            continue;
                        }
                        let b =
                            (if t0 { (a * y).exp() * u0 } else { 0.0 }) + (if t1 { (-a * y).exp() * u1 } else { 0.0 });
                        let rate = (a * (y - c).abs()).exp();
                        assert!(rate <= b * (1.0 + 1e-12), "a {a} [{lo}, {hi}] y {y} c {c}: {rate} > {b}");
                        bounded += 1;
                    }
                }
            }
        }
    }
    assert!(bounded > 100_000, "{bounded} rates bounded");
}

/// After events, the plan is kept while its bounds, widened by their reach, stay within
/// its limits (its factors' and its sides'), at the rate of the junctions attached then:
/// the same bits as summing every bin under the plan's sides; a reach past the limits or
/// a re-base (which forgets the plan) plans anew.
#[test]
fn a_plan_is_kept_while_the_plate_stays_within_its_limits() {
    let mut rng = pcg(9);
    let a = 0.7;
    let mut r = BinnedRupture::try_new(1.0, a, 4096, &mut rng).unwrap();
    let mut attached: Vec<Attached> = Vec::new();
    let drive = Drive { y0: 0.3, v: 0.7 };
    for step in 0..2000u32 {
        let c = (rng.uniform() - 0.5) * 20.0;
        attach(&mut r, &mut attached, c, step, 0.0);
    }
    r.plan(|h| drive.bounds(h), attached.len());
    let mut kept = 0;
    for step in 0..2000u32 {
        if rng.uniform() < 0.5 {
            let c = 0.3 + (rng.uniform() - 0.5) * 4.0;
            attach(&mut r, &mut attached, c, step, 0.3);
        } else {
            detach_any(&mut r, &mut attached, &mut rng);
        }
        let Some(rate) = r.replan(|_, _| 1e-12, attached.len()) else {
            r.plan(|h| drive.bounds(h), attached.len());
            continue;
        };
        kept += 1;
        let full = oracle_sums(&r);
        let (m, p) = r.h.terms(full.last().copied().unwrap());
        assert_eq!(rate.to_bits(), (m + p).to_bits(), "step {step}");
    }
    assert!(kept > 1900, "{kept} of 2000 events kept the plan");
    assert_eq!(r.replan(|_, _| 1e3 / a, attached.len()), None);
    r.plan(|h| drive.bounds(h), attached.len());
    r.rebuild(&mut attached);
    assert_eq!(r.replan(|_, _| 0.0, attached.len()), None, "a re-base forgets the plan");
}

/// The running sums brought up to date from the first changed bin ([`resum`])
/// are those of summing every bin again, bit for bit, through random attachments and
/// detachments (the range of occupied bins moving or not) under fixed sides.
#[test]
fn partial_sums_are_the_bits_of_a_full_sum() {
    let mut rng = pcg(7);
    let a = 0.7;
    let mut r = BinnedRupture::try_new(1.0, a, 64, &mut rng).unwrap();
    let mut attached: Vec<Attached> = Vec::new();
    r.sides = Sides::over(r.scale, -1.0, 1.0);
    for step in 0..5_000u32 {
        if attached.len() < 3 || rng.uniform() < 0.5 {
            let c = (rng.uniform() - 0.5) * 20.0;
            attach(&mut r, &mut attached, c, step, 0.0);
        } else {
            detach_any(&mut r, &mut attached, &mut rng);
        }
        let [lo, hi] = [r.lo, r.hi];
        resum(&r.bins[lo..hi], [lo, hi], r.sides, [&mut r.cumulative, &mut r.weights], &mut r.summed, &mut r.dirty);
        let full = oracle_sums(&r);
        let bits = |v: &[[f64; 2]]| v.iter().map(|x| [x[0].to_bits(), x[1].to_bits()]).collect::<Vec<_>>();
        assert_eq!(bits(&r.cumulative), bits(&full), "step {step}");
    }
}

/// `draws` candidates of `r` with the plate at `y`: the accepted junctions' counts, their
/// chi-square against `r_i / sum r` (`r_i = exp(a |y - c_i|)`), and the accepted
/// fraction with its expected value `sum r / b` and standard error.
fn picks(r: &mut BinnedRupture, rng: &mut Pcg64, attached: &[Attached], y: f64, b: f64, draws: u64) -> Picks {
    let rates: Vec<f64> = attached.iter().map(|j| (r.a * (y - j.c).abs()).exp()).collect();
    let total: f64 = rates.iter().sum();
    let mut counts = vec![0u64; attached.len()];
    for _ in 0..draws {
        if let Some(slot) = r.pick(rng, attached, &LinearRate, || y) {
            counts[slot] += 1;
        }
    }
    let accepted: u64 = counts.iter().sum();
    let chi2 = counts
        .iter()
        .zip(&rates)
        .map(|(&n, &ri)| {
            let expected = accepted as f64 * ri / total;
            (n as f64 - expected).powi(2) / expected
        })
        .sum();
    let p = total / b;
    Picks { counts, chi2, got: accepted as f64 / draws as f64, p, se: (p * (1.0 - p) / draws as f64).sqrt() }
}

struct Picks {
    counts: Vec<u64>,
    chi2: f64,
    got: f64,
    p: f64,
    se: f64,
}

/// With the plate held at `y`, the accepted candidates pick junction `i` with probability
/// `r_i / sum r` (`r_i = exp(a |y - c_i|)`): chi-square over the junctions; and the
/// accepted fraction is `sum r / B` (a binomial proportion, 4.4 standard errors).
#[test]
fn candidates_pick_junctions_in_proportion_to_their_rates() {
    let mut rng = pcg(3);
    let (a, y) = (1.3, 0.4);
    let anchors = [-2.0, -1.1, -0.5, -0.2, 0.0, 0.1, 0.35, 0.4, 0.9, 1.5, 2.2, 3.0];
    let mut r = BinnedRupture::try_new(1.0, a, 64, &mut rng).unwrap();
    let mut attached: Vec<Attached> = anchors.iter().enumerate().map(|(i, &c)| record(c, i as u32)).collect();
    for (slot, &c) in anchors.iter().enumerate() {
        assert!(r.attached(&mut attached, slot, c, y));
    }
    let drive = Drive { y0: y, v: 0.0 };
    let plan = r.plan(|h| drive.bounds(h), anchors.len());
    let Picks { counts, chi2, got, p, se } =
        picks(&mut r, &mut rng, &attached, drive.position(0.0), plan.rate, 400_000);
    // 11 degrees of freedom: 31.26 is the 0.999 quantile.
    assert!(chi2 < 31.26, "chi2 {chi2}, counts {counts:?}");
    assert!((got - p).abs() < 4.4 * se, "accepted {got}, expected {p} +- {se}");
    assert!(p > 0.5, "the bins' bound is loose: acceptance {p}");
}

/// Over a plate step with bounds `[y_lo, y_hi]` across a bin edge ([`RuptureModel::bound`]),
/// with the plate at `y` inside: the accepted candidates pick junction `i` with
/// probability `r_i / sum r` (chi-square over the junctions), and the accepted fraction
/// is `sum r / B` (4.4 standard errors); anchors on both sides of the bounds and inside.
#[test]
fn candidates_over_a_step_pick_junctions_in_proportion_to_their_rates() {
    let mut rng = pcg(5);
    let a = 1.3;
    let (y_lo, y_hi) = (3.0 * H / a - 0.05, 3.0 * H / a + 0.08);
    let anchors = [-2.0, -0.3, 0.1, 0.2, 0.35, 0.45, 0.5, 0.6, 0.9, 1.5, 2.2];
    let mut r = BinnedRupture::try_new(1.0, a, 64, &mut rng).unwrap();
    let mut attached: Vec<Attached> = anchors.iter().enumerate().map(|(i, &c)| record(c, i as u32)).collect();
    for (slot, &c) in anchors.iter().enumerate() {
        assert!(r.attached(&mut attached, slot, c, y_lo));
    }
    let rate_bound = r.bound(y_lo, y_hi);
    let [t0, t1] = [r.sides.terms(r.bin_of(-2.0)), r.sides.terms(r.bin_of(2.2))];
    assert!(t0 == [true, false] && t1 == [false, true], "sides {:?}", r.sides);
    for y in [y_lo, 0.5 * (y_lo + y_hi), y_hi] {
        let Picks { counts, chi2, got, p, se } = picks(&mut r, &mut rng, &attached, y, rate_bound, 300_000);
        // 10 degrees of freedom: 29.59 is the 0.999 quantile.
        assert!(chi2 < 29.59, "y {y}: chi2 {chi2}, counts {counts:?}");
        assert!((got - p).abs() < 4.4 * se, "y {y}: accepted {got}, expected {p} +- {se}");
    }
}
