//! Closed-form propagator of the linear-law plate between junction events.
//!
//! Between two events of the exact engine with the `linear` force law, the plate obeys, in
//! local time `tau >= 0` since the last event and in coordinates re-based by the caller,
//!
//! ```text
//!     M y'' + eta y' + k y = a + b tau,      y(0) = y0,  y'(0) = v0,
//! ```
//!
//! with `M >= 0`, `eta >= 0`, `k >= 0` (`k = K + kappa n_attached`), not both `M = 0` and
//! `eta = 0`. For `M = 0` the equation is first order, `v0` is **ignored** and the initial
//! velocity is `(a - k y0) / eta`.
//!
//! [`LinearPlate::new`] classifies the plate once; [`LinearPlate::trajectory`] fixes the
//! initial state and the forcing; [`Trajectory::at`], [`Trajectory::integrals`] and
//! [`Trajectory::bounds`] evaluate it. Every evaluation works with the displacement
//! `u = y - y0`, which solves the same equation with forcing `f0 + b tau`,
//! `f0 = a - k y0`, and `u(0) = 0`. Per evaluation time one of three representations is
//! used, each free of the cancellations of the textbook `A e^{r1 t} + B e^{r2 t}` form:
//!
//! * **Taylor** (`M > 0` and `rho tau <= 1`, `rho` the largest root modulus): the series of
//!   `u` from the recurrence `M u^(n+2) + eta u^(n+1) + k u^(n) = 0` (`n >= 2`); no
//!   transcendental call, exact to round-off, and the hot path of the engine at large N.
//! * **Slow + fast** (`M = 0`, or real roots with `|r_slow| <= |r_fast| / 2`, i.e.
//!   `eta^2 - 4 M k >= eta^2 / 9`, including `k = 0` and very stiff plates):
//!   `u = S(tau) + c_f e^{r_f tau}`, where `S' = r_s S + g0 + g1 tau` is the slow first-order
//!   motion, written with the `phi` functions `phi_j(z) = (e^z - sum_{i<j} z^i/i!) / z^j`
//!   (series for `|z| <= 1`). `r_s = -k/mu`, `r_f = -mu/M`, `mu = (eta + sqrt(disc))/2`:
//!   the slow root is never formed by cancellation, and `g0, g1, c_f` are divided by
//!   `mu >= eta/2` and `sqrt(disc) >= eta/3` only.
//! * **Clustered** (complex roots, critical and near-critical real roots, `eta = 0`):
//!   particular solution `c0 + c1 tau` plus a homogeneous part in the basis
//!   `u1 = e^{m tau} ch(tau)`, `u2 = e^{m tau} sh(tau)`, `m = -eta/(2M)`, `q = disc/(4M^2)`,
//!   `ch = cosh(sqrt(q) tau)` or `cos(sqrt(-q) tau)`, `sh = sinh(sqrt q tau)/sqrt q` or
//!   `sin(sqrt(-q) tau)/sqrt(-q)`: both are entire functions of `q`, so nothing blows up
//!   at critical damping (`q = 0`: `ch = 1`, `sh = tau`). For real roots they are
//!   evaluated as `e^{r_s tau}(1 + X/2)` and `-e^{r_s tau} X/(2 sqrt q)`,
//!   `X = expm1(-2 sqrt(q) tau)`, which neither overflows nor cancels.
//!
//! See `docs/propagator.md` for the derivations, the integrals, the proof of
//! [`Trajectory::bounds`] and the measured accuracy.

mod short;
#[cfg(test)]
mod short_tests;
mod terms;

use serde::{Deserialize, Serialize};

use short::Short;
pub(crate) use short::{LEN as SHORT_LEN, integrals_in_lanes};
pub use terms::Integrals;
use terms::{NT, RECIP, TAIL, hilbert_fixed, hilbert_square, hilbert_tail};

/// Largest `rho tau` handled by the Taylor series (`rho` = largest root modulus).
const TAYLOR_MAX: f64 = 1.0;
/// Largest `|z|` for which the `phi` functions are summed as series.
const PHI_SERIES_MAX: f64 = 1.0;
/// Relative widening of [`Trajectory::bounds`] that covers round-off (far above it).
const BOUND_REL_MARGIN: f64 = 1e-12;

/// `1/(n (n-1))` for `n = 2..NT + 2` (entries 0, 1 unused).
const RECIP2: [f64; NT + 3] = {
    let mut t = [0.0; NT + 3];
    let mut n = 2;
    while n <= NT + 2 {
        t[n] = 1.0 / (n * (n - 1)) as f64;
        n += 1;
    }
    t
};

/// `1/(n+3)!` for `n = 0..PHI_TERMS`, the Taylor coefficients of `phi_3`.
const PHI_TERMS: usize = 18;
const PHI3_COEF: [f64; PHI_TERMS] = {
    let mut t = [0.0; PHI_TERMS];
    let mut f = 6.0; // 3!
    let mut n = 0;
    while n < PHI_TERMS {
        t[n] = 1.0 / f;
        f *= (n + 4) as f64;
        n += 1;
    }
    t
};

/// How the plate's characteristic polynomial `M r^2 + eta r + k` is handled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Branch {
    /// `M = 0`: first order, one root `-k/eta`.
    FirstOrder,
    /// Real roots with `|r_slow| <= |r_fast| / 2` (includes `k = 0` and stiff plates).
    Separated,
    /// Complex, critical or near-critical real roots (`eta^2 - 4 M k < eta^2 / 9`), and `eta = 0`.
    Clustered,
}

/// Coefficients of `M y'' + eta y' + k y = a + b tau`, with the solution branch chosen once.
///
/// Fields not used by the branch are zero. Written and read as its fields without the
/// short path's and the enclosure's constants, which are derived again from `M`, `eta`, `k`, `rho`
/// when read.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "PlateFields", into = "PlateFields")]
pub struct LinearPlate {
    fields: PlateFields,
    /// The short path's constants ([`short`]).
    short: Short,
    /// The short-horizon enclosure's constants ([`Trajectory::bounds`]).
    reach: Reach,
}

/// `1/eta`, `1/(2M)`, `1/(2 eta)`, `1/(6M)` and `M/eta` (`+inf` or NaN for a zero mass or
/// viscosity, which the enclosure's `min` passes over), so that [`Trajectory::bounds`]
/// multiplies where it would divide: each within two ulps of the quotient, far inside the
/// enclosure's margin. One division (`1/eta`; `1/M` is the plate's own): the engine
/// classifies a plate whenever the attached count reaches a value it has not cached.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Reach {
    inv_eta: f64,
    inv_2m: f64,
    inv_2eta: f64,
    inv_6m: f64,
    m_over_eta: f64,
}

impl Reach {
    fn new(f: &PlateFields) -> Reach {
        let inv_eta = 1.0 / f.eta;
        let inv_m = if f.mass > 0.0 { f.inv_m } else { f64::INFINITY };
        Reach {
            inv_eta,
            inv_2m: 0.5 * inv_m,
            inv_2eta: 0.5 * inv_eta,
            inv_6m: inv_m * (1.0 / 6.0),
            m_over_eta: f.mass * inv_eta,
        }
    }
}

impl std::ops::Deref for LinearPlate {
    type Target = PlateFields;
    #[inline(always)]
    fn deref(&self) -> &PlateFields {
        &self.fields
    }
}

impl From<PlateFields> for LinearPlate {
    fn from(fields: PlateFields) -> Self {
        let short = Short::new(fields.mass, fields.eta, fields.k, fields.rho);
        LinearPlate { fields, short, reach: Reach::new(&fields) }
    }
}

impl From<LinearPlate> for PlateFields {
    fn from(p: LinearPlate) -> Self {
        p.fields
    }
}

/// The classified plate as written: [`LinearPlate`] without the short path's constants.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlateFields {
    mass: f64,
    eta: f64,
    k: f64,
    branch: Branch,
    /// Largest root modulus (`M > 0`), `k/eta` for `M = 0`.
    rho: f64,
    /// `1/M`, `eta/M`, `k/M` (`M > 0`).
    inv_m: f64,
    eta_m: f64,
    k_m: f64,
    /// Slow root (`FirstOrder`, `Separated`; also used by `Clustered` with real roots).
    r_s: f64,
    /// Fast root (`Separated`).
    r_f: f64,
    /// `1/mu` (`Separated`: `mu = (eta + sqrt disc)/2 = M |r_f|`; `FirstOrder`: `1/eta`).
    inv_mu: f64,
    /// `M / sqrt(disc)` (`Separated`).
    m_over_sq: f64,
    /// `m = -eta/(2M)`, `q = disc/(4 M^2)`, `w = sqrt|q|` (`Clustered`).
    m: f64,
    q: f64,
    w: f64,
    /// `1/k` (`Clustered`, and wherever `k > 0` for the bounds).
    inv_k: f64,
}

/// The trajectory from `(y0, v0)` under forcing `a + b tau` (see [`LinearPlate::trajectory`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trajectory {
    plate: LinearPlate,
    y0: f64,
    /// Initial velocity actually used (`(a - k y0)/eta` when `M = 0`).
    v0: f64,
    /// `f0 = a - k y0`: the forcing seen by `u = y - y0`.
    f0: f64,
    b: f64,
}

/// A trajectory's coefficients in its plate's branch, derived from `(v0, f0, b)` when an
/// evaluation leaves the Taylor range ([`Trajectory::coefs`]): the engine's events are so
/// close at large N that most pieces never need them, so a restart does not compute them.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Coefs {
    /// Slow + fast: `[sigma, g0, g1, c_f]` with `u = S + c_f e^{r_f tau}`,
    /// `S = sigma phi0 + g0 tau phi1 + g1 tau^2 phi2`.
    /// Clustered: `[c0, c1, e1, e2]` with `u = c0 + c1 tau + e1 u1 + e2 u2`.
    c: [f64; 4],
    /// Derived: slow + fast: `[S'(0), r_f c_f]`; clustered: `[e1 m + e2, e1 q + e2 m]`
    /// (so that `u' = c1 + d0 u1 + d1 u2`).
    d: [f64; 2],
}

/// `(phi0, phi1, phi2, phi3)(z)` for `z <= 0` (any finite `z`; `-inf` gives the limits).
#[inline]
fn phis(z: f64) -> (f64, f64, f64, f64) {
    let az = z.abs();
    if az <= PHI_SERIES_MAX {
        // Truncation error |z|^N/(N+3)! against phi3 >= 0.13: below 1e-18 relative with
        // 9 terms up to |z| = 1/16, 11 up to 1/4, 18 up to 1.
        let nt = if az <= 0.0625 {
            9
        } else if az <= 0.25 {
            11
        } else {
            PHI_TERMS
        };
        let mut p3 = PHI3_COEF[nt - 1];
        let mut n = nt - 1;
        while n > 0 {
            n -= 1;
            p3 = p3 * z + PHI3_COEF[n];
        }
        let p2 = 0.5 + z * p3;
        let p1 = 1.0 + z * p2;
        let p0 = 1.0 + z * p1;
        (p0, p1, p2, p3)
    } else {
        let iz = 1.0 / z;
        let p0 = z.exp();
        let p1 = (p0 - 1.0) * iz;
        let p2 = (p1 - 1.0) * iz;
        let p3 = (p2 - 0.5) * iz;
        (p0, p1, p2, p3)
    }
}

impl LinearPlate {
    /// Classifies `M y'' + eta y' + k y = forcing`.
    ///
    /// Panics unless `mass, eta, k` are finite and non-negative with `mass + eta > 0`.
    pub fn new(mass: f64, eta: f64, k: f64) -> LinearPlate {
        assert!(
            mass.is_finite() && eta.is_finite() && k.is_finite() && mass >= 0.0 && eta >= 0.0 && k >= 0.0,
            "LinearPlate: mass, eta, k must be finite and >= 0 (got {mass}, {eta}, {k})"
        );
        assert!(mass > 0.0 || eta > 0.0, "LinearPlate: mass and eta are both zero");
        LinearPlate::from(PlateFields::classify(mass, eta, k))
    }
}

impl PlateFields {
    /// The classification of a valid plate (checked by [`LinearPlate::new`]).
    fn classify(mass: f64, eta: f64, k: f64) -> PlateFields {
        let mut p = PlateFields {
            mass,
            eta,
            k,
            branch: Branch::FirstOrder,
            rho: 0.0,
            inv_m: 0.0,
            eta_m: 0.0,
            k_m: 0.0,
            r_s: 0.0,
            r_f: 0.0,
            inv_mu: 0.0,
            m_over_sq: 0.0,
            m: 0.0,
            q: 0.0,
            w: 0.0,
            inv_k: if k > 0.0 { 1.0 / k } else { 0.0 },
        };
        if mass == 0.0 {
            p.inv_mu = 1.0 / eta;
            p.r_s = -k * p.inv_mu;
            p.rho = -p.r_s;
            return p;
        }
        p.inv_m = 1.0 / mass;
        p.eta_m = eta * p.inv_m;
        p.k_m = k * p.inv_m;
        // disc = eta^2 - 4 M k with the product 4 M k carried exactly (compensated).
        let pm = 4.0 * mass * k;
        let pe = (4.0 * mass).mul_add(k, -pm);
        let disc = eta.mul_add(eta, -pm) - pe;
        let eta2 = eta * eta;
        if disc >= eta2 / 9.0 && eta > 0.0 {
            let sq = disc.sqrt();
            let mu = 0.5 * (eta + sq);
            p.branch = Branch::Separated;
            p.inv_mu = 1.0 / mu;
            p.r_s = -k * p.inv_mu;
            p.r_f = -mu * p.inv_m;
            p.rho = -p.r_f;
            p.m_over_sq = mass / sq;
        } else {
            p.branch = Branch::Clustered;
            p.m = -0.5 * p.eta_m;
            p.q = disc * (0.25 * p.inv_m * p.inv_m);
            p.w = p.q.abs().sqrt();
            if p.q > 0.0 {
                let sq = disc.sqrt();
                p.r_s = -2.0 * k / (eta + sq);
                p.rho = p.w - p.m;
            } else {
                p.rho = p.k_m.sqrt();
            }
        }
        p
    }
}

impl LinearPlate {
    /// The branch chosen for this plate.
    pub fn branch(&self) -> Branch {
        self.branch
    }

    /// `(M, eta, k)`.
    pub fn coefficients(&self) -> (f64, f64, f64) {
        (self.mass, self.eta, self.k)
    }

    /// Largest root modulus of `M r^2 + eta r + k` (`k/eta` for `M = 0`): `1/rho` is the
    /// shortest time scale of the plate.
    pub fn rho(&self) -> f64 {
        self.rho
    }

    /// The trajectory from `(y0, v0)` under forcing `a + b tau`.
    /// For `M = 0`, `v0` is ignored (the velocity is `(a + b tau - k y)/eta`).
    #[inline]
    pub fn trajectory(&self, y0: f64, v0: f64, a: f64, b: f64) -> Trajectory {
        let mut t = Trajectory { plate: *self, y0, v0, f0: 0.0, b };
        t.restart(self, y0, v0, a, b);
        t
    }
}

impl Trajectory {
    /// Makes `self` the trajectory of `plate` from `(y0, v0)` under forcing `a + b tau`,
    /// in place (the same result as [`LinearPlate::trajectory`], without building and
    /// moving a new value: the engine restarts its trajectory at every event).
    #[inline]
    pub fn restart(&mut self, plate: &LinearPlate, y0: f64, v0: f64, a: f64, b: f64) {
        self.plate = *plate;
        self.restart_on_plate(y0, v0, a, b);
    }

    /// [`Trajectory::restart`] on the plate this trajectory already has: only the initial
    /// state and the forcing are written (a caller that keeps one trajectory per plate
    /// restarts without copying the plate).
    #[inline]
    pub fn restart_on_plate(&mut self, y0: f64, v0: f64, a: f64, b: f64) {
        let p = &self.plate;
        let f0 = a - p.k * y0;
        // M = 0: the velocity follows from the forces, (a - k y0) / eta.
        self.v0 = if p.branch == Branch::FirstOrder { f0 * p.inv_mu } else { v0 };
        self.y0 = y0;
        self.f0 = f0;
        self.b = b;
    }

    /// The branch coefficients of this trajectory (the same numbers whenever asked).
    #[inline]
    fn coefs(&self) -> Coefs {
        let p = &self.plate;
        let (v0, f0, b) = (self.v0, self.f0, self.b);
        match p.branch {
            Branch::FirstOrder => {
                let g0 = v0;
                let g1 = b * p.inv_mu;
                Coefs { c: [0.0, g0, g1, 0.0], d: [g0, 0.0] }
            }
            Branch::Separated => {
                // (D - r_s) u = g0 + g1 tau + (v0 - g0) e^{r_f tau}.
                let g1 = b * p.inv_mu;
                let g0 = (f0 - p.mass * g1) * p.inv_mu;
                let cf = -(v0 - g0) * p.m_over_sq;
                let sigma = -cf;
                Coefs { c: [sigma, g0, g1, cf], d: [p.r_s * sigma + g0, p.r_f * cf] }
            }
            Branch::Clustered => {
                let c1 = b * p.inv_k;
                let c0 = (f0 - p.eta * c1) * p.inv_k;
                let e1 = -c0;
                let e2 = (v0 - c1) - p.m * e1;
                Coefs { c: [c0, c1, e1, e2], d: [e1 * p.m + e2, e1 * p.q + e2 * p.m] }
            }
        }
    }
}

/// Taylor terms `t_n = u^(n)(0) tau^n / n!`, `n = 0..len` (`t_0 = 0`). The buffer is left
/// uninitialised beyond `len` (zero-filling all `NT` entries cost a tenth of an event at
/// large N); only the written prefix is ever read.
struct Series {
    t: [std::mem::MaybeUninit<f64>; NT],
    len: usize,
}

impl Series {
    fn new() -> Series {
        Series { t: [const { std::mem::MaybeUninit::uninit() }; NT], len: 0 }
    }
    /// Writes terms `0..6`.
    #[inline]
    fn set_head(&mut self, head: [f64; 6]) {
        for (slot, v) in self.t.iter_mut().zip(head) {
            *slot = std::mem::MaybeUninit::new(v);
        }
        self.len = 6;
    }
    /// Writes term `n`; terms must be written in order `0, 1, 2, ...`.
    #[inline]
    fn push(&mut self, n: usize, v: f64) {
        debug_assert_eq!(n, self.len);
        self.t[n] = std::mem::MaybeUninit::new(v);
        self.len = n + 1;
    }
    /// The written terms `t_0 .. t_{len-1}`.
    #[inline]
    fn terms(&self) -> &[f64] {
        // SAFETY: `push` writes entries in order and `len` counts them, so `0..len` are initialised.
        unsafe { std::slice::from_raw_parts(self.t.as_ptr().cast::<f64>(), self.len) }
    }
    #[inline]
    fn terms_mut(&mut self) -> &mut [f64] {
        // SAFETY: as in `terms`.
        unsafe { std::slice::from_raw_parts_mut(self.t.as_mut_ptr().cast::<f64>(), self.len) }
    }
}

/// A piece's integrals ([`Integrals`]), or the short path's polynomial `c_0 .. c_7` to
/// compute them from when they are read ([`Trajectory::at_maybe_terms`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Terms {
    Integrals(Integrals),
    Short([f64; SHORT_LEN]),
}

impl Terms {
    /// The integrals over `[0, h]` with drift `s` (`h`, `s` those the terms were made with).
    #[inline(always)]
    pub fn integrals(&self, h: f64, s: f64) -> Integrals {
        match self {
            Terms::Integrals(i) => *i,
            Terms::Short(c) => Short::integrals(c, h, s),
        }
    }
}

impl Trajectory {
    /// The plate this trajectory belongs to.
    pub fn plate(&self) -> &LinearPlate {
        &self.plate
    }

    /// `y(0)`.
    pub fn y0(&self) -> f64 {
        self.y0
    }

    /// `y'(0)` as used (`(a - k y0)/eta` when `M = 0`).
    pub fn v0(&self) -> f64 {
        self.v0
    }

    /// The short path's polynomial coefficients at `tau > 0`, if it is exact there ([`short`]).
    #[inline(always)]
    fn short(&self, tau: f64) -> Option<[f64; short::DEGREE + 1]> {
        self.plate.short.coefficients(tau, self.v0, self.f0, self.b)
    }

    #[inline]
    fn use_taylor(&self, tau: f64) -> bool {
        self.plate.mass > 0.0 && self.plate.rho * tau <= TAYLOR_MAX
    }

    /// The Taylor series of `u` at `tau` (requires `M > 0`, `rho tau <= 1`): returns
    /// `(u, u')`; with `KEEP` the terms `t_n = u^(n)(0) tau^n / n!` are also stored in `ser`
    /// and `i1 = sum t_n / (n + 1)` (so that `int_0^tau u = tau i1`) is returned.
    ///
    /// Terms come from `t_n = -(A/n) t_{n-1} - (B/(n(n-1))) t_{n-2}`, `A = eta tau/M`,
    /// `B = k tau^2/M` (`n >= 4`), two per step: `t_{n+1} = (a2 a1 - b2) t_{n-1} + a2 b1 t_{n-2}`
    /// does not wait for `t_n`, which halves the latency of the loop. The sum stops when a
    /// bound of the remainder is below `2^-56` of `sum n |t_n|` (`n >= 2`): the next two terms
    /// are bounded by the recurrence in absolute values (`c1`, `c2`), and since `A <= 2 rho tau
    /// <= 2` and `B <= (rho tau)^2 <= 1`, every later term is at most `0.27` times the larger of
    /// the two before it, so the weighted remainder is below `4 (n + 3) (c1 + c2)`, `n` the
    /// last term computed (docs/propagator.md). The
    /// arithmetic runs with and without `KEEP`, so `u, u'` agree bit for bit.
    #[inline(always)]
    fn taylor<const KEEP: bool>(&self, tau: f64, ser: &mut Series) -> (f64, f64, f64) {
        let (u, du, i1, _) = self.taylor_head::<KEEP>(tau, ser);
        (u, du, i1)
    }

    /// [`Trajectory::taylor`], and `Some(t_1 .. t_5)` when the sum stopped after them (the
    /// common case at large N), in which case `ser` was not written: the caller has the
    /// terms in registers.
    #[inline(always)]
    fn taylor_head<const KEEP: bool>(&self, tau: f64, ser: &mut Series) -> (f64, f64, f64, Option<[f64; 5]>) {
        let p = &self.plate;
        let inv_tau = 1.0 / tau;
        let aa = p.eta_m * tau;
        let bb = p.k_m * tau * tau;
        let t1 = self.v0 * tau;
        let t2 = (self.f0 - p.eta * self.v0) * p.inv_m * (0.5 * tau * tau);
        let t3 = self.b * p.inv_m * (tau * tau * tau * RECIP[6]) - (aa * t2 * RECIP[3] + bb * t1 * RECIP[6]);
        // The first step (t4, t5) in straight-line code: at large N the steps are so short
        // (rho tau ~ 1e-5) that the sum usually stops here.
        let (a1, b1) = (aa * RECIP[4], bb * RECIP2[4]);
        let (a2, b2) = (aa * RECIP[5], bb * RECIP2[5]);
        let t4 = -(t3 * a1 + t2 * b1);
        let t5 = t3 * (a2 * a1 - b2) + t2 * (a2 * b1);
        let mut u = (t2 + t3) + (t4 + t5);
        let mut du = (2.0 * t2 + 3.0 * t3) + (4.0 * t4 + 5.0 * t5);
        let mut dabs = (2.0 * t2.abs() + 3.0 * t3.abs()) + (4.0 * t4.abs() + 5.0 * t5.abs());
        let mut i1 = if KEEP {
            (t1 * RECIP[2] + t2 * RECIP[3]) + (t3 * RECIP[4] + (t4 * RECIP[5] + t5 * RECIP[6]))
        } else {
            0.0
        };
        let c1 = (aa * RECIP[6]) * t5.abs() + (bb * RECIP2[6]) * t4.abs();
        let c2 = (aa * RECIP[7]) * c1 + (bb * RECIP2[7]) * t5.abs();
        let long = 4.0 * 8.0 * (c1 + c2) > TAIL * dabs;
        if long {
            if KEEP {
                ser.set_head([0.0, t1, t2, t3, t4, t5]);
            }
            let (mut tm1, mut tm2) = (t5, t4);
            let mut n = 6;
            while n + 1 < NT {
                let (a1, b1) = (aa * RECIP[n], bb * RECIP2[n]);
                let (a2, b2) = (aa * RECIP[n + 1], bb * RECIP2[n + 1]);
                let tn = -(tm1 * a1 + tm2 * b1);
                let tn1 = tm1 * (a2 * a1 - b2) + tm2 * (a2 * b1);
                if KEEP {
                    ser.push(n, tn);
                    ser.push(n + 1, tn1);
                    i1 += tn * RECIP[n + 1] + tn1 * RECIP[n + 2];
                }
                let (nf, nf1) = (n as f64, (n + 1) as f64);
                u += tn + tn1;
                du += nf * tn + nf1 * tn1;
                dabs += nf * tn.abs() + nf1 * tn1.abs();
                // Bounds of the next two terms.
                let c1 = (aa * RECIP[n + 2]) * tn1.abs() + (bb * RECIP2[n + 2]) * tn.abs();
                let c2 = (aa * RECIP[n + 3]) * c1 + (bb * RECIP2[n + 3]) * tn1.abs();
                n += 2;
                if 4.0 * (n + 2) as f64 * (c1 + c2) <= TAIL * dabs {
                    break;
                }
                tm2 = tn;
                tm1 = tn1;
            }
        }
        (t1 + u, self.v0 + du * inv_tau, i1, (!long).then_some([t1, t2, t3, t4, t5]))
    }

    /// `(u, u')` at `tau > 0` from the Taylor series.
    #[inline]
    fn taylor_at(&self, tau: f64) -> (f64, f64) {
        let (u, du, _) = self.taylor::<false>(tau, &mut Series::new());
        (u, du)
    }

    /// `(u, u', integrals)` at `h > 0` from the Taylor series.
    #[inline(always)]
    fn taylor_with_integrals(&self, h: f64, s: f64) -> (f64, f64, Integrals) {
        let mut ser = Series::new();
        let (u, du, i1, head) = self.taylor_head::<true>(h, &mut ser);
        // w = u - s tau: only the linear term changes; t_0 = 0, so the sum starts at n = 1.
        let i2 = match head {
            // Six terms (the common case): the same sums as `hilbert_tail`, in registers.
            Some([t1, t2, t3, t4, t5]) => hilbert_fixed::<6>(&[0.0, t1 - s * h, t2, t3, t4, t5], h),
            None => {
                ser.terms_mut()[1] -= s * h;
                hilbert_tail(ser.terms(), h)
            }
        };
        (u, du, Integrals { i1: i1 * h, i2 })
    }

    /// `(y(tau), y'(tau))` for `tau >= 0`. Always inlined: at large N every event evaluates
    /// the short Taylor path, and a caller that reads only `y` (a thinning candidate) drops
    /// the velocity's sums.
    #[inline(always)]
    pub fn at(&self, tau: f64) -> (f64, f64) {
        debug_assert!(tau >= 0.0, "Trajectory::at: tau must be >= 0");
        if tau <= 0.0 {
            return (self.y0, self.v0);
        }
        if let Some(c) = self.short(tau) {
            let (u, du) = Short::state(&c, tau);
            return (self.y0 + u, du);
        }
        if self.use_taylor(tau) {
            let (u, du) = self.taylor_at(tau);
            return (self.y0 + u, du);
        }
        let (u, up) = match self.plate.branch {
            Branch::FirstOrder | Branch::Separated => self.slow_fast_at(tau),
            Branch::Clustered => {
                let (u1, u2, _) = self.clustered_basis(tau);
                self.clustered_at(tau, u1, u2)
            }
        };
        (self.y0 + u, up)
    }

    #[inline]
    fn slow_fast_at(&self, tau: f64) -> (f64, f64) {
        let p = &self.plate;
        let Coefs { c: [sigma, g0, g1, cf], d } = self.coefs();
        let (f0, f1, f2, _) = phis(p.r_s * tau);
        let mut u = sigma * f0 + tau * (g0 * f1 + g1 * tau * f2);
        let mut up = d[0] * f0 + g1 * tau * f1;
        if p.branch == Branch::Separated {
            let ef = (p.r_f * tau).exp();
            u += cf * ef;
            up += d[1] * ef;
        }
        (u, up)
    }

    /// `(u1, u2, e^{2 m tau})`: `u1 = e^{m tau} ch`, `u2 = e^{m tau} sh`.
    #[inline]
    fn clustered_basis(&self, tau: f64) -> (f64, f64, f64) {
        let p = &self.plate;
        if p.q > 0.0 {
            let es = (p.r_s * tau).exp();
            let x = (-2.0 * p.w * tau).exp_m1();
            (es * (1.0 + 0.5 * x), -es * x / (2.0 * p.w), es * es * (1.0 + x))
        } else if p.q < 0.0 {
            let e = (p.m * tau).exp();
            let (sn, cs) = (p.w * tau).sin_cos();
            (e * cs, e * sn / p.w, e * e)
        } else {
            let e = (p.m * tau).exp();
            (e, e * tau, e * e)
        }
    }

    #[inline]
    fn clustered_at(&self, tau: f64, u1: f64, u2: f64) -> (f64, f64) {
        let Coefs { c: [c0, c1, e1, e2], d } = self.coefs();
        let u = c0 + c1 * tau + (e1 * u1 + e2 * u2);
        let up = c1 + (d[0] * u1 + d[1] * u2);
        (u, up)
    }

    /// `at(h)` and `integrals(h, s)` in one call, with identical results (the short-interval
    /// Taylor path, where large-N engines spend their time, shares the set-up). Inlined: a
    /// caller that drops the integrals (an observer that takes no segments) does not
    /// compute them.
    #[inline(always)]
    pub fn at_with_integrals(&self, h: f64, s: f64) -> (f64, f64, Integrals) {
        let (y, v, terms) = self.at_maybe_terms(h, s, true);
        (y, v, terms.integrals(h, s))
    }

    /// [`Trajectory::at_with_integrals`] when `integrals` (a constant at the call site, or a
    /// flag that changes rarely: a predictable branch), else
    /// [`Trajectory::at`] with zero integrals: the same state bit for bit either way, and
    /// nothing of the integrals computed for a caller that does not read them.
    #[inline(always)]
    pub fn at_maybe_integrals(&self, h: f64, s: f64, integrals: bool) -> (f64, f64, Integrals) {
        let (y, v, terms) = self.at_maybe_terms(h, s, integrals);
        (y, v, terms.integrals(h, s))
    }

    /// [`Trajectory::at_maybe_integrals`] with the integrals left as [`Terms`]: on the short
    /// path its polynomial's coefficients, from which [`Terms::integrals`] (or
    /// `integrals_in_lanes`, several pieces at once) gives the same bits later.
    #[inline(always)]
    pub fn at_maybe_terms(&self, h: f64, s: f64, integrals: bool) -> (f64, f64, Terms) {
        if !integrals {
            let (y, v) = self.at(h);
            return (y, v, Terms::Integrals(Integrals { i1: 0.0, i2: 0.0 }));
        }
        if h > 0.0
            && let Some(c) = self.short(h)
        {
            let (u, du) = Short::state(&c, h);
            return (self.y0 + u, du, Terms::Short(c));
        }
        if h > 0.0 && self.use_taylor(h) {
            let (u, du, ints) = self.taylor_with_integrals(h, s);
            return (self.y0 + u, du, Terms::Integrals(ints));
        }
        let (y, v) = self.at(h);
        (y, v, Terms::Integrals(self.integrals(h, s)))
    }

    /// Integrals over `[0, h]` used for exact time averages:
    /// `i1 = int_0^h (y(tau) - y0) dtau`, `i2 = int_0^h (y(tau) - y0 - s tau)^2 dtau`.
    ///
    /// Both are accurate relative to the natural scale of their integrand (the sizes of the
    /// separate contributions of `v0 - s`, `a - k y0 - eta s`, `b - k s` to `y - y0 - s tau`);
    /// `i2 >= 0` always. Uses the same transcendental calls as `at(h)`.
    pub fn integrals(&self, h: f64, s: f64) -> Integrals {
        debug_assert!(h >= 0.0, "Trajectory::integrals: h must be >= 0");
        if h <= 0.0 {
            return Integrals { i1: 0.0, i2: 0.0 };
        }
        if let Some(c) = self.short(h) {
            return Short::integrals(&c, h, s);
        }
        if self.use_taylor(h) {
            return self.taylor_with_integrals(h, s).2;
        }
        match self.plate.branch {
            Branch::FirstOrder | Branch::Separated => self.slow_fast_integrals(h, s),
            Branch::Clustered => self.clustered_integrals(h, s),
        }
    }

    fn slow_fast_integrals(&self, h: f64, s: f64) -> Integrals {
        let p = &self.plate;
        let Coefs { c: [sigma, g0, g1, cf], .. } = self.coefs();
        let r = p.r_s;
        let z = r * h;
        let (f0, f1, f2, f3) = phis(z);
        let mut i1 = h * (sigma * f1 + h * (g0 * f2 + g1 * h * f3));
        // w = u - s tau = S_w + c_f e^{r_f tau}, S_w' = r S_w + g0w + g1w tau.
        let g0w = g0 - s;
        let g1w = g1 + r * s;
        let iss = if z.abs() <= PHI_SERIES_MAX {
            // Taylor coefficients of S_w in (tau/h): converge at least like 1/n!.
            let mut a = [0.0; NT];
            let s1 = r * sigma + g0w;
            a[0] = sigma;
            a[1] = s1 * h;
            a[2] = (r * s1 + g1w) * (0.5 * h * h);
            let mut sabs = a[0].abs() + a[1].abs() + a[2].abs();
            let mut n = 3;
            while n < NT {
                a[n] = a[n - 1] * z * RECIP[n];
                sabs += a[n].abs();
                n += 1;
                if a[n - 1].abs() <= TAIL * sabs {
                    break;
                }
            }
            hilbert_square(&a[..n], h, 0)
        } else {
            // S_w = P + c e^{r tau}, P = p0 + p1 tau (well conditioned: |r h| > 1).
            let ir = 1.0 / r;
            let p1 = -g1w * ir;
            let p0 = (p1 - g0w) * ir;
            let c = sigma - p0;
            let lam = -r;
            let il = 1.0 / lam;
            let x = lam * h;
            let ex = f0;
            let e0 = (1.0 - ex) * il;
            let e1 = (1.0 - ex * (1.0 + x)) * il * il;
            let e2 = 0.5 * (1.0 - ex * ex) * il;
            let pm = p0 + 0.5 * p1 * h;
            let pp = h * (pm * pm + p1 * p1 * h * h * RECIP[12]);
            (pp + 2.0 * c * (p0 * e0 + p1 * e1) + c * c * e2).max(0.0)
        };
        let mut i2 = iss;
        if p.branch == Branch::Separated {
            let lf = -p.r_f;
            let ilf = 1.0 / lf;
            let xf = lf * h;
            let ef = (p.r_f * h).exp();
            let if0 = (1.0 - ef) * ilf;
            let if1 = (1.0 - ef * (1.0 + xf)) * ilf * ilf;
            let if2 = 0.5 * (1.0 - ef * ef) * ilf;
            i1 += cf * if0;
            let sw_h = sigma * f0 + h * (g0w * f1 + g1w * h * f2);
            let isf = (sw_h * ef - sigma - g0w * if0 - g1w * if1) / (r + p.r_f);
            i2 = (i2 + cf * (2.0 * isf + cf * if2)).max(0.0);
        }
        Integrals { i1, i2 }
    }

    fn clustered_integrals(&self, h: f64, s: f64) -> Integrals {
        let p = &self.plate;
        let Coefs { c: [c0, c1, e1, e2], d } = self.coefs();
        let (u1, u2, e2m) = self.clustered_basis(h);
        let zh = e1 * u1 + e2 * u2;
        let zph = d[0] * u1 + d[1] * u2;
        let dz = zh - e1;
        let dzp = zph - d[0];
        // int z and int tau z from the homogeneous equation (well conditioned here: rho h > 1
        // and k >= M rho^2 / 2).
        let iz = -(p.mass * dzp + p.eta * dz) * p.inv_k;
        let itz = (p.mass * (dz - h * zph) + p.eta * (iz - h * zh)) * p.inv_k;
        let i1 = h * (c0 + 0.5 * c1 * h) + iz;
        // int e^{2 m tau}.
        let x2 = 2.0 * p.m * h;
        let ie2 = if x2.abs() <= PHI_SERIES_MAX { h * phis(x2).1 } else { (e2m - 1.0) / (2.0 * p.m) };
        // Gram matrix of (u1, u2) from d/dtau (u1^2, u1 u2, u2^2) and u1^2 - q u2^2 = e^{2 m tau}.
        let zz = u2 * u2;
        let bb = u1 * u2;
        let izz = (p.m * zz - bb + ie2) * (0.5 / p.k_m);
        let ibb = 0.5 * (zz - 2.0 * p.m * izz);
        let iaa = ie2 + p.q * izz;
        let i_zsq = (e1 * e1 * iaa + 2.0 * e1 * e2 * ibb + e2 * e2 * izz).max(0.0);
        let c1w = c1 - s;
        let pm = c0 + 0.5 * c1w * h;
        let ipp = h * (pm * pm + c1w * c1w * h * h * RECIP[12]);
        let ipz = c0 * iz + c1w * itz;
        Integrals { i1, i2: (ipp + 2.0 * ipz + i_zsq).max(0.0) }
    }

    /// How far a force `g(tau)` with `|g| <= 1`, added to this plate's equation from a state
    /// it shares with another path, moves it from that path over `[0, h]`: the difference
    /// `d` obeys `M d'' + eta d' + k d = g`, `d(0) = d'(0) = 0`, so by the short-horizon
    /// enclosure of [`Trajectory::bounds`] (`v0 = f0 = b = 0`, `g` in place of the forcing)
    /// `sup |d| <= c2 / (1 - k c2) <= c2 (1 + 2 k c2)` when `k c2 <= 1/2`, times `1 + 1e-12`
    /// for round-off; `+inf` otherwise, or for a NaN `h`.
    #[inline]
    pub fn response(&self, h: f64) -> f64 {
        if h.is_nan() {
            return f64::INFINITY;
        }
        let (p, h) = (&self.plate, h.max(0.0));
        let r = &p.reach;
        let c2 = (h * r.inv_eta).min(h * h * r.inv_2m);
        let kc2 = p.k * c2;
        if kc2 <= 0.5 { c2 * (1.0 + 2.0 * kc2) * (1.0 + BOUND_REL_MARGIN) } else { f64::INFINITY }
    }

    /// Proven bounds `lo <= y(tau) <= hi` for all `tau` in `[0, h]` (loose, never wrong).
    ///
    /// The enclosure is the intersection of two independent ones (see `docs/propagator.md`):
    ///
    /// * **Short horizon** (used when `k c2 <= 1/2`): write the equation as
    ///   `M v' + eta v = F(tau) = f0 + b tau - k (y - y0)`. With the kernel
    ///   `H(t) = (1 - e^{-eta t/M})/eta >= 0`, `H <= min(t/M, 1/eta)`,
    ///   `y - y0 = v0 int_0^tau e^{-eta t/M} dt + int_0^tau H(tau - x) F(x) dx`, so
    ///   `y - y0 ∈ hull(0, v0 cv) + hull(0, f0 c2) + hull(0, b c3) ± k c2 D` with
    ///   `cv = min(h, M/eta)` (0 for `M = 0`), `c2 = min(h/eta, h^2/(2M))`,
    ///   `c3 = min(h^2/(2 eta), h^3/(6 M))` and `D = sup |y - y0|`, which the same inequality
    ///   bounds by `D <= (|v0| cv + |f0| c2 + |b| c3) / (1 - k c2)`, itself at most that sum
    ///   times `1 + 2 k c2` (used: a product, not a quotient).
    /// * **Energy** (`k > 0`): `y = y0 + c0 + c1 tau + z` with `z` homogeneous. The energy
    ///   `E = M z'^2/2 + k z^2/2` has `E' = -eta z'^2 <= 0`, so `|z| <= sqrt(z0^2 + M z0'^2/k)`.
    ///   For `M = 0`, `z = z0 e^{r tau}` lies between 0 and `z0`; for separated real roots
    ///   `z = sigma_z e^{r_s tau} + c_f e^{r_f tau}` lies in `hull(0, sigma_z) + hull(0, c_f)`.
    ///
    /// The result is widened by `1e-12` of the magnitudes involved (covers round-off with a
    /// wide margin) plus `4 eps (|y0| + ...)` for the final additions.
    pub fn bounds(&self, h: f64) -> (f64, f64) {
        let p = &self.plate;
        let h = h.max(0.0);
        let (y0, v0, f0, b, k) = (self.y0, self.v0, self.f0, self.b, p.k);
        let mut lo = f64::NEG_INFINITY;
        let mut hi = f64::INFINITY;
        // Short-horizon enclosure.
        let r = &p.reach;
        let cv = if p.mass > 0.0 { h.min(r.m_over_eta) } else { 0.0 };
        let h2 = h * h;
        let c2 = (h * r.inv_eta).min(h2 * r.inv_2m);
        let c3 = (h2 * r.inv_2eta).min(h2 * h * r.inv_6m);
        let kc2 = k * c2;
        if kc2 <= 0.5 {
            let (tv, tf, tb) = (v0 * cv, f0 * c2, b * c3);
            let mag = tv.abs() + tf.abs() + tb.abs();
            // `mag / (1 - kc2) <= mag (1 + 2 kc2)` for `kc2 <= 1/2` (the chord of a convex
            // function): a product where a quotient would wait.
            let d = mag * (1.0 + 2.0 * kc2);
            let kd = kc2 * d;
            let dlo = tv.min(0.0) + tf.min(0.0) + tb.min(0.0) - kd;
            let dhi = tv.max(0.0) + tf.max(0.0) + tb.max(0.0) + kd;
            let margin = BOUND_REL_MARGIN * (mag + kd) + 4.0 * f64::EPSILON * (y0.abs() + mag + kd);
            lo = y0 + dlo - margin;
            hi = y0 + dhi + margin;
        }
        // Energy / decomposition enclosure.
        if k > 0.0 {
            let c1 = b * p.inv_k;
            let c0 = (f0 - p.eta * c1) * p.inv_k;
            let z0 = -c0;
            let (zlo, zhi, zmag) = if p.mass == 0.0 {
                (z0.min(0.0), z0.max(0.0), z0.abs())
            } else {
                let z0p = v0 - c1;
                let r = (z0 * z0 + z0p * z0p * p.mass * p.inv_k).sqrt();
                let (mut zl, mut zh) = (-r, r);
                let mut mag = r + z0p.abs() * (p.mass * p.inv_k).sqrt();
                if p.branch == Branch::Separated {
                    let cf = self.coefs().c[3];
                    let sz = z0 - cf;
                    zl = zl.max(sz.min(0.0) + cf.min(0.0));
                    zh = zh.min(sz.max(0.0) + cf.max(0.0));
                    mag += sz.abs() + cf.abs();
                }
                (zl, zh, mag)
            };
            let plo = c0 + (c1 * h).min(0.0);
            let phi = c0 + (c1 * h).max(0.0);
            let mag = c0.abs() + (c1 * h).abs() + zmag + (f0.abs() + p.eta * c1.abs()) * p.inv_k + b.abs() * p.inv_k;
            let margin = BOUND_REL_MARGIN * mag + 4.0 * f64::EPSILON * (y0.abs() + mag);
            lo = lo.max(y0 + plo + zlo - margin);
            hi = hi.min(y0 + phi + zhi + margin);
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phis_match_definitions() {
        for &z in &[-1e-3, -0.3, -0.999, -1.001, -3.0, -40.0] {
            let (p0, p1, p2, p3) = phis(z);
            let e: f64 = z;
            assert!((p0 - e.exp()).abs() < 1e-15);
            assert!((p1 - e.exp_m1() / z).abs() < 1e-15);
            let q2 = (e.exp_m1() - z) / (z * z);
            let q3 = (e.exp_m1() - z - 0.5 * z * z) / (z * z * z);
            if z.abs() > 0.2 {
                assert!((p2 - q2).abs() < 1e-13, "{z}: {p2} {q2}");
                assert!((p3 - q3).abs() < 1e-12, "{z}: {p3} {q3}");
            }
        }
        assert_eq!(phis(0.0), (1.0, 1.0, 0.5, 1.0 / 6.0));
        let (p0, p1, p2, p3) = phis(-1e300);
        assert!(p0 == 0.0 && p1 > 0.0 && p2 > 0.0 && p3 > 0.0);
    }

    #[test]
    fn branches() {
        assert_eq!(LinearPlate::new(0.0, 1.0, 1.0).branch(), Branch::FirstOrder);
        assert_eq!(LinearPlate::new(1.0, 10.0, 1.0).branch(), Branch::Separated);
        assert_eq!(LinearPlate::new(1.0, 1.0, 0.0).branch(), Branch::Separated);
        assert_eq!(LinearPlate::new(1.0, 2.0, 1.0).branch(), Branch::Clustered);
        assert_eq!(LinearPlate::new(1.0, 0.0, 1.0).branch(), Branch::Clustered);
        assert_eq!(LinearPlate::new(1.0, 0.0, 0.0).branch(), Branch::Clustered);
    }

    #[test]
    fn initial_state() {
        for &(m, e, k) in &[(1.0, 10.0, 1.0), (1.0, 2.0, 1.0), (1.0, 0.0, 3.0), (0.0, 2.0, 3.0)] {
            let t = LinearPlate::new(m, e, k).trajectory(0.5, -0.25, 2.0, 1.0);
            let (y, v) = t.at(0.0);
            assert_eq!(y, 0.5);
            if m > 0.0 {
                assert_eq!(v, -0.25);
            } else {
                assert_eq!(v, (2.0 - k * 0.5) / e);
            }
        }
    }

    /// An observer without segments gets the same plate state bit for bit, whatever the
    /// branch (the Taylor path with its six-term integrals in registers, its longer sums,
    /// and the closed forms).
    #[test]
    fn state_without_integrals_is_the_same() {
        for &(m, eta, k) in &[(75.0, 75.0, 180.0), (1.0, 0.0, 4.0), (1e-6, 1.0, 1e3), (0.0, 2.0, 3.0), (2.0, 4.0, 2.0)]
        {
            let tr = LinearPlate::new(m, eta, k).trajectory(0.3, -0.7, 5.0, 1.5);
            for &h in &[1e-12, 1e-7, 1e-5, 1e-3, 0.05, 0.7, 3.0, 40.0] {
                let (y, v, i) = tr.at_maybe_integrals(h, 0.5, true);
                let (y2, v2, j) = tr.at_maybe_integrals(h, 0.5, false);
                assert_eq!((y.to_bits(), v.to_bits()), (y2.to_bits(), v2.to_bits()), "m {m} eta {eta} k {k} h {h}");
                assert_eq!((i, j.i1, j.i2), (tr.integrals(h, 0.5), 0.0, 0.0));
            }
        }
    }

    #[test]
    fn fused_call_equals_separate_calls() {
        for &(m, eta, k) in &[(75.0, 75.0, 180.0), (1.0, 0.0, 4.0), (1e-6, 1.0, 1e3), (0.0, 2.0, 3.0), (2.0, 4.0, 2.0)]
        {
            let p = LinearPlate::new(m, eta, k);
            let tr = p.trajectory(0.3, -0.7, 5.0, 1.5);
            for &h in &[1e-9, 1e-5, 1e-3, 0.05, 0.7, 3.0, 40.0] {
                let (y, v, i) = tr.at_with_integrals(h, 0.5);
                let (y2, v2) = tr.at(h);
                let j = tr.integrals(h, 0.5);
                assert_eq!((y, v, i.i1, i.i2), (y2, v2, j.i1, j.i2), "m {m} eta {eta} k {k} h {h}");
            }
        }
    }
}
