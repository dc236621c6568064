//! THROWAWAY stand-ins for `physics::series::SeriesSum` (h-series) and
//! `ode::rosenbrock::Rosenbrock` (h-rosen), with their public API, until those land.
#![allow(dead_code)]

use serde::{Deserialize, Serialize};

use crate::ode::{OdeError, OdeStats};
use crate::physics::{ForceLaw, Tilted};

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SeriesSum {
    law: Tilted,
    anchors: Vec<f64>,
    free: Vec<u32>,
    base: f64,
    len: usize,
}

impl SeriesSum {
    pub fn new(law: Tilted, _rtol: f64) -> SeriesSum {
        SeriesSum { law, anchors: Vec::new(), free: Vec::new(), base: 0.0, len: 0 }
    }
    pub fn add(&mut self, c: f64) -> u32 {
        self.len += 1;
        if let Some(h) = self.free.pop() {
            self.anchors[h as usize] = c;
            h
        } else {
            self.anchors.push(c);
            (self.anchors.len() - 1) as u32
        }
    }
    pub fn remove(&mut self, _c: f64, h: u32) {
        self.anchors[h as usize] = f64::NAN;
        self.free.push(h);
        self.len -= 1;
    }
    pub fn rebase(&mut self, y0: f64) {
        self.base = y0;
    }
    pub fn shift(&mut self, dy: f64) {
        self.anchors.iter_mut().for_each(|c| *c -= dy);
        self.base -= dy;
    }
    pub fn base(&self) -> f64 {
        self.base
    }
    pub fn radius(&self) -> f64 {
        self.law.l0 / 8.0
    }
    pub fn force(&self, y: f64) -> f64 {
        self.anchors.iter().filter(|c| !c.is_nan()).map(|&c| self.law.force_x(y - c)).sum()
    }
    pub fn force_and_stiffness(&self, y: f64) -> (f64, f64) {
        let d = self.anchors.iter().filter(|c| !c.is_nan()).map(|&c| self.law.stiffness_x(y - c)).sum();
        (self.force(y), d)
    }
    pub fn integral(&self, y0: f64, y1: f64) -> f64 {
        // Potential: int f^x dx = kappa (x^2/2 - l0 sqrt(x^2 + l0^2)).
        let p = |x: f64| self.law.kappa * (0.5 * x * x - self.law.l0 * x.hypot(self.law.l0));
        self.anchors.iter().filter(|c| !c.is_nan()).map(|&c| p(y1 - c) - p(y0 - c)).sum()
    }
    pub fn error_bound(&self) -> f64 {
        0.0
    }
    pub fn stiffness_error_bound(&self) -> f64 {
        0.0
    }
    pub fn len(&self) -> usize {
        self.len
    }
}

pub trait StiffSystem {
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]);
    fn jacobian(&mut self, t: f64, y: &[f64], dfdy: &mut [f64], dfdt: &mut [f64]);
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RosenbrockConfig {
    pub rtol: f64,
    pub atol: f64,
    pub h_max: Option<f64>,
}

impl Default for RosenbrockConfig {
    fn default() -> Self {
        RosenbrockConfig { rtol: 1e-6, atol: 1e-9, h_max: None }
    }
}

/// Linearly implicit Euler with step doubling (order 2 by extrapolation), linear dense output.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Rosenbrock {
    dim: usize,
    cfg: RosenbrockConfig,
    h: f64,
    t_old: f64,
    t_new: f64,
    y_old: Vec<f64>,
    y_new: Vec<f64>,
    stats: OdeStats,
    has: bool,
}

fn solve(n: usize, a: &mut [f64], b: &mut [f64]) {
    for k in 0..n {
        let mut p = k;
        for i in k + 1..n {
            if a[i * n + k].abs() > a[p * n + k].abs() {
                p = i;
            }
        }
        if p != k {
            for j in 0..n {
                a.swap(k * n + j, p * n + j);
            }
            b.swap(k, p);
        }
        let d = a[k * n + k];
        for i in k + 1..n {
            let f = a[i * n + k] / d;
            for j in k..n {
                a[i * n + j] -= f * a[k * n + j];
            }
            b[i] -= f * b[k];
        }
    }
    for k in (0..n).rev() {
        let mut s = b[k];
        for j in k + 1..n {
            s -= a[k * n + j] * b[j];
        }
        b[k] = s / a[k * n + k];
    }
}

impl Rosenbrock {
    pub fn new(dim: usize, rtol: f64, atol: f64) -> Result<Self, OdeError> {
        Self::with_config(dim, RosenbrockConfig { rtol, atol, h_max: None })
    }
    pub fn with_config(dim: usize, cfg: RosenbrockConfig) -> Result<Self, OdeError> {
        Ok(Rosenbrock {
            dim,
            cfg,
            h: 0.0,
            t_old: 0.0,
            t_new: 0.0,
            y_old: vec![0.0; dim],
            y_new: vec![0.0; dim],
            stats: OdeStats::default(),
            has: false,
        })
    }
    fn euler<S: StiffSystem>(&self, sys: &mut S, t: f64, y: &[f64], h: f64, out: &mut [f64]) {
        let n = self.dim;
        let mut j = vec![0.0; n * n];
        let mut ft = vec![0.0; n];
        let mut f = vec![0.0; n];
        sys.jacobian(t, y, &mut j, &mut ft);
        sys.rhs(t, y, &mut f);
        let mut w = vec![0.0; n * n];
        for i in 0..n {
            for k in 0..n {
                w[i * n + k] = if i == k { 1.0 } else { 0.0 } - h * j[i * n + k];
            }
            f[i] += h * ft[i];
        }
        solve(n, &mut w, &mut f);
        for i in 0..n {
            out[i] = y[i] + h * f[i];
        }
    }
    pub fn step<S: StiffSystem>(
        &mut self,
        sys: &mut S,
        t: &mut f64,
        y: &mut [f64],
        t_max: f64,
    ) -> Result<(), OdeError> {
        let n = self.dim;
        if self.h <= 0.0 {
            self.h = 1e-6 * (t_max - *t).abs().max(1e-12);
        }
        loop {
            let mut h = self.h.min(t_max - *t);
            if let Some(m) = self.cfg.h_max {
                h = h.min(m);
            }
            let mut a = vec![0.0; n];
            let mut b = vec![0.0; n];
            let mut c = vec![0.0; n];
            self.euler(sys, *t, y, h, &mut a);
            self.euler(sys, *t, y, 0.5 * h, &mut b);
            self.euler(sys, *t + 0.5 * h, &b.clone(), 0.5 * h, &mut c);
            let mut err: f64 = 0.0;
            for i in 0..n {
                let sc = self.cfg.atol + self.cfg.rtol * y[i].abs().max(c[i].abs());
                err = err.max(((c[i] - a[i]) / sc).abs());
            }
            if err <= 1.0 || h < 1e-300 {
                self.stats.accepted += 1;
                self.t_old = *t;
                self.y_old.copy_from_slice(y);
                for i in 0..n {
                    y[i] = 2.0 * c[i] - a[i];
                }
                *t = if h == t_max - *t { t_max } else { *t + h };
                self.t_new = *t;
                self.y_new.copy_from_slice(y);
                self.has = true;
                self.h = h * (0.9 / err.max(1e-10).sqrt()).min(4.0);
                return Ok(());
            }
            self.stats.rejected += 1;
            self.h = h * (0.9 / err.sqrt()).max(0.1);
        }
    }
    pub fn dense(&self, t: f64, out: &mut [f64]) -> Result<(), OdeError> {
        let w = if self.t_new > self.t_old { (t - self.t_old) / (self.t_new - self.t_old) } else { 1.0 };
        for i in 0..self.dim {
            out[i] = self.y_old[i] + w * (self.y_new[i] - self.y_old[i]);
        }
        Ok(())
    }
    pub fn dense_component(&self, i: usize, t: f64) -> Result<f64, OdeError> {
        let w = if self.t_new > self.t_old { (t - self.t_old) / (self.t_new - self.t_old) } else { 1.0 };
        Ok(self.y_old[i] + w * (self.y_new[i] - self.y_old[i]))
    }
    pub fn component_bounds(&self, i: usize) -> Result<(f64, f64), OdeError> {
        Ok((self.y_old[i].min(self.y_new[i]), self.y_old[i].max(self.y_new[i])))
    }
    pub fn reset(&mut self) {}
    pub fn stats(&self) -> OdeStats {
        self.stats
    }
    pub fn h_proposal(&self) -> f64 {
        self.h
    }
    pub fn set_h_proposal(&mut self, h: f64) {
        self.h = h;
    }
    pub fn config(&self) -> &RosenbrockConfig {
        &self.cfg
    }
}
