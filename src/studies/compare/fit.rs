//! The fixed-step engine's bias as a function of the step, fitted over the stable points.
//!
//! A single point's error is its bias plus sampling noise, and at small steps the noise
//! dominates. The fixed-step scheme is consistent and first order (`docs/engines.md`,
//! `tests/suite/convergence.rs`), so its bias is modelled as `b(dt) = c1 dt + c2 dt^2` and fitted
//! by generalised least squares to every stable point's error, with the covariance
//! `C_ij = se_i^2 delta_ij + se_ref^2`: the errors share the reference's sampling error.
//! The fit's chi-square tests the model; a scheme that does not converge to the model (the
//! `as-printed` flip rule, or a bug) is rejected by it.

use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::{Status, Study};
use crate::scene::EngineKind;

/// The fitted bias model of one observable.
#[derive(Clone, Debug, PartialEq)]
pub struct BiasFit {
    /// Coefficients of `dt` and `dt^2` (only the first when one point is fitted).
    pub coef: Vec<f64>,
    /// Their covariance.
    pub cov: Vec<Vec<f64>>,
    pub chi2: f64,
    pub df: usize,
    /// Probability of a chi-square at least this large if the model holds (1 when `df = 0`).
    pub p_value: f64,
}

impl BiasFit {
    fn basis(&self, dt: f64) -> Vec<f64> {
        (1..=self.coef.len()).map(|k| dt.powi(k as i32)).collect()
    }
    /// Fitted bias at `dt` and its standard error.
    pub fn at(&self, dt: f64) -> (f64, f64) {
        let x = self.basis(dt);
        let b = x.iter().zip(&self.coef).map(|(x, c)| x * c).sum();
        let var: f64 = (0..x.len()).map(|i| (0..x.len()).map(|j| x[i] * self.cov[i][j] * x[j]).sum::<f64>()).sum();
        (b, var.max(0.0).sqrt())
    }
    /// Whether the model survives its chi-square test at level 0.001.
    pub fn accepted(&self) -> bool {
        self.p_value >= 1e-3
    }
}

/// Inverse of a symmetric positive-definite matrix (Gauss–Jordan); `None` if singular.
pub fn invert(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    let mut m = a.to_vec();
    let mut inv: Vec<Vec<f64>> = (0..n).map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect()).collect();
    for col in 0..n {
        let p = m[col][col];
        if !(p.is_finite() && p > 0.0) {
            return None;
        }
        for j in 0..n {
            m[col][j] /= p;
            inv[col][j] /= p;
        }
        for row in 0..n {
            if row != col {
                let f = m[row][col];
                for j in 0..n {
                    m[row][j] -= f * m[col][j];
                    inv[row][j] -= f * inv[col][j];
                }
            }
        }
    }
    Some(inv)
}

/// Generalised least squares of `y = X beta` with covariance `c`.
pub fn gls(x: &[Vec<f64>], y: &[f64], c: &[Vec<f64>]) -> Option<BiasFit> {
    let (k, p) = (y.len(), x[0].len());
    let ci = invert(c)?;
    // A = X' C^-1 X, g = X' C^-1 y.
    let mut a = vec![vec![0.0; p]; p];
    let mut g = vec![0.0; p];
    for i in 0..k {
        for j in 0..k {
            for u in 0..p {
                g[u] += x[i][u] * ci[i][j] * y[j];
                for v in 0..p {
                    a[u][v] += x[i][u] * ci[i][j] * x[j][v];
                }
            }
        }
    }
    let cov = invert(&a)?;
    let coef: Vec<f64> = (0..p).map(|u| (0..p).map(|v| cov[u][v] * g[v]).sum()).collect();
    let r: Vec<f64> = (0..k).map(|i| y[i] - (0..p).map(|u| x[i][u] * coef[u]).sum::<f64>()).collect();
    let chi2: f64 = (0..k).map(|i| (0..k).map(|j| r[i] * ci[i][j] * r[j]).sum::<f64>()).sum();
    let df = k - p;
    let p_value = if df == 0 { 1.0 } else { ChiSquared::new(df as f64).map_or(f64::NAN, |d| 1.0 - d.cdf(chi2)) };
    Some(BiasFit { coef, cov, chi2, df, p_value })
}

/// The bias model of observable `i` over the study's stable fixed-step points; `None` if no
/// point has a usable error.
pub fn bias_fit(study: &Study, i: usize) -> Option<BiasFit> {
    let pts: Vec<(f64, f64, f64)> = study
        .points
        .iter()
        .filter(|p| p.engine == EngineKind::Fixed && p.status == Status::Ok)
        .filter(|p| p.obs[i].error.is_finite() && p.obs[i].se.is_finite() && p.obs[i].se > 0.0)
        .map(|p| (p.dt.unwrap(), p.obs[i].error, p.obs[i].se))
        .collect();
    if pts.is_empty() {
        return None;
    }
    let se_ref = study.reference.stats[i].se;
    let params = pts.len().min(2);
    let x: Vec<Vec<f64>> = pts.iter().map(|p| (1..=params).map(|k| p.0.powi(k as i32)).collect()).collect();
    let y: Vec<f64> = pts.iter().map(|p| p.1).collect();
    let c: Vec<Vec<f64>> = (0..pts.len())
        .map(|a| (0..pts.len()).map(|b| se_ref * se_ref + if a == b { pts[a].2 * pts[a].2 } else { 0.0 }).collect())
        .collect();
    gls(&x, &y, &c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_data_are_fitted_exactly() {
        let dts = [0.5, 0.25, 0.125, 0.0625];
        let x: Vec<Vec<f64>> = dts.iter().map(|&d| vec![d, d * d]).collect();
        let y: Vec<f64> = dts.iter().map(|&d| -10.0 * d + 3.0 * d * d).collect();
        let c: Vec<Vec<f64>> =
            (0..4).map(|a| (0..4).map(|b| 0.01 + if a == b { 0.04 } else { 0.0 }).collect()).collect();
        let f = gls(&x, &y, &c).unwrap();
        assert!((f.coef[0] + 10.0).abs() < 1e-9 && (f.coef[1] - 3.0).abs() < 1e-9, "{f:?}");
        assert!(f.chi2 < 1e-12 && f.df == 2 && f.p_value > 0.999);
        let (b, se) = f.at(0.1);
        assert!((b - (-1.0 + 0.03)).abs() < 1e-9 && se > 0.0);
    }

    #[test]
    fn a_constant_offset_is_rejected() {
        // Errors of 1 at every step, with standard errors 0.01: no c1 dt + c2 dt^2 fits.
        let dts = [0.5, 0.25, 0.125, 0.0625, 0.03125];
        let x: Vec<Vec<f64>> = dts.iter().map(|&d| vec![d, d * d]).collect();
        let y = vec![1.0; 5];
        let c: Vec<Vec<f64>> = (0..5).map(|a| (0..5).map(|b| if a == b { 1e-4 } else { 0.0 }).collect()).collect();
        assert!(!gls(&x, &y, &c).unwrap().accepted());
    }
}
