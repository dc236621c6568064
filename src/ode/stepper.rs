//! The DOP853 stepper: stages, error estimate, step-size control, FSAL, restarts.
//!
//! Follows Hairer's `DP86CO` (`dop853.f`) with these differences, all documented in
//! `docs/ode.md`: one accepted step per call, never beyond a limit `t_max` (Hairer's `XEND`
//! logic, with the unclamped proposal remembered); restarts after a discontinuity; non-finite
//! values are caught and answered by a smaller trial step or an error; no stiffness detection
//! (our problems are not stiff, and a stiff problem shows up as many small accepted steps,
//! which the engine's counters report).

use serde::{Deserialize, Serialize};

use super::coefficients::{A, B, BHH, C, D, ER, STAGES, STAGES_EXT};
use super::system::{OdeError, OdeStats, OdeSystem};

/// Smallest accepted relative tolerance, `4 eps ~ 8.9e-16`: below it the error estimate is
/// round-off and the step size can collapse to a crawl (not an underflow) instead of failing.
pub const MIN_RTOL: f64 = 4.0 * f64::EPSILON;

/// Index of the FSAL stage `f(t + h, y_new)` in the stage buffer.
const FSAL: usize = 12;

/// Settings of [`Dop853`]. The defaults are Hairer's, with the scene's default tolerances.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Dop853Config {
    /// Relative tolerance (`exact.rtol`), at least [`MIN_RTOL`]: the local error of `y_i` is
    /// kept below about `atol + rtol * max(|y_i(t)|, |y_i(t + h)|)` in a root-mean-square
    /// sense.
    pub rtol: f64,
    /// Absolute tolerance (`exact.atol`), `> 0`.
    pub atol: f64,
    /// Safety factor of the step-size prediction (Hairer `WORK(2)`, default 0.9).
    pub safety: f64,
    /// Smallest step-size ratio `h_new / h` (Hairer `WORK(3)`, default 0.333).
    pub fac_min: f64,
    /// Largest step-size ratio `h_new / h` (Hairer `WORK(4)`, default 6).
    pub fac_max: f64,
    /// Lund stabilisation exponent `beta` (Hairer `WORK(5)`, default 0, at most 0.2).
    pub beta: f64,
    /// Largest step size; `None`: unbounded (every step is bounded by `t_max` anyway).
    pub h_max: Option<f64>,
    /// First step size; `None`: Hairer's `HINIT` estimate (costs one RHS evaluation).
    pub h_init: Option<f64>,
    /// Largest number of consecutive rejected attempts within one call of `step` before
    /// giving up with [`OdeError::TooManyRejections`]. Each rejection shrinks `h` by at most
    /// `fac_min`, so the default 100 covers a factor `0.333^100 ~ 1e-48`.
    pub max_consecutive_rejections: u32,
    /// Number of sub-intervals sampled by event location (`locate*`), default 16.
    pub event_samples: u32,
}

impl Default for Dop853Config {
    fn default() -> Self {
        Self {
            rtol: 1e-10,
            atol: 1e-12,
            safety: 0.9,
            fac_min: 0.333,
            fac_max: 6.0,
            beta: 0.0,
            h_max: None,
            h_init: None,
            max_consecutive_rejections: 100,
            event_samples: 16,
        }
    }
}

impl Dop853Config {
    /// Checks every setting's domain.
    pub fn validate(&self) -> Result<(), OdeError> {
        check_control(self.rtol, self.atol, self.safety, self.fac_min, self.fac_max)?;
        if !(0.0..=0.2).contains(&self.beta) {
            return Err(OdeError::InvalidConfig { name: "beta", value: self.beta });
        }
        check_limits(self.h_max, self.h_init, self.max_consecutive_rejections)?;
        if self.event_samples == 0 {
            return Err(OdeError::InvalidConfig { name: "event_samples", value: 0.0 });
        }
        Ok(())
    }
}

/// The step-size control both steppers share: `rtol >= MIN_RTOL` and `atol > 0` finite,
/// `safety` in `(1e-4, 1)`, `fac_min` in `(0, 1)`, `fac_max > 1` finite.
pub(super) fn check_control(rtol: f64, atol: f64, safety: f64, fac_min: f64, fac_max: f64) -> Result<(), OdeError> {
    let bad = |name: &'static str, value: f64| Err(OdeError::InvalidConfig { name, value });
    if !(rtol.is_finite() && rtol >= MIN_RTOL) {
        return bad("rtol", rtol);
    }
    if !(atol.is_finite() && atol > 0.0) {
        return bad("atol", atol);
    }
    if !(safety > 1e-4 && safety < 1.0) {
        return bad("safety", safety);
    }
    if !(fac_min > 0.0 && fac_min < 1.0) {
        return bad("fac_min", fac_min);
    }
    if !(fac_max > 1.0 && fac_max.is_finite()) {
        return bad("fac_max", fac_max);
    }
    Ok(())
}

/// The limits both steppers share: `h_max` and `h_init`, when given, `> 0` and finite; at
/// least one rejection allowed.
pub(super) fn check_limits(h_max: Option<f64>, h_init: Option<f64>, rejections: u32) -> Result<(), OdeError> {
    // (No let-chains: the crate declares rust-version 1.85.)
    for (name, value) in [("h_max", h_max), ("h_init", h_init)] {
        if let Some(h) = value {
            if !(h > 0.0 && h.is_finite()) {
                return Err(OdeError::InvalidConfig { name, value: h });
            }
        }
    }
    if rejections == 0 {
        return Err(OdeError::InvalidConfig { name: "max_consecutive_rejections", value: 0.0 });
    }
    Ok(())
}

/// Scratch buffers, allocated once (at construction, or at the first use after
/// deserialisation); not serialised because their content never outlives a call.
#[derive(Clone, Debug, Default)]
pub(super) struct Work {
    /// Stages `k_0..k_15`, stage `j` at `j * dim..(j + 1) * dim`.
    k: Vec<f64>,
    /// Argument of the current stage.
    ys: Vec<f64>,
    /// Candidate new state.
    y_new: Vec<f64>,
    /// Dense state for `locate`.
    pub(super) y_dense: Vec<f64>,
}

/// `(y_new, h e5, h e3)` of [`Dop853::probe_step`].
pub type ProbeStep = (Vec<f64>, Vec<f64>, Vec<f64>);

/// Outcome of one trial step.
enum Trial {
    /// Scaled error norm (accept if `<= 1`).
    Error(f64),
    /// A stage or the new state was NaN or infinite.
    NonFinite,
}

/// Dormand–Prince 8(5,3) with step-size control, FSAL, 7th-order dense output over the last
/// accepted step, and event location.
///
/// The state (settings, counters, step-size proposal, FSAL derivative, last step's dense
/// output) is `Serialize + Deserialize` for checkpoints; scratch buffers are not (they are
/// re-allocated on first use). No allocation happens per step.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(try_from = "Dop853Data")]
pub struct Dop853 {
    dim: usize,
    cfg: Dop853Config,
    stats: OdeStats,
    /// Step-size proposal for the next step, not clamped by any `t_max`.
    h_prop: Option<f64>,
    /// Previous accepted error (Lund stabilisation).
    facold: f64,
    /// `f0 = f(t_cur, y_cur)` is valid (FSAL).
    f0_valid: bool,
    t_cur: f64,
    y_cur: Vec<f64>,
    f0: Vec<f64>,
    /// Last accepted step `[t_old, t_new]` of size `h_step` (`t_new` may differ from
    /// `t_old + h_step` in the last bit when the step was clamped to `t_max`).
    dense_valid: bool,
    t_old: f64,
    t_new: f64,
    h_step: f64,
    /// Dense-output coefficients, `cont[r * dim + i]`, `r` in `0..8`.
    pub(super) cont: Vec<f64>,
    /// Accepted state at `t_new`.
    pub(super) y_end: Vec<f64>,
    #[serde(skip)]
    pub(super) work: Work,
}

/// The serialised form of [`Dop853`], checked by `TryFrom` on deserialisation so that a
/// corrupt checkpoint is an error rather than a panic (wrong lengths) or a NaN later.
#[derive(Deserialize)]
struct Dop853Data {
    dim: usize,
    cfg: Dop853Config,
    stats: OdeStats,
    h_prop: Option<f64>,
    facold: f64,
    f0_valid: bool,
    t_cur: f64,
    y_cur: Vec<f64>,
    f0: Vec<f64>,
    dense_valid: bool,
    t_old: f64,
    t_new: f64,
    h_step: f64,
    cont: Vec<f64>,
    y_end: Vec<f64>,
}

impl TryFrom<Dop853Data> for Dop853 {
    type Error = OdeError;

    fn try_from(d: Dop853Data) -> Result<Self, OdeError> {
        d.cfg.validate()?;
        let n = d.dim;
        let bad = |what: &'static str| Err(OdeError::InvalidState { what });
        if n == 0 || d.y_cur.len() != n || d.f0.len() != n || d.y_end.len() != n || d.cont.len() != 8 * n {
            return bad("vector lengths do not match the dimension");
        }
        if let Some(h) = d.h_prop {
            if !(h > 0.0 && h.is_finite()) {
                return bad("step-size proposal");
            }
        }
        if !(d.facold > 0.0 && d.facold.is_finite()) {
            return bad("facold");
        }
        if d.f0_valid && !(d.t_cur.is_finite() && all_finite(&d.y_cur) && all_finite(&d.f0)) {
            return bad("non-finite current point");
        }
        if d.dense_valid
            && !(d.t_old.is_finite()
                && d.t_new.is_finite()
                && d.t_old < d.t_new
                && d.h_step > 0.0
                && d.h_step.is_finite()
                && all_finite(&d.cont)
                && all_finite(&d.y_end))
        {
            return bad("invalid last step");
        }
        let mut s = Self {
            dim: n,
            cfg: d.cfg,
            stats: d.stats,
            h_prop: d.h_prop,
            facold: d.facold,
            f0_valid: d.f0_valid,
            t_cur: d.t_cur,
            y_cur: d.y_cur,
            f0: d.f0,
            dense_valid: d.dense_valid,
            t_old: d.t_old,
            t_new: d.t_new,
            h_step: d.h_step,
            cont: d.cont,
            y_end: d.y_end,
            work: Work::default(),
        };
        s.ensure_work();
        Ok(s)
    }
}

#[inline]
fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// `out = y + h * sum_j a_j k_j` over the sparse row.
#[inline]
fn combine(n: usize, y: &[f64], h: f64, k: &[f64], row: &[(usize, f64)], out: &mut [f64]) {
    for i in 0..n {
        let mut acc = 0.0;
        for &(j, a) in row {
            acc += a * k[j * n + i];
        }
        out[i] = y[i] + h * acc;
    }
}

impl Dop853 {
    /// An integrator for systems of dimension `dim >= 1` with tolerances `rtol >= 0`,
    /// `atol > 0` and Hairer's other defaults.
    pub fn new(dim: usize, rtol: f64, atol: f64) -> Result<Self, OdeError> {
        Self::with_config(dim, Dop853Config { rtol, atol, ..Dop853Config::default() })
    }

    /// An integrator with explicit settings.
    pub fn with_config(dim: usize, cfg: Dop853Config) -> Result<Self, OdeError> {
        cfg.validate()?;
        if dim == 0 {
            return Err(OdeError::DimensionMismatch { expected: 1, got: 0 });
        }
        let mut s = Self {
            dim,
            cfg,
            stats: OdeStats::default(),
            h_prop: None,
            facold: 1e-4,
            f0_valid: false,
            t_cur: 0.0,
            y_cur: vec![0.0; dim],
            f0: vec![0.0; dim],
            dense_valid: false,
            t_old: 0.0,
            t_new: 0.0,
            h_step: 0.0,
            cont: vec![0.0; 8 * dim],
            y_end: vec![0.0; dim],
            work: Work::default(),
        };
        s.ensure_work();
        Ok(s)
    }

    /// Dimension of the system.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The settings.
    pub fn config(&self) -> &Dop853Config {
        &self.cfg
    }

    /// Work counters.
    pub fn stats(&self) -> OdeStats {
        self.stats
    }

    /// The step size the next step will try (before clamping to its `t_max`); `None` before
    /// the first step (then Hairer's initial estimate or `h_init` is used).
    pub fn h_proposal(&self) -> Option<f64> {
        self.h_prop
    }

    /// Overrides the step-size proposal (e.g. with a known time scale); ignored unless
    /// positive and finite.
    pub fn set_h_proposal(&mut self, h: f64) {
        if h > 0.0 && h.is_finite() {
            self.h_prop = Some(h);
        }
    }

    /// The last accepted step `(t_old, t_new)`, over which dense output and event location
    /// work; `None` before the first step.
    pub fn last_step(&self) -> Option<(f64, f64)> {
        self.dense_valid.then_some((self.t_old, self.t_new))
    }

    /// Test hook: installs a last step by hand (dense coefficients of the cubic Hermite part
    /// only, from the given end states and derivatives).
    #[cfg(test)]
    pub(super) fn set_last_step_for_test(&mut self, t_old: f64, y_old: &[f64], t_new: f64, y_new: &[f64]) {
        let n = self.dim;
        self.cont.fill(0.0);
        for i in 0..n {
            self.cont[i] = y_old[i];
            self.cont[n + i] = y_new[i] - y_old[i];
        }
        self.y_end.copy_from_slice(y_new);
        self.t_old = t_old;
        self.t_new = t_new;
        self.h_step = t_new - t_old;
        self.dense_valid = true;
    }

    pub(super) fn dense_interval(&self) -> Option<(f64, f64, f64)> {
        self.dense_valid.then_some((self.t_old, self.t_new, self.h_step))
    }

    /// Forget the FSAL derivative: call after the right-hand side changed discontinuously
    /// (a junction event). The step-size proposal and the last step's dense output are kept.
    /// (A change of `t` or `y` between steps is detected automatically and also forces a
    /// fresh derivative; a change of the RHS itself cannot be detected: call `reset`.)
    pub fn reset(&mut self) {
        self.f0_valid = false;
    }

    pub(super) fn check_len(&self, len: usize) -> Result<(), OdeError> {
        if len == self.dim { Ok(()) } else { Err(OdeError::DimensionMismatch { expected: self.dim, got: len }) }
    }

    pub(super) fn ensure_work(&mut self) {
        let n = self.dim;
        if self.work.k.len() != STAGES_EXT * n {
            self.work =
                Work { k: vec![0.0; STAGES_EXT * n], ys: vec![0.0; n], y_new: vec![0.0; n], y_dense: vec![0.0; n] };
        }
    }

    /// Makes `f0 = f(t, y)` valid (FSAL reuse if `t`, `y` are those of the last step end).
    fn prepare_start<S: OdeSystem + ?Sized>(&mut self, sys: &mut S, t: f64, y: &[f64]) -> Result<(), OdeError> {
        if self.f0_valid && self.t_cur == t && self.y_cur == y {
            return Ok(());
        }
        self.f0_valid = false;
        let n = self.dim;
        let k0 = &mut self.work.k[..n];
        sys.rhs(t, y, k0);
        self.stats.rhs_evals += 1;
        self.stats.restarts += 1;
        if !all_finite(k0) {
            return Err(OdeError::NonFiniteRhs { t });
        }
        self.f0.copy_from_slice(k0);
        self.y_cur.copy_from_slice(y);
        self.t_cur = t;
        self.f0_valid = true;
        Ok(())
    }

    /// Hairer's `HINIT` (order 8): `h` such that `h^8 max(|f0|, |f'|) = 0.01` in the error
    /// norm, at most `100` times the explicit-Euler guess. The Euler probe never goes beyond
    /// `remaining`.
    fn initial_step<S: OdeSystem + ?Sized>(&mut self, sys: &mut S, t: f64, y: &[f64], remaining: f64) -> f64 {
        if let Some(h) = self.cfg.h_init {
            return h;
        }
        let n = self.dim;
        let (rtol, atol) = (self.cfg.rtol, self.cfg.atol);
        let h_max = self.cfg.h_max.unwrap_or(f64::INFINITY);
        let (mut dnf, mut dny) = (0.0, 0.0);
        for (yi, fi) in y.iter().zip(&self.f0) {
            let sk = atol + rtol * yi.abs();
            dnf += (fi / sk).powi(2);
            dny += (yi / sk).powi(2);
        }
        let mut h = if dnf <= 1e-10 || dny <= 1e-10 { 1e-6 } else { (dny / dnf).sqrt() * 0.01 };
        h = h.min(h_max).min(remaining);
        let (k, ys) = (&mut self.work.k, &mut self.work.ys);
        for i in 0..n {
            ys[i] = y[i] + h * self.f0[i];
        }
        let f1 = &mut k[n..2 * n];
        sys.rhs(t + h, ys, f1);
        self.stats.rhs_evals += 1;
        let mut der2 = 0.0;
        for i in 0..n {
            let sk = atol + rtol * y[i].abs();
            der2 += ((f1[i] - self.f0[i]) / sk).powi(2);
        }
        let der2 = der2.sqrt() / h;
        let der12 = der2.abs().max(dnf.sqrt());
        let h1 =
            if der12 <= 1e-15 || !der12.is_finite() { (h * 1e-3).max(1e-6) } else { (0.01 / der12).powf(1.0 / 8.0) };
        let h = (100.0 * h).min(h1).min(h_max);
        if h > 0.0 && h.is_finite() { h } else { remaining }
    }

    /// The eleven new stages of a step of size `h` from `(t, y)`, the candidate `y_new` and
    /// the scaled error (Hairer's combination of the 5th- and 3rd-order estimates).
    fn trial<S: OdeSystem + ?Sized>(&mut self, sys: &mut S, t: f64, y: &[f64], h: f64) -> Trial {
        let n = self.dim;
        let Work { k, ys, y_new, .. } = &mut self.work;
        k[..n].copy_from_slice(&self.f0);
        for s in 1..STAGES {
            combine(n, y, h, k, A[s], ys);
            let ts = if s == STAGES - 1 { t + h } else { t + C[s] * h };
            let ks = &mut k[s * n..(s + 1) * n];
            sys.rhs(ts, ys, ks);
            self.stats.rhs_evals += 1;
            if !all_finite(ks) {
                return Trial::NonFinite;
            }
        }
        let (rtol, atol) = (self.cfg.rtol, self.cfg.atol);
        let (mut err5, mut err3) = (0.0, 0.0);
        for i in 0..n {
            let kk = |j: usize| k[j * n + i];
            let bk: f64 = B.iter().map(|&(j, b)| b * kk(j)).sum();
            y_new[i] = y[i] + h * bk;
            let e3 = bk - BHH.iter().map(|&(j, b)| b * kk(j)).sum::<f64>();
            let e5: f64 = ER.iter().map(|&(j, e)| e * kk(j)).sum();
            let sk = atol + rtol * y[i].abs().max(y_new[i].abs());
            err3 += (e3 / sk).powi(2);
            err5 += (e5 / sk).powi(2);
        }
        if !all_finite(y_new) {
            return Trial::NonFinite;
        }
        let mut deno = err5 + 0.01 * err3;
        if deno <= 0.0 {
            deno = 1.0;
        }
        let err = h.abs() * err5 * (1.0 / (n as f64 * deno)).sqrt();
        if err.is_finite() { Trial::Error(err) } else { Trial::NonFinite }
    }

    /// For an accepted trial: the FSAL stage at `(t_new, y_new)` and the three dense-output
    /// stages. `false` if any is non-finite (the trial must then be rejected).
    fn extra_stages<S: OdeSystem + ?Sized>(&mut self, sys: &mut S, t: f64, y: &[f64], h: f64, t_new: f64) -> bool {
        let n = self.dim;
        let Work { k, ys, y_new, .. } = &mut self.work;
        {
            let kf = &mut k[FSAL * n..(FSAL + 1) * n];
            sys.rhs(t_new, y_new, kf);
            self.stats.rhs_evals += 1;
            if !all_finite(kf) {
                return false;
            }
        }
        for s in FSAL + 1..STAGES_EXT {
            combine(n, y, h, k, A[s], ys);
            let ks = &mut k[s * n..(s + 1) * n];
            sys.rhs(t + C[s] * h, ys, ks);
            self.stats.rhs_evals += 1;
            if !all_finite(ks) {
                return false;
            }
        }
        true
    }

    /// Stores the accepted step: dense coefficients, new state, FSAL derivative.
    fn commit(&mut self, t: &mut f64, y: &mut [f64], h: f64, t_new: f64) {
        let n = self.dim;
        let Work { k, y_new, .. } = &self.work;
        for i in 0..n {
            let kk = |j: usize| k[j * n + i];
            let ydiff = y_new[i] - y[i];
            let bspl = h * kk(0) - ydiff;
            self.cont[i] = y[i];
            self.cont[n + i] = ydiff;
            self.cont[2 * n + i] = bspl;
            self.cont[3 * n + i] = ydiff - h * kk(FSAL) - bspl;
            for (r, row) in D.iter().enumerate() {
                let acc: f64 = row.iter().map(|&(j, d)| d * kk(j)).sum();
                self.cont[(4 + r) * n + i] = h * acc;
            }
        }
        self.dense_valid = true;
        self.t_old = *t;
        self.t_new = t_new;
        self.h_step = h;
        y.copy_from_slice(y_new);
        *t = t_new;
        self.y_end.copy_from_slice(y_new);
        self.y_cur.copy_from_slice(y_new);
        self.f0.copy_from_slice(&k[FSAL * n..(FSAL + 1) * n]);
        self.t_cur = t_new;
        self.f0_valid = true;
        self.stats.accepted += 1;
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

    /// One accepted step from `(t, y)`, never beyond `t_max` (`> t`): on return `t` is the new
    /// time (exactly `t_max` if the step was cut short there) and `y` the new state; dense
    /// output and event location then cover `[t_old, t]`.
    ///
    /// Step size: the remembered proposal `h`, or `t_max - t` if `1.01 h >= t_max - t`
    /// (Hairer's rule, which avoids a sliver step). A step cut short by `t_max` does not
    /// shrink the proposal for the next one. Rejected attempts are retried with a smaller
    /// step within this call. On error, `t` and `y` are unchanged.
    pub fn step<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &mut S,
        t: &mut f64,
        y: &mut [f64],
        t_max: f64,
    ) -> Result<(), OdeError> {
        self.check_inputs(*t, y, t_max)?;
        self.ensure_work();
        let t0 = *t;
        self.prepare_start(sys, t0, y)?;
        let remaining = t_max - t0;
        let mut h_prop = match self.h_prop {
            Some(h) => h,
            None => self.initial_step(sys, t0, y, remaining),
        };
        let cfg = self.cfg.clone();
        if let Some(h_max) = cfg.h_max {
            h_prop = h_prop.min(h_max);
        }
        let expo1 = 1.0 / 8.0 - cfg.beta * 0.2;
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
            let err = match self.trial(sys, t0, y, h) {
                Trial::Error(err) if err <= 1.0 => {
                    if self.extra_stages(sys, t0, y, h, t_new) {
                        Some(err)
                    } else {
                        None
                    }
                }
                Trial::Error(err) => {
                    // Rejected by the error test: h_new = h / min(1/fac_min, err^expo1 / safety).
                    let fac11 = err.powf(expo1);
                    h_prop = h / (1.0 / cfg.fac_min).min(fac11 / cfg.safety);
                    last_non_finite = false;
                    self.stats.rejected += 1;
                    rejections += 1;
                    if rejections >= cfg.max_consecutive_rejections {
                        return Err(OdeError::TooManyRejections { t: t0, h, rejections });
                    }
                    continue;
                }
                Trial::NonFinite => None,
            };
            let Some(err) = err else {
                // Non-finite values: retry with the largest allowed reduction.
                h_prop = h * cfg.fac_min;
                last_non_finite = true;
                self.stats.rejected += 1;
                self.stats.rejected_non_finite += 1;
                rejections += 1;
                if rejections >= cfg.max_consecutive_rejections {
                    return Err(OdeError::NonFiniteStep { t: t0, h, rejections });
                }
                continue;
            };
            // Accepted. New proposal (Hairer): h / clamp(err^expo1 / facold^beta / safety,
            // 1/fac_max, 1/fac_min), no growth right after a rejection, at most h_max.
            let fac11 = err.powf(expo1);
            let fac = (fac11 / self.facold.powf(cfg.beta) / cfg.safety).clamp(1.0 / cfg.fac_max, 1.0 / cfg.fac_min);
            let mut h_new = h / fac;
            if rejections > 0 {
                h_new = h_new.min(h);
            }
            let cut_short = clamped && h < h_prop;
            if cut_short {
                // The step was shortened by t_max: its error estimate (often dominated by
                // round-off for a short step) says nothing against the larger proposal.
                h_new = h_new.max(h_prop);
            } else {
                self.facold = err.max(1e-4);
            }
            if let Some(h_max) = cfg.h_max {
                h_new = h_new.min(h_max);
            }
            self.h_prop = Some(h_new);
            self.commit(t, y, h, t_new);
            return Ok(());
        }
    }

    /// One step of exactly size `h > 0` without error control (always accepted; for
    /// convergence tests and diagnostics). Dense output covers the step afterwards. Fails only
    /// on non-finite values. Does not change the step-size proposal.
    pub fn step_fixed<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &mut S,
        t: &mut f64,
        y: &mut [f64],
        h: f64,
    ) -> Result<(), OdeError> {
        let t0 = *t;
        self.check_inputs(t0, y, t0 + h)?;
        self.ensure_work();
        self.prepare_start(sys, t0, y)?;
        let t_new = t0 + h;
        let ok = match self.trial(sys, t0, y, h) {
            Trial::Error(_) => self.extra_stages(sys, t0, y, h, t_new),
            Trial::NonFinite => false,
        };
        if !ok {
            self.stats.rejected += 1;
            self.stats.rejected_non_finite += 1;
            return Err(OdeError::NonFiniteStep { t: t0, h, rejections: 1 });
        }
        self.commit(t, y, h, t_new);
        Ok(())
    }

    /// The error-estimator parts of a trial step of size `h` from `(t, y)`, without
    /// committing it: `(y_new, e5, e3)` with `h * e5` and `h * e3` the 5th- and 3rd-order
    /// local error estimates. For tests of the coefficients' orders.
    #[doc(hidden)]
    pub fn probe_step<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &mut S,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Result<ProbeStep, OdeError> {
        self.check_inputs(t, y, t + h)?;
        self.ensure_work();
        self.prepare_start(sys, t, y)?;
        if let Trial::NonFinite = self.trial(sys, t, y, h) {
            return Err(OdeError::NonFiniteStep { t, h, rejections: 1 });
        }
        let n = self.dim;
        let k = &self.work.k;
        let (mut e5, mut e3) = (vec![0.0; n], vec![0.0; n]);
        for i in 0..n {
            let kk = |j: usize| k[j * n + i];
            let bk: f64 = B.iter().map(|&(j, b)| b * kk(j)).sum();
            e3[i] = h * (bk - BHH.iter().map(|&(j, b)| b * kk(j)).sum::<f64>());
            e5[i] = h * ER.iter().map(|&(j, e)| e * kk(j)).sum::<f64>();
        }
        Ok((self.work.y_new.clone(), e5, e3))
    }
}
