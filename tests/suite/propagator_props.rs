//! Property tests of `stickslip::engine::exact::stepper::linear::propagator` against an independent double-double reference.
//!
//! The reference never uses the closed form: it propagates the ODE as a linear system
//! `x' = A x` (forcing carried as extra states), lifted to quadratic monomials for `int w^2`,
//! and evaluates `exp(A t)` by scaling and squaring of a Taylor polynomial in double-double
//! arithmetic (`twofloat`, ~106 bits), in time units `1/rho` that balance the matrix.
//!
//! Error measure ("natural scale", see docs/propagator.md): the error of each quantity is
//! divided by the sum of the magnitudes of its separate contributions, i.e. by
//! `|y0| + |v0| sup|U_v| + (|a| + k|y0|) sup|U_a| + |b| sup|U_b| + tau |y'(tau)|`
//! for `y` (`U_*` the exact responses to unit `v0`, `a - k y0`, `b`; the sup is over
//! `[0, tau]`; the last term is the change from rescaling time by one unit of relative error,
//! i.e. the conditioning with respect to `M, eta, k`). Both this sup-based scale and the
//! stricter pointwise one (`|U_*(tau)|` instead of `sup`) are asserted at `1e-10`.
//!
//! Fast by default (`cargo test --release --test suite propagator_props::`); the heavy run is
//! `PROPTEST_CASES=20000 cargo test --release --test suite propagator_props:: -- --include-ignored --nocapture`.

#![allow(clippy::needless_range_loop)] // index-heavy matrix code reads better with ranges

use proptest::prelude::*;
use stickslip::engine::exact::stepper::linear::propagator::{Branch, LinearPlate, Trajectory};
use twofloat::TwoFloat as D;

fn dd(x: f64) -> D {
    D::from(x)
}

// ----------------------------------------------------------------------------------------
// Double-double linear algebra and matrix exponential.

#[derive(Clone)]
struct Mat {
    n: usize,
    a: Vec<D>,
}

impl Mat {
    fn zeros(n: usize) -> Mat {
        Mat { n, a: vec![dd(0.0); n * n] }
    }
    fn eye(n: usize) -> Mat {
        let mut m = Mat::zeros(n);
        for i in 0..n {
            m.a[i * n + i] = dd(1.0);
        }
        m
    }
    fn get(&self, i: usize, j: usize) -> D {
        self.a[i * self.n + j]
    }
    fn set(&mut self, i: usize, j: usize, v: D) {
        self.a[i * self.n + j] = v;
    }
    fn add_to(&mut self, i: usize, j: usize, v: D) {
        let n = self.n;
        self.a[i * n + j] += v;
    }
    fn mul(&self, o: &Mat) -> Mat {
        let n = self.n;
        let mut r = Mat::zeros(n);
        for i in 0..n {
            for l in 0..n {
                let x = self.a[i * n + l];
                if x.hi() == 0.0 {
                    continue;
                }
                for j in 0..n {
                    let y = o.a[l * n + j];
                    if y.hi() != 0.0 {
                        r.a[i * n + j] += x * y;
                    }
                }
            }
        }
        r
    }
    fn norm_inf(&self) -> f64 {
        (0..self.n).map(|i| (0..self.n).map(|j| self.get(i, j).hi().abs()).sum::<f64>()).fold(0.0, f64::max)
    }
    fn apply(&self, x: &[D]) -> Vec<D> {
        (0..self.n).map(|i| (0..self.n).fold(dd(0.0), |acc, j| acc + self.get(i, j) * x[j])).collect()
    }
}

/// `exp(L t)` by scaling and squaring; `target` is the norm of the scaled matrix.
fn expm(l: &Mat, t: f64, target: f64) -> Mat {
    let n = l.n;
    let nrm = l.norm_inf() * t;
    let mut j = 0i32;
    while nrm / 2f64.powi(j) > target {
        j += 1;
    }
    let scale = dd(t) / dd(2f64.powi(j));
    let mut x = l.clone();
    for v in x.a.iter_mut() {
        *v *= scale;
    }
    let mut e = Mat::eye(n);
    let mut term = Mat::eye(n);
    for kk in 1..60 {
        term = term.mul(&x);
        let inv = dd(1.0) / dd(kk as f64);
        for v in term.a.iter_mut() {
            *v *= inv;
        }
        for (ev, tv) in e.a.iter_mut().zip(term.a.iter()) {
            *ev += *tv;
        }
        if term.norm_inf() < 1e-36 {
            break;
        }
    }
    for _ in 0..j {
        e = e.mul(&e);
    }
    e
}

// ----------------------------------------------------------------------------------------
// The reference propagator.

#[derive(Clone, Copy, Debug)]
struct Case {
    m: f64,
    eta: f64,
    k: f64,
    y0: f64,
    v0: f64,
    a: f64,
    b: f64,
}

/// Time unit `1/rho_u` and the balanced linear system of `x = (u, u'/rho, p~, q~)` (`M > 0`)
/// or `(u, p~, q~)` (`M = 0`), where `p = f + b tau` is the forcing.
struct RefSystem {
    rho: D,
    a: Mat,
    /// Multipliers from physical inputs `(v, f, b)` to the scaled initial state entries
    /// (`v` absent for `M = 0`).
    in_scale: Vec<D>,
}

fn ref_system(c: &Case, horizon: f64) -> RefSystem {
    let (m, eta, k) = (dd(c.m), dd(c.eta), dd(c.k));
    if c.m > 0.0 {
        let disc = c.eta * c.eta - 4.0 * c.m * c.k;
        let rho_f = if disc >= 0.0 { (c.eta + disc.sqrt()) / (2.0 * c.m) } else { (c.k / c.m).sqrt() };
        let rho = dd(rho_f.max(1.0 / horizon));
        let mut a = Mat::zeros(4);
        a.set(0, 1, dd(1.0));
        a.set(1, 0, -(k / (m * rho * rho)));
        a.set(1, 1, -(eta / (m * rho)));
        a.set(1, 2, dd(1.0));
        a.set(2, 3, dd(1.0));
        RefSystem { rho, a, in_scale: vec![dd(1.0) / rho, dd(1.0) / (m * rho * rho), dd(1.0) / (m * rho * rho * rho)] }
    } else {
        let rho = dd((c.k / c.eta).max(1.0 / horizon));
        let mut a = Mat::zeros(3);
        a.set(0, 0, -(k / (eta * rho)));
        a.set(0, 1, dd(1.0));
        a.set(1, 2, dd(1.0));
        RefSystem { rho, a, in_scale: vec![dd(1.0) / (eta * rho), dd(1.0) / (eta * rho * rho)] }
    }
}

/// Reference values at `tau` for `u = y - y0`.
#[derive(Clone, Copy, Debug)]
struct RefPoint {
    u: D,
    up: D,
    upp: f64,
    /// `|U_v|, |U_f|, |U_b|` and their derivatives.
    resp: [f64; 3],
    dresp: [f64; 3],
}

fn ref_point(c: &Case, sys: &RefSystem, tau: f64) -> RefPoint {
    let phi = expm(&sys.a, (dd(tau) * sys.rho).hi(), 0.25);
    let f0 = dd(c.a) - dd(c.k) * dd(c.y0);
    let rho = sys.rho;
    if c.m > 0.0 {
        let x0 = [dd(0.0), dd(c.v0) * sys.in_scale[0], f0 * sys.in_scale[1], dd(c.b) * sys.in_scale[2]];
        let x = phi.apply(&x0);
        let u = x[0];
        let up = x[1] * rho;
        let p = x[2] * dd(c.m) * rho * rho;
        let upp = ((p - dd(c.k) * u - dd(c.eta) * up) / dd(c.m)).hi();
        let resp = [1, 2, 3].map(|j| (phi.get(0, j) * sys.in_scale[j - 1]).hi().abs());
        let dresp = [1, 2, 3].map(|j| (phi.get(1, j) * sys.in_scale[j - 1] * rho).hi().abs());
        RefPoint { u, up, upp, resp, dresp }
    } else {
        let x0 = [dd(0.0), f0 * sys.in_scale[0], dd(c.b) * sys.in_scale[1]];
        let x = phi.apply(&x0);
        let u = x[0];
        // u' solves the differentiated equation eta v' + k v = b, v(0) = f0/eta: the same
        // system with other initial values (no cancellation as in (p - k u)/eta).
        let v0 = [f0 / dd(c.eta), dd(c.b) * sys.in_scale[0], dd(0.0)];
        let up = phi.apply(&v0)[0];
        let upp = ((dd(c.b) - dd(c.k) * up) / dd(c.eta)).hi();
        let r = |j: usize| (phi.get(0, j) * sys.in_scale[j - 1]).hi().abs();
        // Responses of u' to unit f0 (v(0) = 1/eta) and unit b (constant forcing b/eta).
        let dr_f = (phi.get(0, 0) / dd(c.eta)).hi().abs();
        let dr_b = (phi.get(0, 1) * sys.in_scale[0]).hi().abs();
        RefPoint { u, up, upp, resp: [0.0, r(1), r(2)], dresp: [0.0, dr_f, dr_b] }
    }
}

/// Reference integrals: `int_0^h u`, `int_0^h (u - s tau)^2`, and `int U_j^2` for the
/// responses of `w = u - s tau` to unit `v - s`, `f - eta s`, `b - k s`.
struct RefIntegrals {
    i1: D,
    i2: D,
    resp_sq: [f64; 3],
    w_h: f64,
}

fn ref_integrals(c: &Case, sys: &RefSystem, h: f64, s: f64) -> RefIntegrals {
    let n = sys.a.n;
    // Lifted state: x (n), monomials x_i x_j (i <= j), I1 = int w, I2 = int w^2.
    let mut mono = vec![vec![0usize; n]; n];
    let mut idx = n;
    for i in 0..n {
        for j in i..n {
            mono[i][j] = idx;
            mono[j][i] = idx;
            idx += 1;
        }
    }
    let i1 = idx;
    let i2 = idx + 1;
    let dim = idx + 2;
    let mut l = Mat::zeros(dim);
    for i in 0..n {
        for j in 0..n {
            l.set(i, j, sys.a.get(i, j));
        }
    }
    for i in 0..n {
        for j in i..n {
            let r = mono[i][j];
            for q in 0..n {
                let ai = sys.a.get(i, q);
                if ai.hi() != 0.0 {
                    l.add_to(r, mono[q][j], ai);
                }
                let aj = sys.a.get(j, q);
                if aj.hi() != 0.0 {
                    l.add_to(r, mono[i][q], aj);
                }
            }
        }
    }
    l.set(i1, 0, dd(1.0));
    l.set(i2, mono[0][0], dd(1.0));
    let phi = expm(&l, (dd(h) * sys.rho).hi(), 0.25);
    let (k, eta) = (dd(c.k), dd(c.eta));
    let f = dd(c.a) - k * dd(c.y0) - eta * dd(s);
    let bw = dd(c.b) - k * dd(s);
    let x0: Vec<D> = if c.m > 0.0 {
        vec![dd(0.0), (dd(c.v0) - dd(s)) * sys.in_scale[0], f * sys.in_scale[1], bw * sys.in_scale[2]]
    } else {
        vec![dd(0.0), f * sys.in_scale[0], bw * sys.in_scale[1]]
    };
    let mut z0 = vec![dd(0.0); dim];
    for i in 0..n {
        z0[i] = x0[i];
        for j in i..n {
            z0[mono[i][j]] = x0[i] * x0[j];
        }
    }
    let z = phi.apply(&z0);
    let rho = sys.rho;
    // int u from the initial state of u itself (s = 0): no cancellation against s h^2/2.
    let fu = dd(c.a) - k * dd(c.y0);
    let xu: Vec<D> = if c.m > 0.0 {
        vec![dd(0.0), dd(c.v0) * sys.in_scale[0], fu * sys.in_scale[1], dd(c.b) * sys.in_scale[2]]
    } else {
        vec![dd(0.0), fu * sys.in_scale[0], dd(c.b) * sys.in_scale[1]]
    };
    let i1v = (0..n).fold(dd(0.0), |acc, j| acc + phi.get(i1, j) * xu[j]) / rho;
    let i2v = z[i2] / rho;
    let mut resp_sq = [0.0; 3];
    for (slot, j) in (1..n).enumerate() {
        let sc = sys.in_scale[slot];
        let slot = if c.m > 0.0 { slot } else { slot + 1 };
        resp_sq[slot] = (phi.get(i2, mono[j][j]) * sc * sc / rho).hi().abs();
    }
    RefIntegrals { i1: i1v, i2: i2v, resp_sq, w_h: z[0].hi() }
}

// ----------------------------------------------------------------------------------------
// Checking one case.

/// Largest errors seen, relative to the natural scales (sup-based and pointwise).
#[derive(Default, Debug, Clone, Copy)]
struct Worst {
    y: f64,
    v: f64,
    y_pointwise: f64,
    v_pointwise: f64,
    i1: f64,
    i2: f64,
}

impl Worst {
    fn merge(&mut self, o: &Worst) {
        self.y = self.y.max(o.y);
        self.v = self.v.max(o.v);
        self.y_pointwise = self.y_pointwise.max(o.y_pointwise);
        self.v_pointwise = self.v_pointwise.max(o.v_pointwise);
        self.i1 = self.i1.max(o.i1);
        self.i2 = self.i2.max(o.i2);
    }
}

const TOL: f64 = 1e-10;

/// Sample times in `(0, tau]`: uniform plus geometric towards 0 (resolves fast layers).
fn sample_times(tau: f64) -> Vec<f64> {
    let mut v: Vec<f64> = (1..=24).map(|j| tau * j as f64 / 24.0).collect();
    let mut t = tau / 48.0;
    for _ in 0..40 {
        v.push(t);
        t *= 0.5;
    }
    v.push(tau * (1.0 - 1e-9));
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v
}

fn check_case(c: &Case, tau: f64, s: f64) -> Result<Worst, String> {
    let plate = LinearPlate::new(c.m, c.eta, c.k);
    let traj = plate.trajectory(c.y0, c.v0, c.a, c.b);
    let sys = ref_system(c, tau);
    let times = sample_times(tau);
    let (lo, hi) = traj.bounds(tau);
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(format!("non-finite bounds {lo} {hi}"));
    }
    let mut sup = [0.0f64; 3];
    let mut dsup = [0.0f64; 3];
    let mut w = Worst::default();
    let fmag = c.a.abs() + c.k * c.y0.abs();
    let vmag = if c.m > 0.0 { c.v0.abs() } else { 0.0 };
    for &t in &times {
        let r = ref_point(c, &sys, t);
        for j in 0..3 {
            sup[j] = sup[j].max(r.resp[j]);
            dsup[j] = dsup[j].max(r.dresp[j]);
        }
        let y_ref = dd(c.y0) + r.u;
        let (y, v) = traj.at(t);
        if !(y.is_finite() && v.is_finite()) {
            return Err(format!("non-finite at({t}) = ({y}, {v})"));
        }
        let ey = (dd(y) - y_ref).hi().abs();
        let ev = (dd(v) - r.up).hi().abs();
        let resc_y = t * r.up.hi().abs();
        let resc_v = t * r.upp.abs();
        let sy = c.y0.abs() + vmag * sup[0] + fmag * sup[1] + c.b.abs() * sup[2] + resc_y;
        let sv = vmag * dsup[0] + fmag * dsup[1] + c.b.abs() * dsup[2] + resc_v;
        let sy_p = c.y0.abs() + vmag * r.resp[0] + fmag * r.resp[1] + c.b.abs() * r.resp[2] + resc_y;
        let sv_p = vmag * r.dresp[0] + fmag * r.dresp[1] + c.b.abs() * r.dresp[2] + resc_v;
        // Errors on values below the normal range (underflowed exponentials) are not counted.
        let rel = |e: f64, s: f64| if e == 0.0 || s < 1e-290 { 0.0 } else { e / s };
        w.y = w.y.max(rel(ey, sy));
        w.v = w.v.max(rel(ev, sv));
        w.y_pointwise = w.y_pointwise.max(rel(ey, sy_p));
        w.v_pointwise = w.v_pointwise.max(rel(ev, sv_p));
        if w.y > TOL || w.v > TOL || w.y_pointwise > TOL || w.v_pointwise > TOL {
            return Err(format!(
                "at({t:e}): y = {y:e} ref {:e} (rel {:e}), v = {v:e} ref {:e} (rel {:e}); pointwise {:e} {:e}",
                y_ref.hi(),
                w.y,
                r.up.hi(),
                w.v,
                w.y_pointwise,
                w.v_pointwise
            ));
        }
        // Bounds: the reference must stay inside (no tolerance).
        if t <= tau && !(lo <= y_ref.hi() && y_ref.hi() <= hi) {
            return Err(format!("bounds({tau:e}) = [{lo:e}, {hi:e}] miss y_ref({t:e}) = {:e}", y_ref.hi()));
        }
    }
    // Integrals.
    let ri = ref_integrals(c, &sys, tau, s);
    let got = traj.integrals(tau, s);
    if !(got.i1.is_finite() && got.i2.is_finite()) || got.i2 < 0.0 {
        return Err(format!("bad integrals {got:?}"));
    }
    let r_end = ref_point(c, &sys, tau);
    // int |U_j| <= sqrt(tau int U_j^2) (Cauchy-Schwarz).
    let rs = ri.resp_sq.map(|x| (tau * x).sqrt());
    let s1 = vmag * rs[0] + fmag * rs[1] + c.b.abs() * rs[2] + tau * r_end.u.hi().abs();
    let e1 = (dd(got.i1) - ri.i1).hi().abs();
    w.i1 = if e1 == 0.0 { 0.0 } else { e1 / s1 };
    let vw = if c.m > 0.0 { (c.v0 - s).abs() } else { 0.0 };
    let fw = fmag + c.eta * s.abs();
    let bw = c.b.abs() + c.k * s.abs();
    let nat = vw * ri.resp_sq[0].sqrt() + fw * ri.resp_sq[1].sqrt() + bw * ri.resp_sq[2].sqrt();
    let s2 = nat * nat + tau * ri.w_h * ri.w_h;
    let e2 = (dd(got.i2) - ri.i2).hi().abs();
    w.i2 = if e2 == 0.0 { 0.0 } else { e2 / s2 };
    if w.i1 > TOL || w.i2 > TOL {
        return Err(format!(
            "integrals({tau:e}, {s:e}) = {got:?}, ref ({:e}, {:e}); rel ({:e}, {:e})",
            ri.i1.hi(),
            ri.i2.hi(),
            w.i1,
            w.i2
        ));
    }
    Ok(w)
}

// ----------------------------------------------------------------------------------------
// Case generation.

fn pow10(x: f64) -> f64 {
    10f64.powf(x)
}

/// A case from unit-interval draws: `kind` selects the regime.
fn make_case(kind: u8, u: [f64; 10], signs: [bool; 5]) -> (Case, f64, f64) {
    let sg = |b: bool, x: f64| if b { -x } else { x };
    let eta = match kind % 8 {
        6 => 0.0,
        _ => pow10(-2.0 + 4.0 * u[0]),
    };
    let m = match kind % 8 {
        5 => 0.0,
        6 => pow10(-3.0 + 6.0 * u[1]),
        _ => eta * pow10(-12.0 * u[1]),
    };
    let k = match kind % 8 {
        0 | 5 => {
            if u[2] < 0.1 {
                0.0
            } else {
                pow10(-6.0 + 15.0 * u[2])
            }
        }
        1 => 0.0,
        2 => {
            // Exactly critical: eta = 2^i, M = 2^j, k = eta^2/(4M) exactly.
            let e = 2f64.powi((u[0] * 8.0) as i32 - 4);
            let mm = 2f64.powi((u[1] * 16.0) as i32 - 12);
            return finish(Case { m: mm, eta: e, k: e * e / (4.0 * mm), y0: 0.0, v0: 0.0, a: 0.0, b: 0.0 }, u, signs);
        }
        3 | 4 => {
            // Near critical: relative discriminant +-10^(-16..-2).
            let kc = eta * eta / (4.0 * m);
            let d = pow10(-16.0 + 14.0 * u[2]);
            kc * (1.0 + sg(kind % 8 == 4, d))
        }
        6 => {
            if u[2] < 0.15 {
                0.0
            } else {
                pow10(-6.0 + 15.0 * u[2])
            }
        }
        _ => eta * eta / m * pow10(-2.0 + 4.0 * u[2]),
    };
    let k = if kind % 8 == 0 { k.min(1e9) } else { k };
    finish(Case { m, eta, k, y0: 0.0, v0: 0.0, a: 0.0, b: 0.0 }, u, signs)
}

fn finish(mut c: Case, u: [f64; 10], signs: [bool; 5]) -> (Case, f64, f64) {
    let sg = |b: bool, x: f64| if b { -x } else { x };
    c.y0 = sg(signs[0], pow10(-3.0 + 6.0 * u[3]));
    c.v0 = sg(signs[1], pow10(-3.0 + 6.0 * u[4]));
    c.a = sg(signs[2], pow10(-3.0 + 9.0 * u[5]));
    c.b = sg(signs[3], pow10(-3.0 + 9.0 * u[6]));
    // Special structure: near equilibrium / steady sliding.
    let s = sg(signs[4], pow10(-3.0 + 6.0 * u[7]));
    if u[8] < 0.15 {
        c.a = c.k * c.y0 + c.eta * s;
        c.b = c.k * s;
        c.v0 = s;
    } else if u[8] < 0.25 {
        c.a = c.k * c.y0;
        c.b = 0.0;
    }
    // Horizon: from 1e-9 to many of the slowest time constants (capped).
    let plate = LinearPlate::new(c.m, c.eta, c.k);
    let rho = plate.rho();
    let slow = slowest_time(&c);
    let tmin: f64 = 1e-9;
    let tmax = (30.0 * slow).min(1e6).max(tmin * 10.0).max(if rho > 0.0 { 3.0 / rho } else { 1.0 });
    let tau = tmin * (tmax / tmin).powf(u[9]);
    (c, tau, s)
}

/// Slowest time scale of the plate (the decay time of the slow mode, or 1e3 periods).
fn slowest_time(c: &Case) -> f64 {
    if c.m == 0.0 {
        return if c.k > 0.0 { c.eta / c.k } else { 1e6 };
    }
    let disc = c.eta * c.eta - 4.0 * c.m * c.k;
    if disc >= 0.0 {
        if c.k == 0.0 {
            return (c.m / c.eta.max(1e-300)).max(1.0);
        }
        (c.eta + disc.sqrt()) / (2.0 * c.k)
    } else if c.eta > 0.0 {
        (2.0 * c.m / c.eta).min(1e3 * (c.m / c.k).sqrt())
    } else {
        1e2 * (c.m / c.k.max(1e-300)).sqrt()
    }
}

fn run_case(kind: u8, u: [f64; 10], signs: [bool; 5]) -> Result<Worst, TestCaseError> {
    let (c, tau, s) = make_case(kind, u, signs);
    check_case(&c, tau, s).map_err(|e| {
        let p = LinearPlate::new(c.m, c.eta, c.k);
        TestCaseError::fail(format!("{c:?} tau={tau:e} s={s:e} branch={:?}: {e}", p.branch()))
    })
}

fn units() -> impl Strategy<Value = [f64; 10]> {
    prop::array::uniform10(0.0..1.0f64)
}

fn signs() -> impl Strategy<Value = [bool; 5]> {
    prop::array::uniform5(any::<bool>())
}

proptest! {
    // A fixed seed, so CI runs the same cases every time; PROPTEST_RNG_SEED=N for others.
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(400),
        rng_seed: proptest::test_runner::RngSeed::Fixed(
            std::env::var("PROPTEST_RNG_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(20261121),
        ),
        ..ProptestConfig::default()
    })]

    #[test]
    fn matches_reference(kind in 0u8..8, u in units(), sg in signs()) {
        run_case(kind, u, sg)?;
    }
}

// ----------------------------------------------------------------------------------------
// Deterministic checks.

/// Worst errors over a deterministic sweep of `n` cases per regime.
fn sweep(n: usize, seed: u64) -> Worst {
    let mut worst = Worst::default();
    let mut state = seed;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for kind in 0..8u8 {
        for _ in 0..n {
            let u = [(); 10].map(|_| next());
            let sg = [(); 5].map(|_| next() < 0.5);
            let w = run_case(kind, u, sg).unwrap_or_else(|e| panic!("{e}"));
            if w.v_pointwise > 1e-13 || w.y_pointwise > 1e-13 {
                println!("pointwise outlier {:?}: {w:?}", make_case(kind, u, sg));
            }
            worst.merge(&w);
        }
    }
    println!("worst relative errors over {} cases: {worst:?}", 8 * n);
    worst
}

/// Prints the worst errors (the numbers quoted in docs/propagator.md):
/// `cargo test --release --test suite propagator_props::sweep -- --nocapture`.
#[test]
fn sweep_records_worst_errors() {
    sweep(60, 0x9e37_79b9_7f4a_7c15);
}

/// The heavy run: 8 x 2500 cases.
/// `cargo test --release --test suite propagator_props:: -- --ignored --nocapture`.
#[test]
#[ignore = "heavy: 20000 reference cases, about a minute"]
fn sweep_heavy() {
    sweep(2500, 0x2545_f491_4f6c_dd1d);
}

/// The reference is self-consistent far below the tolerance (two different scalings).
#[test]
fn reference_is_self_consistent() {
    let cases = [
        Case { m: 1e-12, eta: 1.0, k: 1e-3, y0: 0.3, v0: -2.0, a: 1.0, b: 0.5 },
        Case { m: 1.0, eta: 0.0, k: 4.0, y0: 0.3, v0: -2.0, a: 1.0, b: 0.5 },
        Case { m: 1.0, eta: 2.0, k: 1.0, y0: 0.3, v0: -2.0, a: 1.0, b: 0.5 },
        Case { m: 0.0, eta: 2.0, k: 1e-4, y0: 0.3, v0: -2.0, a: 1.0, b: 0.5 },
    ];
    for c in &cases {
        for &tau in &[1e-6, 1.0, 1e3] {
            let sys = ref_system(c, tau);
            let a = ref_point(c, &sys, tau);
            let phi = expm(&sys.a, (dd(tau) * sys.rho).hi(), 0.01);
            let f0 = dd(c.a) - dd(c.k) * dd(c.y0);
            let x0: Vec<D> = if c.m > 0.0 {
                vec![dd(0.0), dd(c.v0) * sys.in_scale[0], f0 * sys.in_scale[1], dd(c.b) * sys.in_scale[2]]
            } else {
                vec![dd(0.0), f0 * sys.in_scale[0], dd(c.b) * sys.in_scale[1]]
            };
            let u2 = phi.apply(&x0)[0];
            let scale = c.y0.abs() + a.u.hi().abs() + c.v0.abs() * tau + (c.a.abs() + c.b.abs()) * 1e-3;
            let diff = (a.u - u2).hi().abs();
            assert!(diff <= 1e-18 * scale.max(1e-300) + 1e-280, "{c:?} tau {tau}: {diff:e} vs {scale:e}");
        }
    }
}

/// `M -> 0`: after the initial layer the second-order solution approaches the overdamped
/// one, with a difference proportional to `M/eta`.
#[test]
fn small_mass_converges_to_overdamped() {
    let (eta, k, y0, a, b) = (2.0, 3.0, 0.4, 1.5, 0.7);
    let first = LinearPlate::new(0.0, eta, k).trajectory(y0, 0.0, a, b);
    let tau = 1.0;
    let (y1, v1) = first.at(tau);
    let mut prev: Option<f64> = None;
    for j in 2..10 {
        let m = eta * 10f64.powi(-j);
        // Start on the slow manifold to first order: v0 = the overdamped velocity.
        let v0 = (a - k * y0) / eta;
        let t = LinearPlate::new(m, eta, k).trajectory(y0, v0, a, b);
        let (y, v) = t.at(tau);
        let d = (y - y1).abs().max((v - v1).abs() * tau);
        let ratio = d / (m / eta);
        if let Some(p) = prev {
            // Linear convergence: d / (M/eta) settles to a constant.
            assert!((ratio / p - 1.0).abs() < 0.05 || d < 1e-13, "M={m}: ratio {ratio} vs {p}");
        }
        assert!(d <= 1.0 * (m / eta) + 1e-14, "M={m}: d={d}");
        prev = Some(ratio);
    }
}

/// `b = 0`: `y -> a/k` exactly for every branch.
#[test]
fn steady_state() {
    for &(m, eta, k) in &[(1.0, 1.0, 1.0), (1.0, 10.0, 1.0), (1e-9, 1.0, 2.0), (0.0, 1.0, 2.0), (1.0, 2.0, 1.0)] {
        let t = LinearPlate::new(m, eta, k).trajectory(0.3, -1.0, 5.0, 0.0);
        let (y, v) = t.at(1e4);
        assert!((y - 5.0 / k).abs() <= 1e-15 * 5.0 / k, "{m} {eta} {k}: {y}");
        assert!(v.abs() <= 1e-15, "{v}");
    }
}

/// Undamped oscillator: exact amplitude and phase.
#[test]
fn undamped_oscillator() {
    let (m, k) = (2.0, 8.0); // omega = 2
    let (y0, v0, a) = (0.5, 3.0, 4.0);
    let t = LinearPlate::new(m, 0.0, k).trajectory(y0, v0, a, 0.0);
    let c = a / k;
    for &tau in &[0.1, 1.0, 10.0, 1234.5] {
        let (y, v) = t.at(tau);
        let th: f64 = 2.0 * tau;
        let ye = c + (y0 - c) * th.cos() + v0 / 2.0 * th.sin();
        let ve = -2.0 * (y0 - c) * th.sin() + v0 * th.cos();
        let amp = ((y0 - c).powi(2) + (v0 / 2.0).powi(2)).sqrt();
        assert!((y - ye).abs() <= 1e-13 * (1.0 + tau) * amp, "{tau}: {y} {ye}");
        assert!((v - ve).abs() <= 1e-13 * (1.0 + tau) * 2.0 * amp, "{tau}: {v} {ve}");
        let (lo, hi) = t.bounds(tau);
        assert!(hi - lo <= 2.0 * amp * (1.0 + 1e-9) && lo <= y && y <= hi);
        if tau >= std::f64::consts::PI {
            assert!(lo <= c - amp + 1e-12 && hi >= c + amp - 1e-12);
        }
    }
}

/// Free flight (`k = eta = 0`): polynomial, exact for any horizon.
#[test]
fn free_flight() {
    let t = LinearPlate::new(2.0, 0.0, 0.0).trajectory(1.0, -0.5, 3.0, 0.25);
    for &tau in &[1e-9, 1.0, 1e3, 1e12] {
        let (y, v) = t.at(tau);
        let ye = 1.0 - 0.5 * tau + 3.0 * tau * tau / 4.0 + 0.25 * tau.powi(3) / 12.0;
        let ve = -0.5 + 3.0 * tau / 2.0 + 0.25 * tau * tau / 4.0;
        assert!((y - ye).abs() <= 1e-15 * (1.0 + 0.5 * tau + 0.75 * tau * tau + tau.powi(3) / 48.0));
        assert!((v - ve).abs() <= 1e-15 * (0.5 + 1.5 * tau + tau * tau / 16.0));
        let i = t.integrals(tau, 0.0);
        let i1e = -0.25 * tau * tau + tau.powi(3) / 4.0 + tau.powi(4) / 192.0;
        assert!((i.i1 - i1e).abs() <= 1e-14 * (0.25 * tau * tau + tau.powi(3) / 4.0 + tau.powi(4) / 192.0));
    }
}

/// Never NaN or infinite for finite inputs, including horizons of 1e12.
#[test]
fn never_nan() {
    let ms = [0.0, 1e-12, 1e-6, 1.0, 1e3];
    let etas = [0.0, 1e-3, 1.0, 1e3];
    let ks = [0.0, 1e-6, 1.0, 1e9];
    for &m in &ms {
        for &eta in &etas {
            if m == 0.0 && eta == 0.0 {
                continue;
            }
            for &k in &ks {
                for &crit in &[false, true] {
                    let k = if crit && m > 0.0 && eta > 0.0 { eta * eta / (4.0 * m) } else { k };
                    let p = LinearPlate::new(m, eta, k);
                    let t: Trajectory = p.trajectory(0.7, -3.0, 2.0, -1.0);
                    for &tau in &[0.0, 1e-12, 1e-6, 1.0, 1e6, 1e12] {
                        let (y, v) = t.at(tau);
                        let i = t.integrals(tau, 0.5);
                        let (lo, hi) = t.bounds(tau);
                        assert!(y.is_finite() && v.is_finite(), "{m} {eta} {k} {tau}: {y} {v}");
                        assert!(i.i1.is_finite() && i.i2.is_finite() && i.i2 >= 0.0, "{m} {eta} {k} {tau}: {i:?}");
                        assert!(lo.is_finite() && hi.is_finite() && lo <= y && y <= hi, "{m} {eta} {k} {tau}");
                    }
                }
            }
        }
    }
}

/// Bounds are tight for short horizons: width within a small factor of the true excursion.
#[test]
fn bounds_tight_for_short_horizons() {
    for &(m, eta, k) in &[(1.0, 1.0, 2.0), (1e-6, 1.0, 10.0), (0.0, 1.0, 3.0), (1.0, 0.0, 1.0), (1.0, 5.0, 0.0)] {
        // v0, f0 = a - k y0 and b of one sign: the contributions add up, no cancellation.
        let t = LinearPlate::new(m, eta, k).trajectory(0.2, 1.0, 0.2 * k + 1.0, 0.3);
        for &h in &[1e-6, 1e-3] {
            let (lo, hi) = t.bounds(h);
            let (mut ymin, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY);
            for j in 0..=200 {
                let (y, _) = t.at(h * j as f64 / 200.0);
                ymin = ymin.min(y);
                ymax = ymax.max(y);
            }
            let ex = ymax - ymin;
            assert!(hi - lo <= 3.0 * ex + 1e-12 * 0.2, "{m} {eta} {k} h={h}: [{lo}, {hi}] vs excursion {ex}");
        }
    }
}

#[test]
fn branch_coverage_smoke() {
    // Every branch and the Taylor path are reached by the generator above; make sure the
    // classification itself behaves as documented.
    assert_eq!(LinearPlate::new(1e-12, 1.0, 1e9).branch(), Branch::Separated);
    assert_eq!(LinearPlate::new(1.0, 2.0, 1.0 - 1e-16).branch(), Branch::Clustered);
}

/// Rare events: horizons up to 1e12 still match the reference (and stay finite).
#[test]
fn long_horizons_match_reference() {
    let plates = [
        (1.0, 1.0, 1.0),
        (1e-12, 1.0, 1e-6),
        (1e-12, 1.0, 0.0),
        (0.0, 1.0, 0.0),
        (0.0, 1.0, 1e-9),
        (1.0, 2.0, 1.0),
        (1.0, 0.0, 4.0),
        (1.0, 1e-3, 0.0),
    ];
    for &(m, eta, k) in &plates {
        let c = Case { m, eta, k, y0: 0.25, v0: -1.5, a: 0.75, b: 1e-3 };
        for &tau in &[1e9, 1e12] {
            check_case(&c, tau, 1e-3).unwrap_or_else(|e| panic!("{c:?} tau={tau:e}: {e}"));
        }
    }
}

/// `Trajectory::response` bounds how far a junction attached or detached at `tau = 0` moves
/// the plate: the new path (plate `k + s kappa`, forcing `a + s kappa c`, `s = +-1`) starts
/// from the old one's state, and `|y_new - y_old| <= response(h) kappa sup |y_old - c|` over
/// `[0, h]` (the sup bounded by the old path's `bounds(h)`), checked at 200 points of each of
/// random plates of every branch, states, anchors and horizons, with the evaluations'
/// rounding allowed for; and the bound is not loose by more than a few times where the
/// response is a push of one sign. A horizon with `k c2 > 1/2` has no finite response.
#[test]
fn response_bounds_the_plate_after_a_junction_changes() {
    let mut rng = stickslip::rng::pcg(11);
    let mut u = || stickslip::rng::UniformSource::uniform(&mut rng);
    let (mut checked, mut tight) = (0, 0);
    for case in 0..4000 {
        let m = if case % 5 == 0 { 0.0 } else { 10f64.powf(4.0 * u() - 2.0) };
        let eta = if case % 7 == 0 && m > 0.0 { 0.0 } else { 10f64.powf(4.0 * u() - 2.0) };
        let k = if case % 11 == 0 { 0.0 } else { 10f64.powf(4.0 * u() - 2.0) };
        let kappa = k.max(1e-3) * u() * 0.5;
        let sign = if case % 2 == 0 { 1.0 } else { -1.0 };
        if sign < 0.0 && kappa > k {
            continue;
        }
        let (y0, v0, b) = (4.0 * u() - 2.0, 4.0 * u() - 2.0, 2.0 * u() - 1.0);
        let a = k * y0 + 4.0 * u() - 2.0;
        let c = y0 + 6.0 * u() - 3.0;
        let old = LinearPlate::new(m, eta, k).trajectory(y0, v0, a, b);
        let v_new = if m == 0.0 { v0 } else { old.at(0.0).1 };
        let new = LinearPlate::new(m, eta, k + sign * kappa).trajectory(y0, v_new, a + sign * kappa * c, b);
        let h = 10f64.powf(6.0 * u() - 5.0);
        let r = new.response(h);
        if !r.is_finite() {
            continue;
        }
        let (lo, hi) = old.bounds(h);
        let g = kappa * (hi - c).abs().max((lo - c).abs());
        let mut worst: f64 = 0.0;
        for j in 0..=200 {
            let tau = h * j as f64 / 200.0;
            let (yo, yn) = (old.at(tau).0, new.at(tau).0);
            let slack = 1e-12 * (yo.abs() + yn.abs() + g * r);
            assert!(
                (yn - yo).abs() <= r * g + slack,
                "case {case}: M {m} eta {eta} k {k} h {h}: |{yn} - {yo}| > {r} {g}"
            );
            worst = worst.max((yn - yo).abs());
        }
        checked += 1;
        tight += usize::from(worst > 0.2 * r * g);
    }
    assert!(checked > 2000 && tight > checked / 10, "{checked} cases, {tight} within 5x of the bound");
    let p = LinearPlate::new(1.0, 1.0, 10.0).trajectory(0.0, 0.0, 0.0, 0.0);
    assert!(p.response(1.0).is_infinite() && p.response(0.1).is_finite() && p.response(f64::NAN).is_infinite());
}
