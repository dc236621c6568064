//! A stiff-safe integrator: the linearly implicit Rosenbrock method RODAS4 with step-size
//! control, dense output and rigorous bounds of the dense output.
//!
//! **Method.** RODAS4 of Hairer & Wanner (*Solving ODEs II*, 2nd ed., Sect. IV.7, Table 7.3;
//! coefficients from `rodas.f`, see [`super::rodas4`]): 6 stages, order 4, embedded order 3,
//! **L-stable and stiffly accurate** (`R(inf) = 0`: infinitely stiff modes are annihilated in
//! one step, and the step end satisfies the algebraic limit of a singularly perturbed
//! problem, e.g. `M -> 0` of the plate), continuous extension of order 3. Each step solves
//! six linear systems with one LU factorisation of `I / (h gamma) - J` at the step start,
//! using the **analytic Jacobian** and `df/dt` supplied by [`StiffSystem`] (a Rosenbrock
//! method needs the exact Jacobian for its order; no Newton iteration, so no convergence
//! failure). Cost per attempt: 6 RHS evaluations, 1 Jacobian, 1 LU, 6 triangular solves.
//!
//! **Why RODAS4.** The exact engine steps between junction events. At large N (1e6) events
//! are ~1e-5 apart, far below the plate's time scales: the step is one short step cut at the
//! event, where any consistent method is exact to round-off, and the cost is stages + one
//! Jacobian + one LU of a 1..6-dimensional matrix (measured in `benches/rosenbrock.rs`; see
//! `docs/performance.md`). At small N the steps are long and accuracy per stage matters:
//! order 4 with a 3rd-order estimate and a 3rd-order dense output beats the 3-stage order-3
//! candidates (ROS3P is only A-stable with `|R(inf)| = 0.73`, i.e. no damping of the plate's
//! fast mode at `M = 1e-9`; RODAS3 is L-stable but order 3 without a published dense output
//! of its own). Both `M > 0` and `M = 0` plates with any `eta`, `K`, `kappa N` are stable
//! because `S' >= 0` and `eta, K >= 0` put the Jacobian's eigenvalues in the closed left
//! half-plane, where an L-stable method is stable for every `h`.
//!
//! **Error control** (as `rodas.f`): `err = sqrt(mean_i (k6_i / sk_i)^2)`, `sk_i = atol +
//! rtol max(|y_i|, |y_new,i|)`; accept if `err <= 1`; new step `h / clamp(err^(1/4) /
//! safety, 1/fac_max, 1/fac_min)`, with Gustafsson's predictive controller (the `rodas.f`
//! default) after two consecutive accepted, uncut steps; no growth right after a rejection.
//! Steps never pass `t_max`, as in [`super::Dop853::step`]: a step cut short at `t_max` does
//! not shrink the proposal. A non-finite stage or a singular matrix rejects the attempt
//! (`h *= fac_min`).
//!
//! **Dense output** (`rodas.f`'s `CONTRO`): `y(t_old + s h) = (1 - s) y0 + s (y1 + (1 - s)
//! (c2 + s c3))`, a cubic per component; ends returned exactly. [`Rosenbrock::component_bounds`]
//! gives the cubic's range over the step (ends and real critical points) widened by a
//! round-off margin.
//! [`RosenbrockN::dense_integrals`] integrates the cubic (and its square) exactly.
//!
//! See `docs/rosenbrock.md`.

#![allow(clippy::needless_range_loop)] // stage and component loops over fixed arrays read better indexed

use serde::{Deserialize, Serialize};

use super::lu::{Lu, MAX_DIM};
use super::rodas4::{A, ALPHA, C, D, GAMMA, H2, H3, M, STAGES};
use super::stepper::{check_control, check_limits};
use super::system::{OdeError, OdeStats};

/// A system `y' = f(t, y)` with its Jacobian, for the linearly implicit integrator.
pub trait StiffSystem {
    /// Writes `f(t, y)` into `dydt` (same length as `y`). Non-finite output is detected.
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]);
    /// `dfdy` row-major `dim x dim` (`dfdy[i * dim + j] = d f_i / d y_j`) and `dfdt[i] = d f_i / d t` at `(t, y)`.
    fn jacobian(&mut self, t: f64, y: &[f64], dfdy: &mut [f64], dfdt: &mut [f64]);
    /// `f(t, y)` and the Jacobian at the same point (every step's start needs both). The
    /// default calls [`StiffSystem::rhs`] then [`StiffSystem::jacobian`]; override it when
    /// the two share work (the series engine's plate evaluates `S` and `S'` in one pass).
    #[inline]
    fn rhs_and_jacobian(&mut self, t: f64, y: &[f64], dydt: &mut [f64], dfdy: &mut [f64], dfdt: &mut [f64]) {
        self.rhs(t, y, dydt);
        self.jacobian(t, y, dfdy, dfdt);
    }
}

/// Settings of [`Rosenbrock`]; the defaults are `rodas.f`'s with the scene's tolerances.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RosenbrockConfig {
    /// Relative tolerance, at least [`MIN_RTOL`](super::MIN_RTOL).
    pub rtol: f64,
    /// Absolute tolerance, `> 0`.
    pub atol: f64,
    /// Largest step size; `None`: unbounded (every step is bounded by `t_max` anyway).
    pub h_max: Option<f64>,
    /// First step size; `None`: an estimate from `f` and `J f + f_t` at the start (no extra
    /// evaluation).
    pub h_init: Option<f64>,
    /// Safety factor of the step-size prediction (`rodas.f` `WORK(4)`, default 0.9).
    pub safety: f64,
    /// Smallest ratio `h_new / h` (`rodas.f` `1/WORK(2)`, default 0.2).
    pub fac_min: f64,
    /// Largest ratio `h_new / h` (`rodas.f` `1/WORK(3)`, default 6).
    pub fac_max: f64,
    /// Gustafsson's predictive step-size controller (default on, as in `rodas.f`).
    pub predictive: bool,
    /// Largest number of consecutive rejected attempts in one call of `step`.
    pub max_consecutive_rejections: u32,
}

impl Default for RosenbrockConfig {
    fn default() -> Self {
        Self {
            rtol: 1e-10,
            atol: 1e-12,
            h_max: None,
            h_init: None,
            safety: 0.9,
            fac_min: 0.2,
            fac_max: 6.0,
            predictive: true,
            max_consecutive_rejections: 100,
        }
    }
}

impl RosenbrockConfig {
    /// Checks every setting's domain.
    pub fn validate(&self) -> Result<(), OdeError> {
        check_control(self.rtol, self.atol, self.safety, self.fac_min, self.fac_max)?;
        check_limits(self.h_max, self.h_init, self.max_consecutive_rejections)
    }
}

/// Scratch space of one step (fixed arrays of the capacity `N`; never serialised). `jac`
/// is row-major with stride `dim` in the first `dim * dim` entries of its flattening.
#[derive(Clone, Debug)]
struct Work<const N: usize> {
    jac: [[f64; N]; N],
    dfdt: [f64; N],
    f0: [f64; N],
    k: [[f64; N]; STAGES],
    ys: [f64; N],
    dy: [f64; N],
    y_new: [f64; N],
    lu: Lu<N>,
}

impl<const N: usize> Default for Work<N> {
    fn default() -> Self {
        Self {
            jac: [[0.0; N]; N],
            dfdt: [0.0; N],
            f0: [0.0; N],
            k: [[0.0; N]; STAGES],
            ys: [0.0; N],
            dy: [0.0; N],
            y_new: [0.0; N],
            lu: Lu::default(),
        }
    }
}

/// Outcome of one trial step.
enum Trial {
    /// Scaled error norm (accept if `<= 1`).
    Error(f64),
    /// A stage or the new state was NaN or infinite, or `I/(h gamma) - J` was singular.
    NonFinite,
}

/// The general integrator: any dimension `1..=MAX_DIM` (8).
pub type Rosenbrock = RosenbrockN<MAX_DIM>;

/// RODAS4 with step-size control, dense output over the last accepted step and bounds of it
/// (see the module documentation). `Serialize + Deserialize` for checkpoints (validated on
/// load); no allocation per step; dimension `1..=N`. The capacity `N` is chosen at compile
/// time: every array (state, stages, Jacobian, LU) has `N` entries per row, so a small
/// system (`N = 2`, the series engine's plate) steps on small fixed arrays; [`Rosenbrock`]
/// (`N = MAX_DIM`) is the general integrator. The serialised form does not depend on `N`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(try_from = "RosenbrockData", into = "RosenbrockData")]
pub struct RosenbrockN<const N: usize> {
    dim: usize,
    cfg: RosenbrockConfig,
    stats: OdeStats,
    jac_evals: u64,
    /// Step-size proposal for the next step, not clamped by any `t_max`.
    h_prop: Option<f64>,
    /// Gustafsson memory: last accepted uncut step and its error (valid if `hacc > 0`).
    hacc: f64,
    erracc: f64,
    /// `reset` was called since the last step (counted in `stats.restarts`).
    restart_pending: bool,
    /// Last accepted step `[t_old, t_new]` of size `h_step`.
    dense_valid: bool,
    t_old: f64,
    t_new: f64,
    h_step: f64,
    /// Dense coefficients per component: `y0`, `y1`, `c2`, `c3`.
    cont: [[f64; N]; 4],
    work: Work<N>,
}

/// The serialised form of [`Rosenbrock`] (checked on deserialisation).
#[derive(Serialize, Deserialize)]
struct RosenbrockData {
    dim: usize,
    cfg: RosenbrockConfig,
    stats: OdeStats,
    jac_evals: u64,
    h_prop: Option<f64>,
    hacc: f64,
    erracc: f64,
    restart_pending: bool,
    dense_valid: bool,
    t_old: f64,
    t_new: f64,
    h_step: f64,
    cont: Vec<Vec<f64>>,
}

impl<const N: usize> From<RosenbrockN<N>> for RosenbrockData {
    fn from(r: RosenbrockN<N>) -> Self {
        let n = r.dim;
        Self {
            dim: n,
            cfg: r.cfg,
            stats: r.stats,
            jac_evals: r.jac_evals,
            h_prop: r.h_prop,
            hacc: r.hacc,
            erracc: r.erracc,
            restart_pending: r.restart_pending,
            dense_valid: r.dense_valid,
            t_old: r.t_old,
            t_new: r.t_new,
            h_step: r.h_step,
            cont: r.cont.iter().map(|c| c[..n].to_vec()).collect(),
        }
    }
}

impl<const N: usize> TryFrom<RosenbrockData> for RosenbrockN<N> {
    type Error = OdeError;

    fn try_from(d: RosenbrockData) -> Result<Self, OdeError> {
        d.cfg.validate()?;
        let n = d.dim;
        let bad = |what: &'static str| Err(OdeError::InvalidState { what });
        if n == 0 || n > N || d.cont.len() != 4 || d.cont.iter().any(|c| c.len() != n) {
            return bad("vector lengths do not match the dimension");
        }
        if let Some(h) = d.h_prop {
            if !(h > 0.0 && h.is_finite()) {
                return bad("step-size proposal");
            }
        }
        if !(d.hacc >= 0.0 && d.hacc.is_finite() && d.erracc > 0.0 && d.erracc.is_finite()) {
            return bad("controller memory");
        }
        if d.dense_valid
            && !(d.t_old.is_finite()
                && d.t_new.is_finite()
                && d.t_old < d.t_new
                && d.h_step > 0.0
                && d.h_step.is_finite()
                && d.cont.iter().flatten().all(|v| v.is_finite()))
        {
            return bad("invalid last step");
        }
        let mut cont = [[0.0; N]; 4];
        for (c, v) in cont.iter_mut().zip(&d.cont) {
            c[..n].copy_from_slice(v);
        }
        Ok(Self {
            dim: n,
            cfg: d.cfg,
            stats: d.stats,
            jac_evals: d.jac_evals,
            h_prop: d.h_prop,
            hacc: d.hacc,
            erracc: d.erracc,
            restart_pending: d.restart_pending,
            dense_valid: d.dense_valid,
            t_old: d.t_old,
            t_new: d.t_new,
            h_step: d.h_step,
            cont,
            work: Work::default(),
        })
    }
}

/// `x^(1/4)` as two square roots (correctly rounded each; a fraction of `powf`'s cost).
#[inline]
fn fourth_root(x: f64) -> f64 {
    x.sqrt().sqrt()
}

#[inline]
fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

impl<const N: usize> RosenbrockN<N> {
    /// An integrator for systems of dimension `1..=N` with tolerances `rtol >= MIN_RTOL`,
    /// `atol > 0` and the other defaults.
    pub fn new(dim: usize, rtol: f64, atol: f64) -> Result<Self, OdeError> {
        Self::with_config(dim, RosenbrockConfig { rtol, atol, ..RosenbrockConfig::default() })
    }

    /// An integrator with explicit settings.
    pub fn with_config(dim: usize, cfg: RosenbrockConfig) -> Result<Self, OdeError> {
        cfg.validate()?;
        if dim == 0 {
            return Err(OdeError::DimensionMismatch { expected: 1, got: 0 });
        }
        if dim > N {
            return Err(OdeError::DimensionMismatch { expected: N, got: dim });
        }
        Ok(Self {
            dim,
            cfg,
            stats: OdeStats::default(),
            jac_evals: 0,
            h_prop: None,
            hacc: 0.0,
            erracc: 1.0,
            restart_pending: false,
            dense_valid: false,
            t_old: 0.0,
            t_new: 0.0,
            h_step: 0.0,
            cont: [[0.0; N]; 4],
            work: Work::default(),
        })
    }

    /// Dimension of the system.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The settings.
    pub fn config(&self) -> &RosenbrockConfig {
        &self.cfg
    }

    /// Work counters (`restarts` counts the steps taken after a [`Rosenbrock::reset`]).
    pub fn stats(&self) -> OdeStats {
        self.stats
    }

    /// Evaluations of the Jacobian (one per step attempt sequence, i.e. per call of `step`).
    pub fn jacobian_evals(&self) -> u64 {
        self.jac_evals
    }

    /// The step size the next step will try (before clamping to its `t_max`).
    pub fn h_proposal(&self) -> Option<f64> {
        self.h_prop
    }

    /// Overrides the step-size proposal; ignored unless positive and finite.
    pub fn set_h_proposal(&mut self, h: f64) {
        if h > 0.0 && h.is_finite() {
            self.h_prop = Some(h);
        }
    }

    /// The last accepted step `(t_old, t_new)`; `None` before the first step.
    pub fn last_step(&self) -> Option<(f64, f64)> {
        self.dense_valid.then_some((self.t_old, self.t_new))
    }

    /// The right-hand side changed (a junction event): forget the error history of the
    /// predictive controller; keep the step-size proposal and the last step's dense output.
    /// (A Rosenbrock step evaluates `f` and `J` afresh at its start, so no derivative is
    /// carried over between steps.)
    pub fn reset(&mut self) {
        self.hacc = 0.0;
        self.restart_pending = true;
    }

    fn check_len(&self, len: usize) -> Result<(), OdeError> {
        if len == self.dim { Ok(()) } else { Err(OdeError::DimensionMismatch { expected: self.dim, got: len }) }
    }

    fn check_inputs(&self, t: f64, y: &[f64], t_max: f64) -> Result<(), OdeError> {
        self.check_len(y.len())?;
        if !(t.is_finite() && t_max.is_finite() && t_max > t) {
            return Err(OdeError::InvalidInterval { t, t_max });
        }
        if !all_finite(y) {
            return Err(OdeError::NonFiniteState { t });
        }
        Ok(())
    }

    /// `f0 = f(t, y)`, `J`, `f_t` at the step start; an error if non-finite.
    fn prepare_start<S: StiffSystem + ?Sized>(&mut self, sys: &mut S, t: f64, y: &[f64]) -> Result<(), OdeError> {
        let n = self.dim;
        let w = &mut self.work;
        let jac = &mut w.jac.as_flattened_mut()[..n * n];
        sys.rhs_and_jacobian(t, y, &mut w.f0[..n], jac, &mut w.dfdt[..n]);
        self.stats.rhs_evals += 1;
        self.jac_evals += 1;
        if !(all_finite(&w.f0[..n]) && all_finite(jac) && all_finite(&w.dfdt[..n])) {
            return Err(OdeError::NonFiniteRhs { t });
        }
        Ok(())
    }

    /// Initial step (Hairer's `HINIT` for order 4, with the second derivative `J f + f_t`
    /// taken from the Jacobian instead of an explicit Euler probe): `h` such that
    /// `h^4 max(|f|, |y''|) = 0.01` in the error norm, at most `100 * 0.01 |y| / |f|`.
    fn initial_step(&self, y: &[f64], remaining: f64) -> f64 {
        if let Some(h) = self.cfg.h_init {
            return h;
        }
        let n = self.dim;
        let w = &self.work;
        let (rtol, atol) = (self.cfg.rtol, self.cfg.atol);
        let (mut dnf, mut dny, mut der2) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let sk = atol + rtol * y[i].abs();
            let jac = w.jac.as_flattened();
            let ypp: f64 = (0..n).map(|j| jac[i * n + j] * w.f0[j]).sum::<f64>() + w.dfdt[i];
            dnf += (w.f0[i] / sk).powi(2);
            dny += (y[i] / sk).powi(2);
            der2 += (ypp / sk).powi(2);
        }
        let h0 = if dnf <= 1e-10 || dny <= 1e-10 { 1e-6 } else { (dny / dnf).sqrt() * 0.01 };
        let der12 = der2.sqrt().max(dnf.sqrt());
        let h1 = if der12 <= 1e-15 || !der12.is_finite() { (h0 * 1e-3).max(1e-6) } else { (0.01 / der12).powf(0.25) };
        let h = (100.0 * h0).min(h1).min(self.cfg.h_max.unwrap_or(f64::INFINITY));
        if h > 0.0 && h.is_finite() { h } else { remaining }
    }

    /// The six stages of a step of size `h` from `(t, y)`, the candidate `y_new` and the
    /// scaled error norm of `k_6`.
    fn trial<S: StiffSystem + ?Sized>(&mut self, sys: &mut S, t: f64, y: &[f64], h: f64) -> Trial {
        let n = self.dim;
        let w = &mut self.work;
        if !w.lu.factor_shifted(n, 1.0 / (h * GAMMA), &w.jac.as_flattened()[..n * n]) {
            return Trial::NonFinite;
        }
        let inv_h = 1.0 / h;
        for s in 0..STAGES {
            // Stage argument and its RHS (stage 0 uses f0).
            if s > 0 {
                for i in 0..n {
                    let mut acc = y[i];
                    for j in 0..s {
                        acc += A[s][j] * w.k[j][i];
                    }
                    w.ys[i] = acc;
                }
                sys.rhs(t + ALPHA[s] * h, &w.ys[..n], &mut w.dy[..n]);
                self.stats.rhs_evals += 1;
            } else {
                w.dy[..n].copy_from_slice(&w.f0[..n]);
            }
            let hd = h * D[s];
            let mut rhs = [0.0; N];
            // `f(stage) + h d_s f_t + sum_j (c_sj / h) k_j`, summed so that `f(stage)`, the
            // last value to be ready (it waits for the stage's RHS), comes last: the terms
            // before it are summed while the RHS is evaluated, off the critical path.
            for i in 0..n {
                let mut acc = hd * w.dfdt[i];
                for j in 0..s {
                    acc += C[s][j] * inv_h * w.k[j][i];
                }
                rhs[i] = acc + w.dy[i];
            }
            w.lu.solve(&mut rhs[..n]);
            w.k[s] = rhs;
        }
        let (rtol, atol) = (self.cfg.rtol, self.cfg.atol);
        let mut err = 0.0;
        for i in 0..n {
            let mut acc = y[i];
            for j in 0..STAGES {
                acc += M[j] * w.k[j][i];
            }
            w.y_new[i] = acc;
            let sk = atol + rtol * y[i].abs().max(acc.abs());
            err += (w.k[STAGES - 1][i] / sk).powi(2);
        }
        // One check for the whole attempt: a non-finite value in any stage reaches `y_new`
        // (every weight `M_j` is non-zero, and no operation here turns an infinity or a NaN
        // finite: the solves multiply by finite factors, `inf * 0` is NaN), so a stage's
        // failure is caught here as surely as after the stage, without a test per stage.
        if !all_finite(&w.y_new[..n]) {
            return Trial::NonFinite;
        }
        let err = (err / n as f64).sqrt();
        if err.is_finite() { Trial::Error(err) } else { Trial::NonFinite }
    }

    /// Stores the accepted step: dense coefficients and the new state.
    fn commit(&mut self, t: &mut f64, y: &mut [f64], h: f64, t_new: f64) {
        let n = self.dim;
        let w = &self.work;
        for i in 0..n {
            let (mut c2, mut c3) = (0.0, 0.0);
            for j in 0..STAGES {
                c2 += H2[j] * w.k[j][i];
                c3 += H3[j] * w.k[j][i];
            }
            self.cont[0][i] = y[i];
            self.cont[1][i] = w.y_new[i];
            self.cont[2][i] = c2;
            self.cont[3][i] = c3;
        }
        self.dense_valid = true;
        self.t_old = *t;
        self.t_new = t_new;
        self.h_step = h;
        y.copy_from_slice(&w.y_new[..n]);
        *t = t_new;
        self.stats.accepted += 1;
    }

    /// One accepted step from `*t` towards `t_max`, never beyond it (the last step is cut to
    /// land on `t_max` exactly). Same contract as [`super::Dop853::step`]: on error `t` and
    /// `y` are unchanged, errors are [`OdeError`] values, never panics, never a non-finite
    /// state.
    ///
    /// Step size: the remembered proposal `h`, or `t_max - t` if `1.01 h >= t_max - t`. A
    /// step cut short by `t_max` does not shrink the proposal. `f`, `J` and `f_t` are
    /// evaluated once per call (at `(t, y)`), then rejected attempts reuse them.
    pub fn step<S: StiffSystem + ?Sized>(
        &mut self,
        sys: &mut S,
        t: &mut f64,
        y: &mut [f64],
        t_max: f64,
    ) -> Result<(), OdeError> {
        self.check_inputs(*t, y, t_max)?;
        let t0 = *t;
        self.prepare_start(sys, t0, y)?;
        if self.restart_pending {
            self.restart_pending = false;
            self.stats.restarts += 1;
        }
        let remaining = t_max - t0;
        let mut h_prop = match self.h_prop {
            Some(h) => h,
            None => self.initial_step(y, remaining),
        };
        let cfg = &self.cfg;
        let (safety, fac_min, fac_max, max_rej) =
            (cfg.safety, cfg.fac_min, cfg.fac_max, cfg.max_consecutive_rejections);
        let (h_max, predictive) = (cfg.h_max, cfg.predictive);
        if let Some(h_max) = h_max {
            h_prop = h_prop.min(h_max);
        }
        let h_min = 10.0 * f64::EPSILON * t0.abs();
        let mut rejections = 0u32;
        let mut last_non_finite = false;
        loop {
            let (h, clamped) = if 1.01 * h_prop >= remaining { (remaining, true) } else { (h_prop, false) };
            if !clamped && (h.is_nan() || h <= h_min) {
                return Err(if last_non_finite {
                    OdeError::NonFiniteStep { t: t0, h, rejections }
                } else {
                    OdeError::StepSizeUnderflow { t: t0, h }
                });
            }
            let t_new = if clamped { t_max } else { t0 + h };
            match self.trial(sys, t0, y, h) {
                Trial::Error(err) if err <= 1.0 => {
                    // Accepted: h / clamp(err^(1/4) / safety, 1/fac_max, 1/fac_min).
                    let q = fourth_root(err);
                    let mut fac = (q / safety).clamp(1.0 / fac_max, 1.0 / fac_min);
                    let cut_short = clamped && h < h_prop;
                    if !cut_short {
                        if predictive && self.hacc > 0.0 {
                            // Gustafsson: (h_acc / h) (err^2 / err_acc)^(1/4) / safety.
                            let facgus = (self.hacc / h * fourth_root(err * err / self.erracc) / safety)
                                .clamp(1.0 / fac_max, 1.0 / fac_min);
                            fac = fac.max(facgus);
                        }
                        self.hacc = h;
                        self.erracc = err.max(1e-2);
                    }
                    let mut h_new = h / fac;
                    if rejections > 0 {
                        h_new = h_new.min(h);
                    }
                    if cut_short {
                        h_new = h_new.max(h_prop);
                    }
                    if let Some(h_max) = h_max {
                        h_new = h_new.min(h_max);
                    }
                    self.h_prop = Some(h_new);
                    self.commit(t, y, h, t_new);
                    return Ok(());
                }
                Trial::Error(err) => {
                    h_prop = h / (fourth_root(err) / safety).min(1.0 / fac_min);
                    last_non_finite = false;
                    self.stats.rejected += 1;
                    rejections += 1;
                    if rejections >= max_rej {
                        return Err(OdeError::TooManyRejections { t: t0, h, rejections });
                    }
                }
                Trial::NonFinite => {
                    h_prop = h * fac_min;
                    last_non_finite = true;
                    self.stats.rejected += 1;
                    self.stats.rejected_non_finite += 1;
                    rejections += 1;
                    if rejections >= max_rej {
                        return Err(OdeError::NonFiniteStep { t: t0, h, rejections });
                    }
                }
            }
        }
    }

    /// One step of exactly size `h > 0` without error control (for convergence tests).
    /// Dense output covers the step afterwards; the step-size proposal is unchanged.
    pub fn step_fixed<S: StiffSystem + ?Sized>(
        &mut self,
        sys: &mut S,
        t: &mut f64,
        y: &mut [f64],
        h: f64,
    ) -> Result<(), OdeError> {
        let t0 = *t;
        self.check_inputs(t0, y, t0 + h)?;
        self.prepare_start(sys, t0, y)?;
        match self.trial(sys, t0, y, h) {
            Trial::Error(_) => {
                self.commit(t, y, h, t0 + h);
                Ok(())
            }
            Trial::NonFinite => {
                self.stats.rejected += 1;
                self.stats.rejected_non_finite += 1;
                Err(OdeError::NonFiniteStep { t: t0, h, rejections: 1 })
            }
        }
    }

    /// Maps `t` to `s` in `[0, 1]` of the last step (`None`: an end, returned exactly).
    fn dense_s(&self, t: f64) -> Result<DensePoint, OdeError> {
        if !self.dense_valid {
            return Err(OdeError::NoDenseOutput);
        }
        let (t_old, t_new) = (self.t_old, self.t_new);
        let slack = 4.0 * f64::EPSILON * t_old.abs().max(t_new.abs());
        if !(t >= t_old - slack && t <= t_new + slack) {
            return Err(OdeError::OutsideDenseInterval { t, t_old, t_new });
        }
        Ok(if t <= t_old {
            DensePoint::Start
        } else if t >= t_new {
            DensePoint::End
        } else {
            DensePoint::Inside(((t - t_old) / self.h_step).clamp(0.0, 1.0))
        })
    }

    #[inline]
    fn dense_at(&self, i: usize, p: DensePoint) -> f64 {
        let c = |r: usize| self.cont[r][i];
        match p {
            DensePoint::Start => c(0),
            DensePoint::End => c(1),
            DensePoint::Inside(s) => {
                let s1 = 1.0 - s;
                c(0) * s1 + s * (c(1) + s1 * (c(2) + s * c(3)))
            }
        }
    }

    /// Dense output inside the last accepted step (order 3; the ends are the accepted
    /// states exactly).
    pub fn dense(&self, t: f64, out: &mut [f64]) -> Result<(), OdeError> {
        self.check_len(out.len())?;
        let p = self.dense_s(t)?;
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.dense_at(i, p);
        }
        Ok(())
    }

    /// Component `i` of the dense output at `t` in the last accepted step.
    pub fn dense_component(&self, i: usize, t: f64) -> Result<f64, OdeError> {
        if i >= self.dim {
            return Err(OdeError::DimensionMismatch { expected: self.dim, got: i });
        }
        let p = self.dense_s(t)?;
        Ok(self.dense_at(i, p))
    }

    /// Exact integrals of the dense-output interpolant of component `i` minus `shift` from
    /// the start of the last step to `t` (inside it): `(int (y_i - shift) dt, int (y_i -
    /// shift)^2 dt)` over `[t_old, t]`.
    ///
    /// With `q(s) = p(s) - shift = a0 + b1 s + b2 s^2 + b3 s^3` (`a0 = y0 - shift`, `b1 = y1 -
    /// y0 + c2`, `b2 = c3 - c2`, `b3 = -c3`, see [`Rosenbrock::component_bounds`]) and `sigma
    /// = (t - t_old) / h`: `int q = h sigma sum_k b_k sigma^k / (k + 1)` and `int q^2 = h
    /// sigma sum_k e_k sigma^k / (k + 1)`, `e` the coefficients of `q^2` (degree 6).
    /// `shift` near the values keeps the square free of cancellation.
    pub fn dense_integrals(&self, i: usize, t: f64, shift: f64) -> Result<(f64, f64), OdeError> {
        if i >= self.dim {
            return Err(OdeError::DimensionMismatch { expected: self.dim, got: i });
        }
        let (sigma, width) = match self.dense_s(t)? {
            DensePoint::Start => return Ok((0.0, 0.0)),
            DensePoint::End => (1.0, self.t_new - self.t_old),
            DensePoint::Inside(s) => (s, t - self.t_old),
        };
        let (y0, y1, c2, c3) = (self.cont[0][i], self.cont[1][i], self.cont[2][i], self.cont[3][i]);
        let b = [y0 - shift, y1 - y0 + c2, c3 - c2, -c3];
        let e = [
            b[0] * b[0],
            2.0 * b[0] * b[1],
            b[1] * b[1] + 2.0 * b[0] * b[2],
            2.0 * (b[0] * b[3] + b[1] * b[2]),
            b[2] * b[2] + 2.0 * b[1] * b[3],
            2.0 * b[2] * b[3],
            b[3] * b[3],
        ];
        let i1 = b[0] + sigma * (b[1] / 2.0 + sigma * (b[2] / 3.0 + sigma * (b[3] / 4.0)));
        let mut i2 = 0.0;
        for k in (0..7).rev() {
            i2 = i2 * sigma + e[k] / (k as f64 + 1.0);
        }
        Ok((width * i1, width * i2))
    }

    /// Rigorous bounds `(lo, hi)` of the dense-output interpolant of component `i` over the
    /// whole last step.
    ///
    /// The interpolant is the cubic `p(s) = y0 + (y1 - y0 + c2) s + (c3 - c2) s^2 - c3 s^3`,
    /// `s` in `[0, 1]`; its extrema are at the ends and at the real roots of `p'` in `(0, 1)`
    /// (found stably). The range of those values is widened by `16 eps (|y0| + |y1| + |c2| +
    /// |c3|)`, which exceeds the round-off of evaluating the cubic (in either form) and of the
    /// critical points, so every value returned by [`Rosenbrock::dense_component`] inside the
    /// step lies within the bounds (test `component_bounds_contain_dense_values`).
    pub fn component_bounds(&self, i: usize) -> Result<(f64, f64), OdeError> {
        if i >= self.dim {
            return Err(OdeError::DimensionMismatch { expected: self.dim, got: i });
        }
        if !self.dense_valid {
            return Err(OdeError::NoDenseOutput);
        }
        let (y0, y1, c2, c3) = (self.cont[0][i], self.cont[1][i], self.cont[2][i], self.cont[3][i]);
        let (mut lo, mut hi) = (y0.min(y1), y0.max(y1));
        // p'(s) = b1 + 2 b2 s + 3 b3 s^2 with b1 = y1 - y0 + c2, b2 = c3 - c2, b3 = -c3.
        let (b1, b2, b3) = (y1 - y0 + c2, c3 - c2, -c3);
        let mut roots = [f64::NAN; 2];
        quadratic_roots(3.0 * b3, 2.0 * b2, b1, &mut roots);
        for s in roots {
            if s > 0.0 && s < 1.0 {
                let v = self.dense_at(i, DensePoint::Inside(s));
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        let margin = 16.0 * f64::EPSILON * (y0.abs() + y1.abs() + c2.abs() + c3.abs());
        Ok((lo - margin, hi + margin))
    }
}

/// Where a time falls in the last step.
#[derive(Clone, Copy, Debug)]
enum DensePoint {
    Start,
    End,
    Inside(f64),
}

/// Real roots of `a s^2 + b s + c` (NaN where none), without cancellation.
fn quadratic_roots(a: f64, b: f64, c: f64, out: &mut [f64; 2]) {
    *out = [f64::NAN; 2];
    if a == 0.0 {
        if b != 0.0 {
            out[0] = -c / b;
        }
        return;
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        // A double root lost to round-off is caught by the margin only if it is near an
        // extremum of size ~eps; treat a slightly negative discriminant as zero.
        if disc > -1e-12 * b * b {
            out[0] = -b / (2.0 * a);
        }
        return;
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    if q != 0.0 {
        out[0] = q / a;
        out[1] = c / q;
    } else {
        out[0] = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Decay(f64);
    impl StiffSystem for Decay {
        fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
            d[0] = self.0 * y[0];
        }
        fn jacobian(&mut self, _t: f64, _y: &[f64], j: &mut [f64], ft: &mut [f64]) {
            j[0] = self.0;
            ft[0] = 0.0;
        }
    }

    /// One fixed step on `y' = lambda y` reproduces the stability function, and `R(-inf) ~ 0`.
    #[test]
    fn very_stiff_decay_is_annihilated_in_one_step() {
        let mut ode = Rosenbrock::new(1, 1e-8, 1e-10).unwrap();
        let (mut t, mut y) = (0.0, [1.0]);
        ode.step_fixed(&mut Decay(-1e12), &mut t, &mut y, 1.0).unwrap();
        assert!(y[0].abs() < 1e-9, "{}", y[0]);
    }

    /// The bounds are the cubic's range, not a loose hull: `p(s) = s (1 - s) (1 + 2 s)`
    /// (`y0 = y1 = 0`, `c2 = 1`, `c3 = 2`) has its maximum `p(s*)` at `s* = (1 + sqrt 7)/6`
    /// and its minimum 0 at the ends; a cubic with an interior minimum and maximum too.
    #[test]
    fn component_bounds_are_the_range_of_the_cubic() {
        let mut ode = Rosenbrock::new(2, 1e-8, 1e-10).unwrap();
        ode.cont[0][..2].copy_from_slice(&[0.0, 1.0]);
        ode.cont[1][..2].copy_from_slice(&[0.0, 1.0]);
        ode.cont[2][..2].copy_from_slice(&[1.0, 0.0]);
        // Component 1: p(s) = 1 + (c3 - c2) s^2 - c3 s^3 + c2 s with c2 = 0, c3 = 3:
        // p = 1 + 3 s^2 - 3 s^3, max at s = 2/3 (p = 1 + 4/9), min 1 at the ends.
        ode.cont[3][..2].copy_from_slice(&[2.0, 3.0]);
        ode.dense_valid = true;
        (ode.t_old, ode.t_new, ode.h_step) = (1.0, 3.0, 2.0);
        let s = (1.0 + 7f64.sqrt()) / 6.0;
        let p_max = s * (1.0 - s) * (1.0 + 2.0 * s);
        // Widening: the documented margin 16 eps sum|c| plus a few ulps of the extremum.
        let (m0, m1) = (16.0 * f64::EPSILON * 3.0 + 4e-16, 16.0 * f64::EPSILON * 5.0 + 8e-16);
        let (lo, hi) = ode.component_bounds(0).unwrap();
        assert!(lo <= 0.0 && lo >= -m0, "{lo}");
        assert!(hi >= p_max && hi - p_max <= m0, "{hi} vs {p_max}");
        assert!((ode.dense_component(0, 1.0 + 2.0 * s).unwrap() - p_max).abs() < 1e-15);
        let (lo, hi) = ode.component_bounds(1).unwrap();
        assert!(lo <= 1.0 && lo >= 1.0 - m1, "{lo}");
        assert!(hi >= 13.0 / 9.0 && hi - 13.0 / 9.0 <= m1, "{hi}");
    }

    /// `dense_integrals` equals a fine Simpson rule on `dense_component` (the interpolant is
    /// a cubic, its square degree 6: Simpson with 2000 intervals is exact to ~1e-13), at the
    /// step's end and inside it, for a shift away from the values.
    #[test]
    fn dense_integrals_match_quadrature_of_the_interpolant() {
        let mut ode = Rosenbrock::new(2, 1e-8, 1e-10).unwrap();
        let (mut t, mut y) = (0.3, [1.0, -0.5]);
        let mut osc = |_t: f64, y: &[f64], d: &mut [f64]| {
            d[0] = y[1];
            d[1] = -4.0 * y[0] - 0.3 * y[1];
        };
        struct Osc<'a, F>(&'a mut F);
        impl<F: FnMut(f64, &[f64], &mut [f64])> StiffSystem for Osc<'_, F> {
            fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
                (self.0)(t, y, d)
            }
            fn jacobian(&mut self, _t: f64, _y: &[f64], j: &mut [f64], ft: &mut [f64]) {
                j.copy_from_slice(&[0.0, 1.0, -4.0, -0.3]);
                ft.fill(0.0);
            }
        }
        ode.step_fixed(&mut Osc(&mut osc), &mut t, &mut y, 0.7).unwrap();
        let (t0, t1) = ode.last_step().unwrap();
        for i in 0..2 {
            for (end, shift) in [(t1, 0.0), (t0 + 0.41, 0.8), (t1, -0.3)] {
                let n = 2000;
                let h = (end - t0) / n as f64;
                let (mut q1, mut q2) = (0.0, 0.0);
                for k in 0..=n {
                    let w = if k == 0 || k == n {
                        1.0
                    } else if k % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    };
                    let v = ode.dense_component(i, t0 + k as f64 * h).unwrap() - shift;
                    q1 += w * v;
                    q2 += w * v * v;
                }
                let (q1, q2) = (q1 * h / 3.0, q2 * h / 3.0);
                let (i1, i2) = ode.dense_integrals(i, end, shift).unwrap();
                assert!((i1 - q1).abs() < 1e-13, "component {i} to {end}: {i1} vs {q1}");
                assert!((i2 - q2).abs() < 1e-13, "component {i} to {end}: {i2} vs {q2}");
            }
            assert_eq!(ode.dense_integrals(i, t0, 0.0).unwrap(), (0.0, 0.0));
        }
        assert!(ode.dense_integrals(2, t1, 0.0).is_err());
        assert!(ode.dense_integrals(0, t1 + 1.0, 0.0).is_err());
    }

    #[test]
    fn quadratic_roots_are_found() {
        let mut r = [0.0; 2];
        quadratic_roots(1.0, -3.0, 2.0, &mut r);
        let (a, b) = (r[0].min(r[1]), r[0].max(r[1]));
        assert!((a - 1.0).abs() < 1e-15 && (b - 2.0).abs() < 1e-15);
        quadratic_roots(0.0, 2.0, -1.0, &mut r);
        assert_eq!(r[0], 0.5);
        quadratic_roots(1.0, 0.0, 1.0, &mut r);
        assert!(r[0].is_nan() && r[1].is_nan());
    }

    #[test]
    fn too_large_a_dimension_is_refused() {
        assert!(matches!(Rosenbrock::new(9, 1e-8, 1e-10), Err(OdeError::DimensionMismatch { .. })));
        assert!(matches!(Rosenbrock::new(0, 1e-8, 1e-10), Err(OdeError::DimensionMismatch { .. })));
    }
}
