//! The plate over one step as a Taylor series in time, for scenes that are not stiff
//! ([`super::plate::RosenbrockPlate`] chooses it once per run; docs/engines.md, "Plate
//! between events (tilted law): a series, Taylor steps and a stiff integrator").
//!
//! With the lag `u = X - V t`, the step's local time `s` and the bond force's Taylor
//! polynomial about the step's start `y0`, `S(y0 + e) = sum_j t_j e^j` (`t_j = S^(j)(y0)/j!`
//! of the series, [`super::SeriesSum::derivatives_at`]), the plate equation
//! `M u'' + eta (u' + V) + S(y) + K u = 0`, `y(s) = y0 + e(s)`, `e(s) = u(s) - u(0) + V s`,
//! gives the coefficients of `u(s) = sum_k u_k s^k` one after another:
//!
//! - `u_(k+2) = -(eta V [k = 0] + C_k + K u_k + eta (k+1) u_(k+1)) / (M (k+1) (k+2))`;
//! - overdamped (`M = 0`): `u_(k+1) = -(eta V [k = 0] + C_k + K u_k) / (eta (k+1))`;
//!
//! with `C_k = [S(y(s))]_k = sum_(j=1..k) t_j [e^j]_k` (`C_0 = t_0`), `[e^j]_k =
//! sum_(i=1..k-j+1) b_i [e^(j-1)]_(k-i)`, `b_1 = u_1 + V`, `b_k = u_k` (`k >= 2`). Each
//! `C_k` needs only `u_1..u_k`, so the recurrence is explicit; the powers cost O(K^3/6)
//! flops for order `K`. The polynomial `S` is the series itself (not a further
//! approximation of it), so the series' error bound applies unchanged; the one new
//! approximation is the truncation in time, estimated from the last two terms (Jorba and
//! Zou, *Experimental Mathematics* 14, 2005) and held to the integrator's tolerance.
//!
//! The recurrence stops at the first order `k >= MIN_ORDER` whose last two terms are
//! within the tolerance over the whole step to the target (one step per event when the
//! events are closer than the plate's time scales), else at `ORDER`, and the step is cut
//! to the length those two terms allow.

/// Largest order of the series in time.
pub const ORDER: usize = 12;
/// Smallest order used (the estimate reads two terms; fewer would trust a lucky zero).
const MIN_ORDER: usize = 4;
/// Safety factor on the step the last two terms allow.
const SAFETY: f64 = 0.8;

/// Tolerances of one step's truncation: `u` on the lag, `w` on the velocity `u'` (unused
/// for the overdamped plate, whose state is the lag alone).
#[derive(Clone, Copy, Debug)]
pub struct Tol {
    pub u: f64,
    pub w: f64,
}

/// `1 / (k + 1)` and `1 / ((k + 1) (k + 2))`: the recurrence multiplies.
const RECIP1: [f64; ORDER + 1] = {
    let mut t = [0.0; ORDER + 1];
    let mut k = 0;
    while k <= ORDER {
        t[k] = 1.0 / (k + 1) as f64;
        k += 1;
    }
    t
};
const RECIP2: [f64; ORDER + 1] = {
    let mut t = [0.0; ORDER + 1];
    let mut k = 0;
    while k <= ORDER {
        t[k] = 1.0 / ((k + 1) * (k + 2)) as f64;
        k += 1;
    }
    t
};

/// `1 / (m + 1)` for `m <= 2 ORDER` (the square's integral).
const RECIP_2N: [f64; 2 * ORDER + 1] = {
    let mut t = [0.0; 2 * ORDER + 1];
    let mut k = 0;
    while k <= 2 * ORDER {
        t[k] = 1.0 / (k + 1) as f64;
        k += 1;
    }
    t
};

/// `u(s) = sum_(k <= order) u_k s^k` over one step of the plate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TimeSeries {
    pub u: [f64; ORDER + 1],
    pub order: usize,
    /// The last two terms are within the tolerance over the whole step asked for.
    pub converged: bool,
}

/// What the recurrence needs besides the state: the plate's constants and the force's
/// Taylor coefficients `t_j` at the step's start (`j <= ORDER`).
#[derive(Clone, Copy, Debug)]
pub struct Plant<'a> {
    pub mass: f64,
    pub eta: f64,
    pub k: f64,
    pub v: f64,
    pub force: &'a [f64; ORDER + 1],
    /// `force[j]` is known for `j <= degree` (the rest unused): the series stops at the
    /// order whose `C_k` needs `t_(degree+1)`.
    pub degree: usize,
}

/// `[e^j]_k` at `[j][k]` for `1 <= j <= k < ORDER`. [`TimeSeries::of`]'s stages are
/// unrolled and every index is a constant, so the entries become scalars (registers or fixed
/// stack slots): the zeros are never stored, and no index is computed. Row `k` is written
/// at stage `k` (`[e]_k` by [`TimeSeries::of`], `j >= 2` by [`row`]) before anything reads
/// it.
type Powers = [[f64; ORDER]; ORDER];

/// Row `K >= 2` of the powers, `[e^j]_K = sum_(i=1..K-j+1) [e]_i [e^(j-1)]_(K-i)` for `2 <= j
/// <= K` (rows below `K` and `[e]_1..[e]_(K-1)` known: none of it needs the newest
/// coefficient). Returns `sum_(j=3..K) t_j [e^j]_K` and `[e^2]_K`, the parts of `C_K =
/// sum_(j=1..K) t_j [e^j]_K` without `t_1 [e]_K` and `t_2 [e^2]_K` (the caller adds those
/// last).
///
/// Every sum takes its terms oldest first, so that the newest arrives at the end of a short
/// chain instead of the start of a long one: `[e^2]_K` holds `[e]_(K-1)` (the stage before's
/// coefficient) and `[e^j]_K` holds `[e^(j-1)]_(K-1)` (the row before's), each in the term
/// `i = 1`, added last; `[e^2]_K` is symmetric, `2 sum_(2 <= i < K/2) [e]_i [e]_(K-i) (+
/// [e]_(K/2)^2) + 2 [e]_1 [e]_(K-1)`; over `j`, the highest (oldest) rows first.
#[inline(always)]
fn row<const K: usize>(pw: &mut Powers, t: &[f64; ORDER + 1]) -> (f64, f64) {
    let e1 = pw[1][1];
    let mut c = 0.0;
    for j in (3..K + 1).rev() {
        let mut acc = 0.0;
        for i in 2..K - j + 1 {
            acc += pw[1][i] * pw[j - 1][K - i];
        }
        if K - j + 1 >= 2 {
            acc += pw[1][K - j + 1] * pw[j - 1][j - 1];
        }
        acc += e1 * pw[j - 1][K - 1];
        pw[j][K] = acc;
        c += t[j] * acc;
    }
    let e2 = if K == 2 {
        e1 * e1
    } else {
        let mut half = 0.0;
        for i in (2..(K - 1) / 2 + 1).rev() {
            half += pw[1][i] * pw[1][K - i];
        }
        let square = if K % 2 == 0 && K >= 4 { pw[1][K / 2] * pw[1][K / 2] } else { 0.0 };
        (square + 2.0 * half) + (2.0 * e1) * pw[1][K - 1]
    };
    pw[2][K] = e2;
    (c, e2)
}

/// `q_k = (u_k - c [k = 0]) s^k` for `k < L`, zero above `order`. A fixed trip count, so
/// that the terms stay in registers for [`quad`]: written one at a time to memory and read
/// back two at a time, they would wait on the stores (no store-to-load forwarding).
#[inline(always)]
fn scaled<const L: usize>(u: &[f64; ORDER + 1], order: usize, s: f64, c: f64) -> [f64; L] {
    let mut q = [0.0; L];
    let mut sk = 1.0;
    for k in 0..L {
        q[k] = if k <= order { u[k] * sk } else { 0.0 };
        sk *= s;
    }
    q[0] -= c;
    q
}

/// `sum_(k<L) q_k / (k + 1)` and `sum_(i,j<L) q_i q_j / (i + j + 1)` (the upper triangle,
/// doubled off the diagonal). Each row `sum_(j>i) q_j / (i + j + 1)` is summed in order of
/// `j`, all rows side by side (the loop over `j` outside): the rows' additions are
/// independent, so they run as vector operations instead of one chain per row, with the
/// same sums bit for bit (unit test `quad_is_the_row_by_row_sum`).
#[inline(always)]
fn quad<const L: usize>(q: &[f64; L]) -> (f64, f64) {
    let mut row = [0.0; L];
    for j in 1..L {
        for i in 0..j {
            row[i] += q[j] * RECIP_2N[i + j];
        }
    }
    let (mut i1, mut i2) = (0.0, 0.0);
    for i in 0..L {
        i1 += q[i] * RECIP1[i];
        i2 += q[i] * (q[i] * RECIP_2N[2 * i] + 2.0 * row[i]);
    }
    (i1, i2)
}

impl TimeSeries {
    /// The coefficients from `u(0) = u0` and `u'(0) = w0` (ignored when `M = 0`), up to the
    /// first order `n >= MIN_ORDER` at which the last two terms are within `tol` over `h`
    /// (`TimeSeries::within`: the step `h` to the target then needs no cut), or `ORDER`.
    ///
    /// Compiled for AVX2 where the processor has it (a run-time check): its three-operand
    /// instructions save the register copies of SSE2's two-operand ones, and the operations
    /// are the same, so the values are the same bit for bit (no FMA).
    #[inline]
    pub fn of(p: &Plant<'_>, u0: f64, w0: f64, h: f64, tol: Tol) -> TimeSeries {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, checked just above.
            return unsafe { Self::of_avx2(p, u0, w0, h, tol) };
        }
        Self::of_in(p, u0, w0, h, tol)
    }

    /// [`TimeSeries::of`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn of_avx2(p: &Plant<'_>, u0: f64, w0: f64, h: f64, tol: Tol) -> TimeSeries {
        Self::of_in(p, u0, w0, h, tol)
    }

    /// [`TimeSeries::of`] for the plate at hand.
    #[inline(always)]
    fn of_in(p: &Plant<'_>, u0: f64, w0: f64, h: f64, tol: Tol) -> TimeSeries {
        if p.mass != 0.0 {
            Self::recurrence::<true>(p, u0, w0, h, tol)
        } else {
            Self::recurrence::<false>(p, u0, w0, h, tol)
        }
    }

    /// [`TimeSeries::of`] for the dynamic plate (`DYNAMIC`, `M != 0`) or the overdamped one,
    /// its stages unrolled: stage `k` gives `u_n`, `n = k + 2` (dynamic) or `k + 1`, with
    /// every index and order a constant.
    #[inline(always)]
    fn recurrence<const DYNAMIC: bool>(p: &Plant<'_>, u0: f64, w0: f64, h: f64, tol: Tol) -> TimeSeries {
        let first = if DYNAMIC { 2 } else { 1 };
        let mut u = [0.0; ORDER + 1];
        u[0] = u0;
        if DYNAMIC {
            u[1] = w0;
        }
        // [e^j]_k for 1 <= j <= k (row k written at stage k, read later); j = 1 is `e`
        // itself: [e]_1 = u_1 + V, [e]_k = u_k.
        let mut pw: Powers = [[0.0; ORDER]; ORDER];
        let t = p.force;
        let inv = 1.0 / if DYNAMIC { p.mass } else { p.eta };
        let last = ORDER.min(p.degree + first);
        // h^(n-1) for the newest coefficient u_n (times h at each stage after the first).
        let mut hn1 = if DYNAMIC { h } else { 1.0 };
        let hw = h * tol.w;
        macro_rules! stage {
            ($k:literal) => {{
                // u_n from C_k, k = n - 2 (dynamic) or n - 1 (overdamped).
                const K: usize = $k;
                let n = K + first;
                if n > last {
                    return TimeSeries { u, order: last, converged: false };
                }
                if K > 0 {
                    hn1 *= h;
                }
                // `u_n = scale (drive + C_K + K u_K (+ eta (K+1) u_(K+1)))`, the scale
                // distributed over the terms and the terms in the order they become known:
                // the newest coefficient's last, each with its constant factor, so that a
                // stage waits on the one before for one multiplication and one addition.
                let scale = -(inv * if DYNAMIC { RECIP2[K] } else { RECIP1[K] });
                let older = if K == 0 {
                    (p.eta * p.v + t[0] + p.k * u[0]) * scale
                } else {
                    let e = if K == 1 { u[1] + p.v } else { u[K] };
                    pw[1][K] = e;
                    if K == 1 {
                        (t[1] * e + p.k * u[1]) * scale
                    } else {
                        let (c, e2) = row::<K>(&mut pw, t);
                        (c * scale + (t[2] * scale) * e2) + ((t[1] + p.k) * scale) * e
                    }
                };
                let kf = K as f64;
                u[n] = if DYNAMIC { older + (p.eta * (kf + 1.0) * scale) * u[K + 1] } else { older };
                if n >= MIN_ORDER && Self::within(&u, n, h, hn1, hw, DYNAMIC, tol) {
                    return TimeSeries { u, order: n, converged: true };
                }
            }};
        }
        stage!(0);
        stage!(1);
        stage!(2);
        stage!(3);
        stage!(4);
        stage!(5);
        stage!(6);
        stage!(7);
        stage!(8);
        stage!(9);
        stage!(10);
        if !DYNAMIC {
            stage!(11);
        }
        TimeSeries { u, order: last, converged: false }
    }

    /// Whether the last two terms are within the tolerance over `h`: `|u_(n-1)| h^(n-1) +
    /// |u_n| h^n <= tol.u` and, for the dynamic plate, their derivative's `(n-1) |u_(n-1)|
    /// h^(n-2) + n |u_n| h^(n-1) <= tol.w`; `hn1 = h^(n-1)`, `hw = h tol.w` (a caller testing
    /// several orders forms it once).
    #[inline(always)]
    fn within(u: &[f64; ORDER + 1], n: usize, h: f64, hn1: f64, hw: f64, dynamic: bool, tol: Tol) -> bool {
        let (a, b) = (u[n - 1].abs() * hn1, u[n].abs() * hn1 * h);
        a + b <= tol.u && (!dynamic || (n - 1) as f64 * a + n as f64 * b <= hw)
    }

    /// The longest step, at most `h`, over which the last two terms stay within `tol`: if `h`
    /// is not, each term gets half of each tolerance, `h <= (tol.u / (2 |u_i|))^(1/i)` and
    /// `h <= (tol.w / (2 i |u_i|))^(1/(i-1))`, times a safety factor.
    pub fn step_within(&self, h: f64, tol: Tol, dynamic: bool) -> f64 {
        let n = self.order;
        if Self::within(&self.u, n, h, h.powi(n as i32 - 1), h * tol.w, dynamic, tol) {
            return h;
        }
        let mut hmax = h;
        for i in [n - 1, n] {
            let c = self.u[i].abs();
            if c > 0.0 {
                hmax = hmax.min(SAFETY * (0.5 * tol.u / c).powf(1.0 / i as f64));
                if dynamic {
                    hmax = hmax.min(SAFETY * (0.5 * tol.w / (i as f64 * c)).powf(1.0 / (i - 1) as f64));
                }
            }
        }
        hmax
    }

    /// `u(s)` (Horner).
    #[inline]
    pub fn at(&self, s: f64) -> f64 {
        let mut acc = 0.0;
        for k in (0..self.order + 1).rev() {
            acc = acc * s + self.u[k];
        }
        acc
    }

    /// `(u(s), u'(s))` (Horner, both at once).
    #[inline]
    pub fn at_with_slope(&self, s: f64) -> (f64, f64) {
        let (mut acc, mut d) = (0.0, 0.0);
        for k in (0..self.order + 1).rev() {
            d = d * s + acc;
            acc = acc * s + self.u[k];
        }
        (acc, d)
    }

    /// `sum_(k>=2) |u_k| s^k`: how far `u` can stray from its tangent `u_0 + u_1 s` over `[0, s]`.
    #[inline]
    pub fn curvature_bound(&self, s: f64) -> f64 {
        let mut acc = 0.0;
        for k in (2..self.order + 1).rev() {
            acc = acc * s + self.u[k].abs();
        }
        acc * s * s
    }

    /// `int_0^s (u - c)` and `int_0^s (u - c)^2`, exact integrals of the polynomial: with
    /// `q_k = (u_k - c [k = 0]) s^k`, `s sum_k q_k / (k + 1)` and `s sum_(i,j) q_i q_j /
    /// (i + j + 1)`, the latter over `i <= j` (the Hilbert matrix is symmetric).
    /// Compiled for AVX2 where the processor has it (a run-time check; the same operations,
    /// none fused, so the same values bit for bit: unit test
    /// `integrals_are_the_same_in_every_vector_width`).
    pub fn integrals(&self, s: f64, c: f64) -> (f64, f64) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, checked just above.
            return unsafe { self.integrals_avx2(s, c) };
        }
        self.integrals_in(s, c)
    }

    /// [`TimeSeries::integrals_in`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn integrals_avx2(&self, s: f64, c: f64) -> (f64, f64) {
        self.integrals_in(s, c)
    }

    /// [`TimeSeries::integrals`].
    #[inline(always)]
    fn integrals_in(&self, s: f64, c: f64) -> (f64, f64) {
        // Fixed trip counts (unrolled), one size per order from MIN_ORDER: the terms a
        // larger size would add are zeros, which leave both sums as they are.
        let (u, n) = (&self.u, self.order);
        let (i1, i2) = match n {
            0..=4 => quad::<5>(&scaled(u, n, s, c)),
            5 => quad::<6>(&scaled(u, n, s, c)),
            6 => quad::<7>(&scaled(u, n, s, c)),
            7 => quad::<8>(&scaled(u, n, s, c)),
            8 => quad::<9>(&scaled(u, n, s, c)),
            9 => quad::<10>(&scaled(u, n, s, c)),
            10 => quad::<11>(&scaled(u, n, s, c)),
            11 => quad::<12>(&scaled(u, n, s, c)),
            _ => quad::<{ ORDER + 1 }>(&scaled(u, n, s, c)),
        };
        (i1 * s, i2 * s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear force `S = t0 + t1 e` makes the plate a damped oscillator: the series
    /// must match its closed form (here integrated by a tight RK4 as the oracle).
    fn rk4(p: &Plant<'_>, u0: f64, w0: f64, h: f64) -> (f64, f64) {
        let [t0, t1] = [p.force[0], p.force[1]];
        let f = |u: f64, w: f64, s: f64| {
            let e = u - u0 + p.v * s;
            (w, -(p.eta * (w + p.v) + t0 + t1 * e + p.k * u) / p.mass)
        };
        let (mut u, mut w, mut s) = (u0, w0, 0.0);
        let n = 20_000;
        let dt = h / n as f64;
        for _ in 0..n {
            let (a1, b1) = f(u, w, s);
            let (a2, b2) = f(u + 0.5 * dt * a1, w + 0.5 * dt * b1, s + 0.5 * dt);
            let (a3, b3) = f(u + 0.5 * dt * a2, w + 0.5 * dt * b2, s + 0.5 * dt);
            let (a4, b4) = f(u + dt * a3, w + dt * b3, s + dt);
            u += dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
            w += dt / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
            s += dt;
        }
        (u, w)
    }

    #[test]
    fn damped_oscillator_matches_its_integral() {
        let mut force = [0.0; ORDER + 1];
        force[0] = 3.0;
        force[1] = 15.0;
        let p = Plant { mass: 75.0, eta: 75.0, k: 150.0, v: 0.5, force: &force, degree: ORDER };
        let (u0, w0) = (-0.02, 0.3);
        for h in [0.01, 0.1, 0.4] {
            let tol = Tol { u: 1e-14, w: 1e-14 };
            let ts = TimeSeries::of(&p, u0, w0, h, tol);
            let h = ts.step_within(h, tol, true);
            let (u, w) = ts.at_with_slope(h);
            let (ur, wr) = rk4(&p, u0, w0, h);
            assert!((u - ur).abs() <= 1e-12, "h {h}: u {u} vs {ur}");
            assert!((w - wr).abs() <= 1e-11, "h {h}: w {w} vs {wr}");
        }
    }

    /// A cubic force: the series' derivative satisfies the ODE at several points of the step.
    #[test]
    fn residual_of_the_plate_equation_is_small() {
        let mut force = [0.0; ORDER + 1];
        force[..4].copy_from_slice(&[2.0, 14.0, -3.0, 0.7]);
        let (m, eta, k, v) = (75.0, 75.0, 150.0, 0.5);
        let p = Plant { mass: m, eta, k, v, force: &force, degree: ORDER };
        let (u0, w0) = (0.01, -0.2);
        let tol = Tol { u: 1e-15, w: 1e-15 };
        let ts = TimeSeries::of(&p, u0, w0, 0.2, tol);
        assert_eq!(ts.order, ORDER, "no early stop at h = 0.2");
        let h = ts.step_within(0.2, tol, true);
        for i in 0..=4 {
            let s = h * i as f64 / 4.0;
            let (u, w) = ts.at_with_slope(s);
            // u'' by differentiating twice.
            let mut a = 0.0;
            for kk in (2..=ts.order).rev() {
                a = a * s + (kk * (kk - 1)) as f64 * ts.u[kk];
            }
            let e = u - u0 + v * s;
            let f = force[0] + e * (force[1] + e * (force[2] + e * force[3]));
            let r = m * a + eta * (w + v) + f + k * u;
            assert!(r.abs() <= 1e-9, "residual {r} at s {s}");
        }
    }

    /// Overdamped: `eta (u' + V) + S + K u = 0` with linear `S` has the closed form
    /// `u(s) = u_inf + (u0 - u_inf) exp(-a s)` when `S` does not depend on `s` through `e`
    /// (here `t1 = 0`).
    #[test]
    fn overdamped_relaxation_is_exponential() {
        let mut force = [0.0; ORDER + 1];
        force[0] = 1.5;
        let (eta, k, v) = (2.0, 3.0, 0.5);
        let p = Plant { mass: 0.0, eta, k, v, force: &force, degree: ORDER };
        let u0 = 0.4;
        let tol = Tol { u: 1e-15, w: f64::NAN };
        let ts = TimeSeries::of(&p, u0, 0.0, 0.3, tol);
        let h = ts.step_within(0.3, tol, false);
        let a = k / eta;
        let u_inf = -(eta * v + 1.5) / k;
        let exact = u_inf + (u0 - u_inf) * (-a * h).exp();
        assert!((ts.at(h) - exact).abs() <= 1e-14, "{} vs {exact}", ts.at(h));
    }

    #[test]
    fn short_steps_stop_early() {
        let mut force = [0.0; ORDER + 1];
        force[..3].copy_from_slice(&[2.0, 14.0, -3.0]);
        let p = Plant { mass: 75.0, eta: 75.0, k: 150.0, v: 0.5, force: &force, degree: ORDER };
        let tol = Tol { u: 1e-12, w: 1e-12 };
        let ts = TimeSeries::of(&p, 0.0, 0.1, 1e-4, tol);
        assert!(ts.order < 8, "order {} for a short step", ts.order);
        assert_eq!(ts.step_within(1e-4, tol, true), 1e-4);
    }

    /// The integrals compiled for AVX2 (where the processor has it) are the baseline
    /// build's bit for bit, at every order and over steps and offsets of several scales.
    #[test]
    fn integrals_are_the_same_in_every_vector_width() {
        for order in 0..=ORDER {
            let mut u = [0.0; ORDER + 1];
            for (k, uk) in u.iter_mut().enumerate().take(order + 1) {
                *uk = (1.3f64).powi(-(k as i32)) * if k % 3 == 1 { -0.7 } else { 1.1 + 0.01 * k as f64 };
            }
            let ts = TimeSeries { u, order, converged: true };
            for (s, c) in [(1e-4, 0.0), (0.033, 0.3), (0.5, -2.0), (1.0, 1e3)] {
                let (a, b) = (ts.integrals(s, c), ts.integrals_in(s, c));
                assert_eq!((a.0.to_bits(), a.1.to_bits()), (b.0.to_bits(), b.1.to_bits()), "order {order}, s {s}");
            }
        }
    }

    /// A NaN or an infinity in the state or in a force coefficient the series uses shows in
    /// its last coefficient (what the plate step checks), whatever the plant's zeros.
    #[test]
    fn non_finite_inputs_reach_the_last_coefficient() {
        let tol = Tol { u: 1e-12, w: 1e-12 };
        for (mass, eta, k) in [(75.0, 75.0, 150.0), (0.0, 75.0, 150.0), (1.0, 0.0, 0.0), (0.0, 2.0, 0.0)] {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                for at in 0..5 {
                    let mut force = [0.0; ORDER + 1];
                    force[..3].copy_from_slice(&[1.0, 3.0, -0.5]);
                    let (mut u0, mut w0) = (0.01, -0.2);
                    match at {
                        0 => u0 = bad,
                        1 => w0 = bad,
                        j => force[j - 2] = bad,
                    }
                    if at == 1 && mass == 0.0 {
                        continue; // the overdamped plate has no velocity in its state
                    }
                    let p = Plant { mass, eta, k, v: 0.5, force: &force, degree: ORDER };
                    let ts = TimeSeries::of(&p, u0, w0, 0.05, tol);
                    assert!(!ts.u[ts.order].is_finite(), "M {mass}, eta {eta}, K {k}, {bad} at {at}: {:?}", ts.u);
                }
            }
        }
    }

    /// [`quad`] before its loops were exchanged: each row summed in turn.
    fn quad_rowwise<const L: usize>(q: &[f64; ORDER + 1]) -> (f64, f64) {
        let (mut i1, mut i2) = (0.0, 0.0);
        for i in 0..L {
            i1 += q[i] * RECIP1[i];
            let mut row = 0.0;
            for j in i + 1..L {
                row += q[j] * RECIP_2N[i + j];
            }
            i2 += q[i] * (q[i] * RECIP_2N[2 * i] + 2.0 * row);
        }
        (i1, i2)
    }

    /// The rows summed side by side give the row-by-row sums bit for bit, at every size,
    /// over coefficients of mixed signs and magnitudes (a fixed-seed generator).
    #[test]
    fn quad_is_the_row_by_row_sum() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        for _ in 0..20_000 {
            let mut q = [0.0; ORDER + 1];
            for qk in &mut q {
                *qk = rng.random_range(-1.0..1.0) * 10f64.powf(rng.random_range(-12.0..3.0));
            }
            let bits = |(a, b): (f64, f64)| (a.to_bits(), b.to_bits());
            fn head<const L: usize>(q: &[f64; ORDER + 1]) -> [f64; L] {
                q[..L].try_into().expect("L <= ORDER + 1")
            }
            assert_eq!(bits(quad::<5>(&head(&q))), bits(quad_rowwise::<5>(&q)));
            assert_eq!(bits(quad::<6>(&head(&q))), bits(quad_rowwise::<6>(&q)));
            assert_eq!(bits(quad::<7>(&head(&q))), bits(quad_rowwise::<7>(&q)));
            assert_eq!(bits(quad::<8>(&head(&q))), bits(quad_rowwise::<8>(&q)));
            assert_eq!(bits(quad::<9>(&head(&q))), bits(quad_rowwise::<9>(&q)));
            assert_eq!(bits(quad::<10>(&head(&q))), bits(quad_rowwise::<10>(&q)));
            assert_eq!(bits(quad::<11>(&head(&q))), bits(quad_rowwise::<11>(&q)));
            assert_eq!(bits(quad::<12>(&head(&q))), bits(quad_rowwise::<12>(&q)));
            assert_eq!(bits(quad::<{ ORDER + 1 }>(&head(&q))), bits(quad_rowwise::<{ ORDER + 1 }>(&q)));
        }
    }

    #[test]
    fn integrals_match_quadrature() {
        let ts = TimeSeries {
            u: [0.3, -1.0, 0.5, 0.2, -0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            order: 4,
            converged: true,
        };
        let (s, c) = (0.7, 0.1);
        let n = 10_000;
        let (mut a, mut b) = (0.0, 0.0);
        for i in 0..n {
            let x = s * (i as f64 + 0.5) / n as f64;
            let q = ts.at(x) - c;
            a += q;
            b += q * q;
        }
        let (a, b) = (a * s / n as f64, b * s / n as f64);
        let (i1, i2) = ts.integrals(s, c);
        assert!((i1 - a).abs() < 1e-7 && (i2 - b).abs() < 1e-7, "{i1} {a} {i2} {b}");
    }

    /// The recurrence as it was before its stages were unrolled (a triangle with computed
    /// indices, dispatched per stage), kept as the oracle of bit-identity: verbatim but for
    /// each stage's arithmetic, which is the unrolled form's term for term (the divisor in
    /// each term's factor, `[e^2]_k` by its symmetry, every sum oldest term first).
    mod oracle {
        use super::super::{MIN_ORDER, ORDER, Plant, RECIP1, RECIP2, TimeSeries, Tol};

        /// `[e^j]_k` for `1 <= j <= k < ORDER`, row by row: the triangle flattened. Row `k` is
        /// written in full at stage `k` (`[e]_k` by `of`, `j >= 2` by `row`)
        /// before anything reads it, and only earlier rows and its own first entry are read, so
        /// the triangle starts uninitialised: zeroing its 66 entries cost about 50 instructions a
        /// step, a sixth of the recurrence's own work at order 8.
        struct Powers {
            v: [std::mem::MaybeUninit<f64>; POWERS],
            /// Entries written (checked in debug builds).
            #[cfg(debug_assertions)]
            written: u128,
        }
        const POWERS: usize = ORDER * (ORDER - 1) / 2;

        impl Powers {
            #[inline(always)]
            fn new() -> Powers {
                Powers {
                    v: [const { std::mem::MaybeUninit::uninit() }; POWERS],
                    #[cfg(debug_assertions)]
                    written: 0,
                }
            }
            #[inline(always)]
            fn set(&mut self, i: usize, x: f64) {
                self.v[i] = std::mem::MaybeUninit::new(x);
                #[cfg(debug_assertions)]
                {
                    self.written |= 1 << i;
                }
            }
        }

        impl std::ops::Index<usize> for Powers {
            type Output = f64;
            #[inline(always)]
            fn index(&self, i: usize) -> &f64 {
                #[cfg(debug_assertions)]
                assert!(self.written & (1 << i) != 0, "Powers: entry {i} read before it was written");
                // SAFETY: rows are written in full, in order, before they are read (type doc), so
                // every entry read has been written by `set`.
                unsafe { self.v[i].assume_init_ref() }
            }
        }
        /// Where `[e^j]_k` sits in `Powers`.
        #[inline(always)]
        const fn at(j: usize, k: usize) -> usize {
            k * (k - 1) / 2 + j - 1
        }

        /// Row `k >= 2` of the powers, `[e^j]_k = sum_(i=1..k-j+1) [e]_i [e^(j-1)]_(k-i)` for
        /// `2 <= j <= k` (rows below `k` and `[e]_1..[e]_k` known), with `sum_(j>=3) t_j
        /// [e^j]_k` and `[e^2]_k`. Dispatched to a copy per `k` whose loops have constant trip
        /// counts, so they unroll.
        #[inline]
        fn power_row(k: usize, pw: &mut Powers, t: &[f64; ORDER + 1]) -> (f64, f64) {
            match k {
                2 => row::<2>(pw, t),
                3 => row::<3>(pw, t),
                4 => row::<4>(pw, t),
                5 => row::<5>(pw, t),
                6 => row::<6>(pw, t),
                7 => row::<7>(pw, t),
                8 => row::<8>(pw, t),
                9 => row::<9>(pw, t),
                10 => row::<10>(pw, t),
                _ => row::<11>(pw, t),
            }
        }

        /// `power_row` for a fixed `K` (`2 <= K < ORDER`): the unrolled form's terms in its
        /// order (oldest first, the symmetric `[e^2]_K` halved).
        #[inline(always)]
        fn row<const K: usize>(pw: &mut Powers, t: &[f64; ORDER + 1]) -> (f64, f64) {
            let e1 = pw[at(1, 1)];
            let mut c = 0.0;
            for j in (3..K + 1).rev() {
                let mut acc = 0.0;
                for i in 2..K - j + 1 {
                    acc += pw[at(1, i)] * pw[at(j - 1, K - i)];
                }
                if K - j + 1 >= 2 {
                    acc += pw[at(1, K - j + 1)] * pw[at(j - 1, j - 1)];
                }
                acc += e1 * pw[at(j - 1, K - 1)];
                pw.set(at(j, K), acc);
                c += t[j] * acc;
            }
            let e2 = if K == 2 {
                e1 * e1
            } else {
                let mut half = 0.0;
                for i in (2..(K - 1) / 2 + 1).rev() {
                    half += pw[at(1, i)] * pw[at(1, K - i)];
                }
                let square = if K % 2 == 0 && K >= 4 { pw[at(1, K / 2)] * pw[at(1, K / 2)] } else { 0.0 };
                (square + 2.0 * half) + (2.0 * e1) * pw[at(1, K - 1)]
            };
            pw.set(at(2, K), e2);
            (c, e2)
        }

        pub struct Old;

        impl Old {
            /// The coefficients from `u(0) = u0` and `u'(0) = w0` (ignored when `M = 0`), up to the
            /// first order `n >= MIN_ORDER` at which the last two terms are within `tol` over `h`
            /// (`within`: the step `h` to the target then needs no cut), or `ORDER`.
            pub fn of(p: &Plant<'_>, u0: f64, w0: f64, h: f64, tol: Tol) -> TimeSeries {
                let mut u = [0.0; ORDER + 1];
                u[0] = u0;
                let dynamic = p.mass != 0.0;
                let first = if dynamic { 2 } else { 1 };
                if dynamic {
                    u[1] = w0;
                }
                // [e^j]_k for 1 <= j <= k (row k written at stage k, read later); j = 1 is `e`
                // itself: [e]_1 = u_1 + V, [e]_k = u_k.
                let mut pw = Powers::new();
                let t = p.force;
                let inv = 1.0 / if dynamic { p.mass } else { p.eta };
                let last = ORDER.min(p.degree + first);
                let mut order = last;
                let mut converged = false;
                // h^(n-1) and h^n for the newest coefficient u_n.
                let mut hn = if dynamic { h } else { 1.0 };
                for n in first..last + 1 {
                    // u_n from C_k, k = n - 2 (dynamic) or n - 1 (overdamped).
                    let k = n - first;
                    let scale = -(inv * if dynamic { RECIP2[k] } else { RECIP1[k] });
                    let older = if k == 0 {
                        (p.eta * p.v + t[0] + p.k * u[0]) * scale
                    } else if k == 1 {
                        let e = u[1] + p.v;
                        pw.set(at(1, 1), e);
                        (t[1] * e + p.k * u[1]) * scale
                    } else {
                        pw.set(at(1, k), u[k]);
                        let (c, e2) = power_row(k, &mut pw, t);
                        (c * scale + (t[2] * scale) * e2) + ((t[1] + p.k) * scale) * u[k]
                    };
                    let kf = k as f64;
                    u[n] = if dynamic { older + (p.eta * (kf + 1.0) * scale) * u[k + 1] } else { older };
                    let hn1 = hn;
                    hn *= h;
                    if n >= MIN_ORDER && Old::within(&u, n, h, hn1, dynamic, tol) {
                        order = n;
                        converged = true;
                        break;
                    }
                }
                TimeSeries { u, order, converged }
            }

            /// Whether the last two terms are within the tolerance over `h`: `|u_(n-1)| h^(n-1) +
            /// |u_n| h^n <= tol.u` and, for the dynamic plate, their derivative's `(n-1) |u_(n-1)|
            /// h^(n-2) + n |u_n| h^(n-1) <= tol.w`; `hn1 = h^(n-1)`.
            #[inline]
            fn within(u: &[f64; ORDER + 1], n: usize, h: f64, hn1: f64, dynamic: bool, tol: Tol) -> bool {
                let (a, b) = (u[n - 1].abs() * hn1, u[n].abs() * hn1 * h);
                a + b <= tol.u && (!dynamic || (n - 1) as f64 * a + n as f64 * b <= h * tol.w)
            }
        }
    }

    /// The unrolled recurrence gives the oracle's coefficients bit for bit, with the same
    /// order and convergence, over random plants (dynamic and overdamped), force
    /// coefficients of varied magnitudes and degrees, steps from 1e-4 to 1 and tolerances
    /// from 1e-15 to 1e-6.
    #[test]
    fn unrolled_recurrence_is_bit_identical_to_the_oracle() {
        use rand::RngExt;
        let mut rng = crate::rng::pcg(20261126);
        let log_uniform = |rng: &mut crate::rng::Pcg64, lo: f64, hi: f64| {
            let x: f64 = rng.random();
            10f64.powf(lo + (hi - lo) * x)
        };
        let (mut converged, mut orders) = (0usize, [0usize; ORDER + 1]);
        let cases = 200_000;
        for case in 0..cases {
            let dynamic = case % 4 != 3;
            let sign = |rng: &mut crate::rng::Pcg64| if rng.random::<bool>() { 1.0 } else { -1.0 };
            let mass = if dynamic { log_uniform(&mut rng, -2.0, 3.0) } else { 0.0 };
            let eta = if dynamic && case % 16 == 0 { 0.0 } else { log_uniform(&mut rng, -2.0, 3.0) };
            let k = if case % 8 == 1 { 0.0 } else { log_uniform(&mut rng, -2.0, 3.0) };
            let v = if case % 8 == 2 { 0.0 } else { sign(&mut rng) * log_uniform(&mut rng, -3.0, 1.0) };
            // Coefficients t_j ~ A / R^j (a force of scale A varying over a length R), some
            // exactly zero or negative zero.
            let (scale, radius) = (log_uniform(&mut rng, -3.0, 4.0), log_uniform(&mut rng, -2.0, 1.0));
            let mut force = [0.0; ORDER + 1];
            let mut rj = 1.0;
            for f in force.iter_mut() {
                *f = match rng.random_range(0..20) {
                    0 => 0.0,
                    1 => -0.0,
                    _ => sign(&mut rng) * scale * log_uniform(&mut rng, -1.0, 1.0) / rj,
                };
                rj *= radius;
            }
            let degree = match case % 5 {
                0 => 4,
                1 => 7,
                2 => ORDER - 2,
                3 => ORDER,
                _ => rng.random_range(0..ORDER + 1),
            };
            let p = Plant { mass, eta, k, v, force: &force, degree };
            let u0 = if case % 32 == 5 { 0.0 } else { sign(&mut rng) * log_uniform(&mut rng, -5.0, 0.0) };
            let w0 = if case % 32 == 6 { -0.0 } else { sign(&mut rng) * log_uniform(&mut rng, -5.0, 0.0) };
            let h = log_uniform(&mut rng, -4.0, 0.0);
            let tol = Tol {
                u: log_uniform(&mut rng, -15.0, -6.0),
                w: if !dynamic && case % 2 == 1 { f64::NAN } else { log_uniform(&mut rng, -15.0, -6.0) },
            };
            let old = oracle::Old::of(&p, u0, w0, h, tol);
            // The dispatched form (AVX2 where the processor has it) and the portable one.
            for new in [TimeSeries::of(&p, u0, w0, h, tol), TimeSeries::of_in(&p, u0, w0, h, tol)] {
                assert_eq!(
                    new.u.map(f64::to_bits),
                    old.u.map(f64::to_bits),
                    "case {case}: {p:?} {u0} {w0} {h} {tol:?}"
                );
                assert_eq!((new.order, new.converged), (old.order, old.converged), "case {case}");
            }
            let new = TimeSeries::of(&p, u0, w0, h, tol);
            converged += new.converged as usize;
            orders[new.order] += 1;
        }
        // Both exits are exercised, at many orders.
        assert!(converged > cases / 10 && converged < cases - cases / 10, "{converged} of {cases} converged");
        assert!(orders.iter().filter(|&&c| c > 100).count() >= 6, "orders {orders:?}");
    }
}
