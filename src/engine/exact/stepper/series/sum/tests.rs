use super::bins::DENSE_MAX;
use super::bound::{Q_NARROW, Q_WIDE, tails_at};
use super::coefficients::{COMPILED_ORDERS, LANES, by_chain, by_output, phi_taylor_lanes, recentred_at, sums};
use super::*;
use crate::physics::ForceLaw;
use twofloat::TwoFloat as D;

/// Low coefficients against the closed forms `f^x`, `d f^x/dx` and a central difference
/// of `d f^x/dx` for `f''/2`.
#[test]
fn taylor_low_orders_match_closed_forms() {
    let law = Tilted { kappa: 0.3, l0: 0.7 };
    for &x in &[-40.0, -2.0, -0.3, 0.0, 1e-9, 0.5, 3.0, 1e4, 1e200, -1e-200] {
        let mut c = [0.0; 4];
        tilted_taylor(&law, x, &mut c);
        assert!((c[0] - law.force_x(x)).abs() <= 1e-15 * (1.0 + law.force_x(x).abs()), "x = {x}");
        assert!((c[1] - law.stiffness_x(x)).abs() <= 1e-15, "x = {x}: {} vs {}", c[1], law.stiffness_x(x));
        if x.abs() < 1e10 {
            let h = 1e-5;
            let fd = (law.stiffness_x(x + h) - law.stiffness_x(x - h)) / (2.0 * h) / 2.0;
            assert!((c[2] - fd).abs() <= 1e-8, "x = {x}: {} vs {fd}", c[2]);
        }
    }
}

/// `phi_k(x)`, `k <= 31`, in double-double by the power recurrence for `h = u^(-1/2)`,
/// `u(d) = (x + d)^2 + l0^2`: `k u0 h_k = -(2k-1) x h_(k-1) - (k-1) h_(k-2)`, then
/// `phi_k = -kappa l0 (x h_k + h_(k-1))`. Independent of the Legendre form.
fn phi_oracle(law: &Tilted, x: f64) -> Vec<D> {
    let (x0, l0) = (D::from(x), D::from(law.l0));
    let u0 = x0 * x0 + l0 * l0;
    let mut h = vec![D::from(1.0) / u0.sqrt()];
    for k in 1..PMAX {
        let mut v = D::from(-(2.0 * k as f64 - 1.0)) * x0 * h[k - 1];
        if k >= 2 {
            v -= D::from(k as f64 - 1.0) * h[k - 2];
        }
        h.push(v / (D::from(k as f64) * u0));
    }
    let a = D::from(-law.kappa) * l0;
    (0..PMAX).map(|k| a * (x0 * h[k] + if k >= 1 { h[k - 1] } else { D::from(0.0) })).collect()
}

/// Stability of the Legendre recurrence in `phi_taylor`: over `|x|/l0` from 0 to 1e6
/// (both signs, several `l0`), every `k <= 31` is within `4 (k+1) eps kappa l0 R^-k` of the
/// double-double value (the absolute error of `P_(k-1) - t P_k`, `|P_k| <= 1`, near
/// `|t| = 1` where the difference cancels), and the error in the norm
/// `sum_k |d phi_k| rho^k` of one junction's increment is below `OP_ROUNDOFF / 4` in units
/// of `eps kappa l0 / (1 - q)`, at the radius of either mode (`rho = l0/8`, wide bins, which
/// covers the narrow bins' `l0/16`; `l0/4`, direct; the worst of each is printed).
#[test]
fn direct_coefficients_roundoff() {
    let mut worst_norm: f64 = 0.0;
    let mut worst_norm_d: f64 = 0.0;
    let mut worst_k: f64 = 0.0;
    for &(kappa, l0) in &[(1.0, 1.0), (0.3, 0.07), (2.0, 9.0)] {
        let law = Tilted { kappa, l0 };
        let rho = 0.125 * l0;
        let rho_d = Q_D * l0;
        let mut ratios = vec![0.0];
        for i in 0..=240 {
            let r = 10f64.powf(-6.0 + 12.0 * i as f64 / 240.0) * (1.0 + 0.013 * i as f64);
            ratios.push(r);
            ratios.push(-r);
        }
        for &ratio in &ratios {
            let x = ratio * l0;
            let mut c = [0.0; PMAX];
            phi_taylor(&law, x, &mut c);
            let want = phi_oracle(&law, x);
            let r = x.hypot(l0);
            let (mut norm, mut norm_d) = (0.0, 0.0);
            for k in 0..PMAX {
                let err = (D::from(c[k]) - want[k]).hi().abs();
                let scale = kappa * l0 * r.powi(-(k as i32));
                let rel = err / (EPS * scale);
                assert!(rel <= 4.0 * (k as f64 + 1.0), "x/l0 = {ratio}, k = {k}: {rel} eps");
                worst_k = worst_k.max(rel / (k as f64 + 1.0));
                norm += err * rho.powi(k as i32);
                norm_d += err * rho_d.powi(k as i32);
            }
            worst_norm = worst_norm.max(norm / (EPS * kappa * l0 / (1.0 - Q_WIDE)));
            worst_norm_d = worst_norm_d.max(norm_d / (EPS * kappa * l0 / (1.0 - Q_D)));
        }
    }
    println!(
        "worst error: {worst_k:.3} (k+1) eps kappa l0 R^-k; norm {worst_norm:.3} (rho = l0/8), {worst_norm_d:.3} (rho = l0/4) eps kappa l0/(1-q)"
    );
    assert!(worst_norm <= OP_ROUNDOFF / 4.0, "norm {worst_norm}");
    assert!(worst_norm_d <= OP_ROUNDOFF / 4.0, "norm at l0/4 {worst_norm_d}");
}

/// The re-centring against the same sums in double-double arithmetic (`out[j] = sum_k
/// C(k, j) A_k t0^(k-j)`, term by term): within `(2p + 4) eps sum_k C(k, j) |A_k|
/// |t0|^(k-j)`, the Horner allowance of the round-off bound, for every order, every
/// coefficient asked for, and offsets across the disc (coefficients of mixed signs and
/// magnitudes from a fixed-seed generator).
#[test]
fn recentring_is_within_its_rounding_allowance() {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    let binom = |k: usize, j: usize| (0..j).fold(1.0, |c: f64, i| c * (k - i) as f64 / (i + 1) as f64);
    for _ in 0..2_000 {
        let p = rng.random_range(0..PMAX);
        let (mut a, mut al) = ([0.0; PMAX], [0.0; PMAX]);
        for k in 0..=p {
            a[k] = rng.random_range(-1.0..1.0) * 4f64.powi(k as i32);
            al[k] = a[k] * rng.random_range(-1.0..1.0) * 1e-17;
        }
        let t0 = rng.random_range(-0.25..0.25);
        let got = recentred::<11>(&a, &al, p, t0);
        for (j, &g) in got.iter().enumerate() {
            let (mut exact, mut size) = (D::from(0.0), 0.0);
            for k in j..=p {
                let term = D::from(binom(k, j)) * (D::from(a[k]) + D::from(al[k])) * D::from(t0).powi((k - j) as i32);
                exact += term;
                size += f64::from(term).abs();
            }
            let allowance = (2.0 * p as f64 + 4.0) * EPS * size;
            let err = (g - f64::from(exact)).abs();
            assert!(err <= allowance, "p {p}, j {j}, t0 {t0}: off by {err}, allowance {allowance}");
        }
    }
}

/// The re-centring at an order read at run time (`recentred_at` with `ORDER = 0`).
fn recentred_in<const M: usize>(a: &[f64; PMAX], al: &[f64; PMAX], p: usize, t0: f64) -> [f64; M] {
    recentred_at::<M, 0>(a, al, p, t0)
}

/// A fixed series of order `p`, high and low parts of mixed signs and magnitudes, zero above
/// `p` as the series keeps them (what the re-centring reads).
fn series_of_order(p: usize) -> ([f64; PMAX], [f64; PMAX]) {
    let mut a = [0.0; PMAX];
    let mut al = [0.0; PMAX];
    for k in 0..=p {
        a[k] = (1.7f64).powi(-(k as i32)) * if k % 3 == 1 { -1.3 } else { 0.9 + 0.01 * k as f64 };
        al[k] = a[k] * 1e-17 * (k as f64 - 7.5);
    }
    (a, al)
}

/// The re-centring's chains in full, every step taken (the zeros above `p` included): the
/// oracle of the skipped steps.
fn recentred_in_full<const M: usize>(a: &[f64; PMAX], al: &[f64; PMAX], p: usize, t0: f64) -> [f64; M] {
    let sum = sums(a, al, p);
    let (t2, t4) = (t0 * t0, t0 * t0 * (t0 * t0));
    let mut c = [[0.0; M]; 4];
    for i in (0..=p.min(PMAX - 1) / 4).rev() {
        for (r, cr) in c.iter_mut().enumerate() {
            let m = 4 * i + r;
            for j in 0..M {
                cr[j] = cr[j] * t4 + BINOM_SHIFT[m][j] * sum[m + j];
            }
        }
    }
    let mut out = [0.0; M];
    for j in 0..M {
        out[j] = (c[0][j] + t0 * c[1][j]) + t2 * (c[2][j] + t0 * c[3][j]);
    }
    out
}

/// Skipping the steps that add only zeros changes no bit: both loop orders against the
/// chains in full, at every order and every size the plate asks for, at points inside,
/// at and beyond the radius, of both signs.
#[test]
fn skipped_steps_change_no_bit() {
    fn check<const M: usize>(a: &[f64; PMAX], al: &[f64; PMAX], p: usize, t0: f64) {
        let full = recentred_in_full::<M>(a, al, p, t0).map(f64::to_bits);
        let sum = sums(a, al, p);
        assert_eq!(by_output::<M>(&sum, p, t0).map(f64::to_bits), full, "by_output, p {p}, M {M}, t0 {t0}");
        assert_eq!(by_chain::<M>(&sum, p, t0).map(f64::to_bits), full, "by_chain, p {p}, M {M}, t0 {t0}");
        assert_eq!(recentred::<M>(a, al, p, t0).map(f64::to_bits), full, "recentred, p {p}, M {M}, t0 {t0}");
    }
    for p in 0..PMAX {
        let (a, al) = series_of_order(p);
        for t0 in [0.0, -0.0, 1e-300, -0.03, 0.123456789, -0.25, 0.9, -3.0] {
            check::<4>(&a, &al, p, t0);
            check::<5>(&a, &al, p, t0);
            check::<8>(&a, &al, p, t0);
            check::<11>(&a, &al, p, t0);
            check::<12>(&a, &al, p, t0);
        }
    }
}

/// The re-centring in 256-bit vectors (where the processor has AVX2), at a compiled order
/// where `COMPILED_ORDERS` has one, is the baseline build's at a run-time order bit for
/// bit, for every size the plate asks for.
#[test]
fn recentring_is_the_same_in_every_vector_width() {
    for p in [0, 3, 11, 17, PMAX - 1] {
        let (a, al) = series_of_order(p);
        for t0 in [0.0, -0.2, 0.123456789, 0.25] {
            assert_eq!(
                recentred::<5>(&a, &al, p, t0).map(f64::to_bits),
                recentred_in::<5>(&a, &al, p, t0).map(f64::to_bits)
            );
            assert_eq!(
                recentred::<8>(&a, &al, p, t0).map(f64::to_bits),
                recentred_in::<8>(&a, &al, p, t0).map(f64::to_bits)
            );
            assert_eq!(
                recentred::<11>(&a, &al, p, t0).map(f64::to_bits),
                recentred_in::<11>(&a, &al, p, t0).map(f64::to_bits)
            );
        }
    }
}

/// The re-centring's two orders of the loops give the same values bit for bit, for every
/// size either serves and every order.
#[test]
fn recentring_orders_agree_bit_for_bit() {
    for p in 0..PMAX {
        let (a, al) = series_of_order(p);
        let sum = sums(&a, &al, p);
        for t0 in [0.0, -0.2, 0.123456789, 0.25] {
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&by_chain::<4>(&sum, p, t0)), bits(&by_output::<4>(&sum, p, t0)));
            assert_eq!(bits(&by_chain::<5>(&sum, p, t0)), bits(&by_output::<5>(&sum, p, t0)));
            assert_eq!(bits(&by_chain::<8>(&sum, p, t0)), bits(&by_output::<8>(&sum, p, t0)));
            assert_eq!(bits(&by_chain::<12>(&sum, p, t0)), bits(&by_output::<12>(&sum, p, t0)));
        }
    }
}

/// A direct-mode update in 256-bit vectors (where the processor has AVX2), compiled for its
/// length where it is one of the compiled ones, leaves the series and `X0` exactly as the
/// baseline build's does at a run-time length, at every graded order and at extensions over
/// twelve decades, both signs, added and removed.
#[test]
fn direct_updates_are_the_same_in_every_vector_width() {
    let law = Tilted { kappa: 0.3, l0: 0.7 };
    let mut s = SeriesSum::direct(law, 1e-10);
    for i in 0..50 {
        s.add(0.093 * i as f64 - 2.0);
    }
    for i in 0..=48 {
        let x = 10f64.powf(-6.0 + 0.25 * i as f64) * if i % 2 == 0 { 1.0 } else { -1.0 };
        for n in [1, 3, 4, 5, 11, s.p + 1, s.p + 2, 25] {
            for sign in [1.0, -1.0] {
                let (mut a, mut b) = (s.clone(), s.clone());
                a.apply_direct(x, n, sign);
                b.apply_direct_in::<0>(x, n, sign);
                let bits = |t: &SeriesSum| {
                    let v: Vec<u64> = t.a.iter().chain(&t.al).chain(&t.x0).map(|v| v.to_bits()).collect();
                    v
                };
                assert_eq!(bits(&a), bits(&b), "x {x}, n {n}, sign {sign}");
            }
        }
    }
}

/// A bins-mode update in 256-bit vectors (where the processor has AVX2) and at a
/// compiled order (`COMPILED_ORDERS`) leaves the series and the bin's moments exactly as the
/// baseline build's does at a run-time order: wide bins (`p = 17`), narrow bins (`p = 11`)
/// and an order not compiled as a constant (`rtol = 1e-4`).
#[test]
fn bin_updates_are_the_same_in_every_vector_width() {
    let law = Tilted { kappa: 0.4, l0: 1.0 };
    let orders: Vec<usize> = [SeriesSum::new(law, 1e-10), SeriesSum::narrow(law, 1e-10), SeriesSum::new(law, 1e-4)]
        .iter()
        .map(SeriesSum::order)
        .collect();
    assert_eq!(orders[..2], [17, 11]);
    assert!(!COMPILED_ORDERS.contains(&orders[2]), "{orders:?}");
    for mut s in [SeriesSum::new(law, 1e-10), SeriesSum::narrow(law, 1e-10), SeriesSum::new(law, 1e-4)] {
        for i in 0..200 {
            s.add(0.0137 * i as f64 - 1.1);
        }
        s.rebase(0.3);
        let slot = s.add(0.25) as usize;
        for (e, sign) in [(0.01, 1.0), (-0.0234, -1.0), (0.1, 1.0), (1e-9, -1.0)] {
            let (mut a, mut b) = (s.clone(), s.clone());
            a.apply(slot, e, sign);
            b.apply_in::<0>(slot, e, sign);
            let bits = |t: &SeriesSum| {
                let bin = &t.bins[slot];
                let v: Vec<u64> = t.a.iter().chain(&t.al).chain(&bin.m).chain(&bin.ml).map(|v| v.to_bits()).collect();
                v
            };
            assert_eq!(bits(&a), bits(&b), "p {} e {e}", s.p);
        }
    }
}

/// `phi_taylor_lanes` gives `phi_taylor`'s values bit for bit (the same operations), for
/// every number of coefficients, the same in every lane or not, at points over twelve decades of `|x|/l0` and both
/// signs, several laws.
#[test]
fn phi_taylor_lanes_is_phi_taylor() {
    let mut xs = vec![0.0, -0.0, 1e-300];
    for i in 0..=120 {
        let r = 10f64.powf(-6.0 + 12.0 * i as f64 / 120.0) * (1.0 + 0.017 * i as f64);
        xs.extend([r, -r]);
    }
    for &(kappa, l0) in &[(1.0, 1.0), (0.3, 0.07), (2.0, 9.0)] {
        let law = Tilted { kappa, l0 };
        for n in 1..=PMAX {
            for (i, chunk) in xs.chunks_exact(LANES).enumerate() {
                let x = [chunk[0] * l0, chunk[1] * l0, chunk[2] * l0, chunk[3] * l0];
                // Every lane to `n`, or the lanes to different counts up to `n`.
                let ns = if i % 2 == 0 { [n; LANES] } else { [n, 1.max(n / 2), 1.max(n / 3), n.min(2)] };
                let mut acc = [[0.0; LANES]; PMAX];
                phi_taylor_lanes(&law, x, ns, &mut acc);
                for (l, &xl) in x.iter().enumerate() {
                    let n = ns[l];
                    let mut c = [0.0; PMAX];
                    phi_taylor(&law, xl, &mut c[..n]);
                    for k in 0..PMAX {
                        // `0 + v` is `v` (but `-0` becomes `+0`, which `==` accepts).
                        assert!(acc[k][l] == c[k], "n = {n}, x = {xl}, k = {k}: {} vs {}", acc[k][l], c[k]);
                    }
                }
            }
            // Eight lanes add the same sums as two calls of four, bit for bit.
            for (i, chunk) in xs.chunks_exact(2 * LANES).enumerate() {
                let x: [f64; 2 * LANES] = std::array::from_fn(|l| chunk[l] * l0);
                let ns: [usize; 2 * LANES] = std::array::from_fn(|l| if i % 2 == 0 { n } else { 1.max(n / (l + 1)) });
                let (mut two, mut eight) = ([[0.0; LANES]; PMAX], [[0.0; LANES]; PMAX]);
                two[3][1] = 0.25;
                eight[3][1] = 0.25;
                let (xa, xb): ([f64; LANES], [f64; LANES]) =
                    (std::array::from_fn(|l| x[l]), std::array::from_fn(|l| x[l + LANES]));
                let (na, nb): ([usize; LANES], [usize; LANES]) =
                    (std::array::from_fn(|l| ns[l]), std::array::from_fn(|l| ns[l + LANES]));
                phi_taylor_lanes(&law, xa, na, &mut two);
                phi_taylor_lanes(&law, xb, nb, &mut two);
                phi_taylor_lanes(&law, x, ns, &mut eight);
                let bits = |a: &[[f64; LANES]; PMAX]| a.map(|r| r.map(f64::to_bits));
                assert_eq!(bits(&two), bits(&eight), "n = {n}, batch {i}");
            }
        }
    }
}

/// Direct mode: radius `l0/4`, the smallest order with `T_d = (1/4)^(p+1)/(3/4) <= rtol/4`
/// (17 at `rtol = 1e-10`), no bins; `for_junctions` picks it below `DIRECT_MAX`.
#[test]
fn direct_mode_order_radius_and_choice() {
    let law = Tilted { kappa: 1.0, l0: 2.0 };
    let s = SeriesSum::direct(law, 1e-10);
    assert!(s.is_direct());
    assert_eq!((s.order(), s.radius()), (17, 0.5));
    for rtol in [1e-1, 1e-4, 1e-10, 1e-13, 1e-17] {
        let p = order_for_direct(rtol);
        assert!(tails_at(Q_D, p).0 <= 0.25 * rtol, "rtol {rtol}: p = {p}");
        assert!(p == 1 || tails_at(Q_D, p - 1).0 > 0.25 * rtol, "rtol {rtol}: p = {p} not minimal");
    }
    assert!(SeriesSum::for_junctions(law, 1e-10, 300).is_direct());
    assert!(SeriesSum::for_junctions(law, 1e-10, DIRECT_MAX - 1).is_direct());
    assert!(!SeriesSum::for_junctions(law, 1e-10, DIRECT_MAX).is_direct());
    assert!(!SeriesSum::new(law, 1e-10).is_direct());
}

/// Direct mode: an add/remove pair cancels exactly in the double-double accumulators
/// (the same terms added and subtracted, `TwoSum` exact): right after each other, the
/// coefficients `A_k = hi + lo` the evaluation uses, `X0` and the force are back bit for
/// bit; interleaved with other pairs and a `shift`, and with a `c` at `remove` that
/// rounds differently (the stored offset is used), the double-double values are back
/// to the rounding of the low parts' sums (`O(eps^2)`). Nothing is charged as residue;
/// handles are reused; `len() = 0` is exactly zero.
#[test]
fn direct_add_remove_cancels_exactly() {
    let law = Tilted { kappa: 0.4, l0: 1.0 };
    let mut s = SeriesSum::direct(law, 1e-10);
    let mut hs: Vec<(f64, u32)> = (0..50).map(|i| (-0.013 * i as f64, s.add(-0.013 * i as f64))).collect();
    s.rebase(0.05);
    let coef = |s: &SeriesSum| -> Vec<f64> { (0..=s.p).map(|k| s.a[k] + s.al[k]).collect() };
    let before = s.clone();
    for c in [7.3, -0.2, 0.05, 1e-9] {
        let h = s.add(c);
        s.remove(c, h);
        assert_eq!(coef(&s), coef(&before), "c = {c}");
        assert_eq!(s.x0[0] + s.x0[1], before.x0[0] + before.x0[1]);
        assert_eq!(s.force_and_stiffness(0.1), before.force_and_stiffness(0.1));
    }
    let h = s.add(7.3);
    let h2 = s.add(-0.2);
    s.shift(0.1);
    s.remove(-0.2 - 0.1 + 1e-15, h2);
    s.remove(7.3 - 0.1, h);
    for k in 0..=s.p {
        let diff = (s.a[k] - before.a[k]) + (s.al[k] - before.al[k]);
        assert!(diff.abs() <= 4.0 * EPS * EPS * before.a[k].abs().max(law.kappa), "k = {k}: {diff:e}");
    }
    let dx0 = (s.x0[0] - before.x0[0]) + (s.x0[1] - before.x0[1]);
    assert!(dx0.abs() <= 4.0 * EPS * EPS * before.x0[0].abs(), "X0: {dx0:e}");
    assert_eq!((s.resid, s.residue(), s.bin_count()), (0, 0, 0));
    assert!(s.roff > before.roff, "the pairs' rounding is still charged");
    let again = s.add(1.0);
    assert!(again == h || again == h2, "a freed handle is reused: {again}");
    hs.push((1.0, again));
    for (c, h) in hs.drain(..) {
        s.remove(c, h);
    }
    assert!(s.is_empty());
    assert_eq!((s.force_and_stiffness(0.3), s.error_bound()), ((0.0, 0.0), 0.0));
}

/// Direct mode's re-base (four junctions at a time, blocks folded into the double-double
/// series, a tail of fewer than four, and one batch with a point outside `phi_taylor_lanes`'
/// range) against the same series built junction by junction (`add`, double-double) at
/// the same base: coefficients within the two round-off allowances, `X0` and the spread
/// to a few ulps.
#[test]
fn direct_rebase_matches_the_incremental_series() {
    for &(kappa, l0, n) in &[(1.0, 1.0, 1003usize), (0.3, 0.07, 37), (2.0, 9.0, 3)] {
        let law = Tilted { kappa, l0 };
        let y0 = 0.3 * l0;
        let mut by_add = SeriesSum::direct(law, 1e-10);
        by_add.rebase(y0);
        let mut state = 5u64;
        for i in 0..n {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            let c = if i == 5 { -1e151 * l0 } else { l0 * 30.0 * (u - 0.9) };
            by_add.add(c);
        }
        let mut rebuilt = by_add.clone();
        rebuilt.rebase(y0);
        assert_eq!(rebuilt.base(), by_add.base());
        let tol = by_add.coeff_roundoff() + rebuilt.coeff_roundoff();
        let rho = rebuilt.radius();
        let far = if n > 5 { 1e151 } else { 0.0 };
        let norm: f64 = (0..=rebuilt.p)
            .map(|k| ((rebuilt.a[k] + rebuilt.al[k]) - (by_add.a[k] + by_add.al[k])).abs() * rho.powi(k as i32))
            .sum();
        assert!(norm <= tol, "n = {n}: |dA|_rho = {norm:e} > {tol:e}");
        let x0 = |s: &SeriesSum| s.x0[0] + s.x0[1];
        assert!((x0(&rebuilt) - x0(&by_add)).abs() <= 4.0 * EPS * rebuilt.spread, "X0");
        assert!((rebuilt.spread - by_add.spread).abs() <= 4.0 * EPS * (by_add.spread + far), "spread");
        assert_eq!(rebuilt.roff, n as f64 * REBUILD_ROUNDOFF);
    }
}

/// `p` is the smallest order whose residue bound meets `rtol/4`, for wide and narrow bins;
/// non-finite or non-positive `rtol` give the cap; the radius and width follow the ratio.
#[test]
fn order_is_minimal() {
    for (q, p_at_1e10) in [(Q_WIDE, 17), (Q_NARROW, 11)] {
        assert_eq!(order_for(q, 1e-10), p_at_1e10);
        let tail = |p: usize| tails_at(q, p).0 + tails_at(0.5 * q, p).0;
        for rtol in [1e-1, 1e-4, 1e-10, 1e-13, 1e-18] {
            let p = order_for(q, rtol);
            assert!(tail(p) <= 0.25 * rtol, "q {q}, rtol {rtol}: p = {p}");
            assert!(p == 1 || tail(p - 1) > 0.25 * rtol, "q {q}, rtol {rtol}: p = {p} not minimal");
        }
        for rtol in [0.0, -1.0, f64::NAN, 1e-300] {
            assert_eq!(order_for(q, rtol), PMAX - 1);
        }
    }
    let law = Tilted { kappa: 1.0, l0: 2.0 };
    let s = SeriesSum::new(law, 1e-10);
    assert_eq!((s.order(), s.radius(), s.width()), (17, 0.25, 0.5));
    let s = SeriesSum::narrow(law, 1e-10);
    assert_eq!((s.order(), s.radius(), s.width()), (11, 0.125, 0.25));
    let pick = |n| {
        let s = SeriesSum::for_junctions(law, 1e-10, n);
        (s.is_direct(), s.width())
    };
    assert!(pick(DIRECT_MAX - 1).0);
    assert_eq!(pick(DIRECT_MAX), (false, 0.5));
    assert_eq!(pick(NARROW_FROM - 1), (false, 0.5));
    assert_eq!(pick(NARROW_FROM), (false, 0.25));
}

/// An attach/detach pair with the same anchor leaves the series exactly as it was
/// (double-double accumulation), and the count-0 bin is freed; without a re-base in
/// between no residue is charged.
#[test]
fn attach_detach_cancels() {
    let law = Tilted { kappa: 0.4, l0: 1.0 };
    let mut s = SeriesSum::new(law, 1e-10);
    for i in 0..50 {
        s.add(-0.01 * i as f64);
    }
    s.rebase(0.05);
    let before = s.force_and_stiffness(0.1);
    let bins = s.bin_count();
    let h = s.add(7.3);
    assert_eq!(s.bin_count(), bins + 1);
    let h2 = s.add(-0.2);
    s.remove(-0.2, h2);
    s.remove(7.3, h);
    assert_eq!(s.bin_count(), bins);
    assert_eq!(s.force_and_stiffness(0.1), before);
    // Two removals charged (they could have been present at the re-base), at most n_rb.
    assert_eq!((s.n_rb, s.resid), (50, 2));
}

/// The residue count is capped by the junctions present at the last re-base and reset by
/// the next one.
#[test]
fn residue_count_is_capped_and_reset() {
    let law = Tilted { kappa: 1.0, l0: 1.0 };
    let mut s = SeriesSum::new(law, 1e-10);
    let hs: Vec<(f64, u32)> = (0..10).map(|i| (0.01 * i as f64, s.add(0.01 * i as f64))).collect();
    assert_eq!((s.n_rb, s.resid), (0, 0));
    s.rebase(0.02);
    let extra: Vec<(f64, u32)> = (0..30).map(|i| (-0.03 * i as f64, s.add(-0.03 * i as f64))).collect();
    for &(c, h) in extra.iter().chain(&hs[..5]) {
        s.remove(c, h);
    }
    assert_eq!((s.n_rb, s.resid, s.len()), (10, 10, 5));
    s.rebase(0.0);
    assert_eq!((s.n_rb, s.resid), (5, 0));
}

/// The O(1) grid-index cache agrees with the sorted index, also when the anchors span
/// more than `DENSE_MAX` bins (lookups outside its range fall back to the binary search),
/// and `add` puts each anchor in bin `floor((c - origin) / w)`.
#[test]
fn dense_cache_matches_index() {
    let law = Tilted { kappa: 1.0, l0: 1.0 };
    let mut s = SeriesSum::new(law, 1e-6);
    let mut live: Vec<(f64, u32)> = Vec::new();
    let mut state = 12345u64;
    for step in 0..4000 {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let u = (state >> 11) as f64 / (1u64 << 53) as f64;
        let scale = if step % 500 < 10 { 1e7 } else { 30.0 };
        if live.is_empty() || u < 0.55 {
            let c = scale * (2.0 * u - 1.0) - 0.125;
            let h = s.add(c);
            assert_eq!(s.bins[h as usize].j, ((c - s.origin) / s.width()).floor() as i64, "c = {c}");
            live.push((c, h));
        } else {
            let (c, h) = live.swap_remove(((state >> 20) as usize) % live.len());
            s.remove(c, h);
        }
        for &(j, slot) in &s.index {
            if let Some(d) = s.dense.get(j) {
                assert_eq!(d, slot, "j = {j}");
            }
        }
        let recorded = s.dense.slots.iter().filter(|&&d| d != NONE).count();
        let in_range = s.index.iter().filter(|&&(j, _)| s.dense.get(j).is_some()).count();
        assert_eq!(recorded, in_range);
        assert!(s.dense.slots.len() <= DENSE_MAX);
    }
    assert!(s.dense.slots.len() > 100);
}

/// A series of `n` anchors spread over about `2 l0` (several bins), re-based at `y0`.
fn cubic_fixture(mut s: SeriesSum, n: usize, y0: f64) -> (SeriesSum, Vec<f64>) {
    let law = s.law;
    let mut state = 99u64;
    let anchors: Vec<f64> = (0..n)
        .map(|_| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            law.l0 * (2.0 * u - 1.2)
        })
        .collect();
    for &c in &anchors {
        s.add(c);
    }
    s.rebase(y0);
    (s, anchors)
}

/// `taylor_at`'s `c_j` against (a) the series' own derivatives by a direct sum
/// `sum_k C(k, j) A_k t0^(k-j)` (no Horner; relative 1e-13 of the sum of absolute terms)
/// and `force`, `force_and_stiffness` (bit for bit is not required: a few ulps), and
/// (b) the law's closed forms summed over the junctions, `sum_i f^x_j(y - c_i)`
/// (`tilted_taylor`), within the bins' truncation of the `j`-th coefficient,
/// `n kappa l0^(1-j) sum_(k>p) C(k, j) q^(k-j)` (`|phi_k| <= kappa l0^(1-k)`,
/// `|d - e| <= q l0`), plus the coefficients' round-off allowance seen through the `j`-th
/// derivative, `C(p, j) rho^-j` times it.
#[test]
fn taylor_at_matches_the_series_and_the_law() {
    let binom = |k: usize, j: usize| (0..j).fold(1.0, |acc, i| acc * (k - i) as f64 / (i + 1) as f64);
    for (&(kappa, l0), narrow) in [(1.0, 1.0), (0.3, 0.07)].iter().flat_map(|c| [(c, false), (c, true)]) {
        let law = Tilted { kappa, l0 };
        let s = if narrow { SeriesSum::narrow(law, 1e-10) } else { SeriesSum::new(law, 1e-10) };
        let (s, anchors) = cubic_fixture(s, 300, 0.1 * l0);
        let (p, rho) = (s.order(), s.radius());
        let n = anchors.len() as f64;
        for frac in [-0.95, -0.5, 0.0, 0.3, 0.99] {
            let y = s.base() + frac * rho;
            let (c, _) = s.taylor_at(y, 0.0);
            let t0 = y - s.base();
            let (f, fs) = s.force_and_stiffness(y);
            assert!((c[0] - f).abs() <= 4.0 * EPS * f.abs().max(kappa * l0), "c0 {} vs {f}", c[0]);
            assert!((c[1] - fs).abs() <= 4.0 * EPS * fs.abs().max(kappa), "c1 {} vs {fs}", c[1]);
            for j in 0..4 {
                let (mut direct, mut mag) = (0.0, 0.0);
                for k in j..=p {
                    let term = binom(k, j) * (s.a[k] + s.al[k]) * t0.powi((k - j) as i32);
                    direct += term;
                    mag += term.abs();
                }
                if j == 0 {
                    direct += s.linear(t0);
                    mag += s.linear(t0).abs();
                } else if j == 1 {
                    direct += kappa * n;
                    mag += kappa * n;
                }
                assert!((c[j] - direct).abs() <= 1e-13 * mag, "j = {j}: {} vs {direct}", c[j]);
                let mut law_sum = 0.0;
                let mut buf = [0.0; 5];
                for &a in &anchors {
                    tilted_taylor(&law, y - a, &mut buf);
                    law_sum += buf[j];
                }
                let trunc: f64 = (p + 1..200).map(|k| binom(k, j) * s.q.powi((k - j) as i32)).sum();
                let mut tol = n * kappa * l0.powi(1 - j as i32) * trunc
                    + binom(p, j) * rho.powi(-(j as i32)) * s.coeff_roundoff();
                if j <= 1 {
                    tol += if j == 0 { s.linear_roundoff() } else { 4.0 * EPS * kappa * n };
                }
                assert!((c[j] - law_sum).abs() <= tol, "j = {j}, y = {y}: {} vs {law_sum}, tol {tol}", c[j]);
            }
        }
    }
}

/// The remainder bound: for `|z - y| <= d` (`|y - base| + d <= radius`), the series
/// `force(z)` and the cubic differ by at most `r4 |z - y|^4` plus the rounding of the two
/// evaluations (`8 eps` of the sum of absolute terms, far below the remainder here: `d` is
/// large); `|S''''|/24` of the law's closed forms summed over the junctions is below `r4`
/// (plus the truncation of the 4th coefficient, as above); and the bound is not vacuous:
/// the largest observed remainder is at least 1e-3 of it.
#[test]
fn taylor_at_remainder_bound_holds() {
    let binom = |k: usize, j: usize| (0..j).fold(1.0, |acc, i| acc * (k - i) as f64 / (i + 1) as f64);
    for (&(kappa, l0), narrow) in [(1.0, 1.0), (0.3, 0.07)].iter().flat_map(|c| [(c, false), (c, true)]) {
        let law = Tilted { kappa, l0 };
        let s = if narrow { SeriesSum::narrow(law, 1e-10) } else { SeriesSum::new(law, 1e-10) };
        let (s, anchors) = cubic_fixture(s, 300, -0.2 * l0);
        let rho = s.radius();
        let n = anchors.len() as f64;
        let mut worst: f64 = 0.0;
        for &(frac, dfrac) in &[(0.0, 1.0), (0.0, 0.5), (0.5, 0.5), (-0.25, 0.75), (0.9, 0.1)] {
            let y = s.base() + frac * rho;
            let d = dfrac * rho;
            let (c, r4) = s.taylor_at(y, d);
            let cubic = LocalCubic { at: y, c };
            assert!(r4 > 0.0 && r4.is_finite());
            for i in 0..=40 {
                let z = y + d * (i as f64 / 20.0 - 1.0);
                let e = z - y;
                let mag = s.linear(z - s.base()).abs()
                    + (0..=s.order()).map(|k| (s.a[k] + s.al[k]).abs() * rho.powi(k as i32)).sum::<f64>();
                let diff = (s.force(z) - cubic.force(z)).abs();
                let bound = r4 * e.powi(4);
                assert!(diff <= bound + 8.0 * EPS * mag, "y = {y}, z = {z}: {diff} > {bound}");
                if bound > 1e6 * EPS * mag {
                    worst = worst.max(diff / bound);
                }
                let mut buf = [0.0; 5];
                let mut d4 = 0.0;
                for &a in &anchors {
                    tilted_taylor(&law, z - a, &mut buf);
                    d4 += buf[4];
                }
                let trunc: f64 = (s.order() + 1..200).map(|k| binom(k, 4) * s.q.powi(k as i32 - 4)).sum();
                let tol = n * kappa * l0.powi(-3) * trunc + binom(s.order(), 4) * rho.powi(-4) * s.coeff_roundoff();
                assert!(d4.abs() <= r4 + tol, "z = {z}: |S''''|/24 = {} > r4 = {r4}", d4.abs());
            }
        }
        println!("largest remainder / bound: {worst:.3e}");
        assert!(worst >= 1e-3, "the bound is vacuous here: {worst}");
    }
}

/// The cubic's derivative is the derivative of its value (`force_and_stiffness` against
/// a central difference of `force`, exact for a cubic up to rounding).
#[test]
fn local_cubic_stiffness_is_its_derivative() {
    let cubic = LocalCubic { at: 0.3, c: [1.5, -2.0, 0.7, 4.0] };
    for z in [0.3, 0.31, 0.25, -1.0] {
        let h = 1e-4;
        let fd = (cubic.force(z + h) - cubic.force(z - h)) / (2.0 * h);
        // Central difference of a cubic: exact but for c3 h^2 and rounding.
        let (f, fs) = cubic.force_and_stiffness(z);
        assert_eq!(f, cubic.force(z));
        assert!((fs - fd).abs() <= 4.0 * h * h + 1e-10, "{fs} vs {fd}");
    }
}

/// A checkpoint's series reads back as written, narrow bins included; a bins-mode state that
/// names no ratio has wide bins; a ratio the series does not know is refused.
#[test]
fn wire_keeps_the_bins_ratio() {
    let law = Tilted { kappa: 0.5, l0: 1.0 };
    for s in [SeriesSum::new(law, 1e-10), SeriesSum::narrow(law, 1e-10), SeriesSum::direct(law, 1e-10)] {
        let (s, _) = cubic_fixture(s, 50, 0.05);
        let text = serde_json::to_string(&s).unwrap();
        let back: SeriesSum = serde_json::from_str(&text).unwrap();
        assert_eq!(back, s);
        assert_eq!(text.contains("\"ratio\""), !s.is_direct() && s.width() != 0.25);
    }
    let wide = serde_json::to_value(cubic_fixture(SeriesSum::narrow(law, 1e-10), 20, 0.0).0).unwrap();
    let mut v = wide.clone();
    v.as_object_mut().unwrap().remove("ratio");
    let old: SeriesSum = serde_json::from_value(v).unwrap();
    assert_eq!((old.width(), old.radius()), (0.25, 0.125));
    let mut v = wide;
    v["ratio"] = serde_json::json!(0.3);
    let err = serde_json::from_value::<SeriesSum>(v).unwrap_err().to_string();
    assert!(err.contains("ratio 0.3"), "{err}");
}
