//! The friction law's smooth form, fitted by (weighted) linear least squares.
//!
//! The form is a polynomial of total degree `d` (1 or 2) in
//!
//! ```text
//! x = ln(V / V0),   y = T_ref / T - 1   (V0 = l0 / t0, the velocity unit; T in kelvin)
//! mu(V, T) = sum over i + j <= d of c_ij x^i y^j
//! ```
//!
//! plus a term `c_v V / V0` linear in the velocity: the plate's viscous force `eta V` is part
//! of the friction at the driving spring and grows linearly, not logarithmically, in `V`. At
//! `d = 1` the form is the rate-and-state steady form `mu0 + (a - b) ln(V / V0)` with an
//! Arrhenius-like term in `1/T` (and the viscous term); at `d = 2` it can hold a maximum in
//! `V` or `T`. A term is used only when the data can determine it: `x^i` needs more than `i`
//! distinct `x`, `y^j` more than `j` distinct `y`, `V / V0` at least `d + 2` distinct `x`
//! (it is not a polynomial in `x`), and the terms must be no more than the points; when the
//! design is still singular the degree is lowered (and said).
//!
//! With a standard error `sigma_i` for every point (two replicas or more) the fit minimises
//! `chi^2 = sum ((mu_i - mu(V_i, T_i)) / sigma_i)^2`; the parameters' standard errors are
//! the square roots of the diagonal of `(A^T W A)^-1`, `W = diag(1 / sigma_i^2)`, and the
//! goodness of fit is `chi^2` on `n - p` degrees of freedom with its upper-tail probability.
//! Without (one replica) it is ordinary least squares and the standard errors are scaled
//! by the residual variance `RSS / (n - p)`.
//!
//! The solve is a Householder QR of the column-scaled, row-weighted design matrix (no
//! normal equations: their condition number is the square of the matrix's).

use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// A term of the form: `x^i y^j`, or `V / V0 = exp(x)` when `linear_v`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Term {
    /// Power of `x = ln(V / V0)`.
    pub i: u32,
    /// Power of `y = T_ref / T - 1`.
    pub j: u32,
    /// The term linear in the velocity, `V / V0` (`i = j = 0`).
    pub linear_v: bool,
}

impl Term {
    /// The term as text, e.g. `x^2*y`.
    pub fn name(&self) -> String {
        if self.linear_v {
            return "V/V0".to_string();
        }
        let p = |v: &str, k: u32| match k {
            0 => None,
            1 => Some(v.to_string()),
            k => Some(format!("{v}^{k}")),
        };
        let parts: Vec<String> = [p("x", self.i), p("y", self.j)].into_iter().flatten().collect();
        if parts.is_empty() { "1".to_string() } else { parts.join("*") }
    }

    /// The term's value at `(x, y)`.
    pub fn eval(&self, x: f64, y: f64) -> f64 {
        if self.linear_v {
            return x.exp();
        }
        x.powi(self.i as i32) * y.powi(self.j as i32)
    }
}

/// One point to fit: `z` at `(x, y)`, with its standard error when known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitPoint {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub sigma: Option<f64>,
}

/// A fitted form.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fit {
    /// The degree asked for.
    pub degree_requested: u32,
    /// The degree fitted (lower when the data cannot determine the requested one).
    pub degree: u32,
    pub terms: Vec<Term>,
    pub coefficients: Vec<f64>,
    /// Standard errors of the coefficients (`None` with as many terms as points and no
    /// standard errors of the points).
    pub standard_errors: Vec<Option<f64>>,
    /// `z_i - fit(x_i, y_i)`, in the order of the points.
    pub residuals: Vec<f64>,
    /// Whether the points' standard errors weighted the fit.
    pub weighted: bool,
    /// Points less terms.
    pub dof: usize,
    /// `sum (r_i / sigma_i)^2` (weighted fits only).
    pub chi_square: Option<f64>,
    /// `P(chi^2_dof >= chi_square)` (weighted, `dof > 0`).
    pub p_value: Option<f64>,
    /// `sqrt(sum r_i^2 / n)`.
    pub rms_residual: f64,
}

impl Fit {
    /// The fitted form at `(x, y)`.
    pub fn eval(&self, x: f64, y: f64) -> f64 {
        self.terms.iter().zip(&self.coefficients).map(|(t, c)| c * t.eval(x, y)).sum()
    }
}

/// Why no form could be fitted.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FitError {
    #[error("no steady point to fit")]
    NoPoints,
    #[error("the points do not determine even a constant")]
    Singular,
}

/// The terms of total degree at most `degree` that `dx` distinct `x` and `dy` distinct `y`
/// can determine, in the order `1, x, y, x^2, x*y, y^2`, then `V/V0`.
pub fn terms(degree: u32, dx: usize, dy: usize) -> Vec<Term> {
    let mut t = Vec::new();
    for d in 0..=degree {
        for i in (0..=d).rev() {
            let j = d - i;
            if (i as usize) < dx && (j as usize) < dy {
                t.push(Term { i, j, linear_v: false });
            }
        }
    }
    if dx >= degree as usize + 2 {
        t.push(Term { i: 0, j: 0, linear_v: true });
    }
    t
}

fn distinct(mut v: Vec<f64>) -> usize {
    v.sort_by(f64::total_cmp);
    v.dedup();
    v.len()
}

/// Fits the form of degree `degree` (lowered while the data cannot determine it) to
/// `points`. Standard errors weight the fit only when every point has a finite one > 0.
pub fn fit(points: &[FitPoint], degree: u32) -> Result<Fit, FitError> {
    if points.is_empty() {
        return Err(FitError::NoPoints);
    }
    let dx = distinct(points.iter().map(|p| p.x).collect());
    let dy = distinct(points.iter().map(|p| p.y).collect());
    let sigma: Option<Vec<f64>> =
        points.iter().map(|p| p.sigma.filter(|s| s.is_finite() && *s > 0.0)).collect::<Option<Vec<f64>>>();
    for d in (0..=degree).rev() {
        let terms = terms(d, dx, dy);
        if terms.len() > points.len() {
            continue;
        }
        if let Some(f) = solve(points, &terms, sigma.as_deref()) {
            return Ok(finish(points, degree, d, terms, f, sigma.as_deref()));
        }
    }
    Err(FitError::Singular)
}

/// Coefficients and `(A^T W A)^-1` of a weighted least-squares solve, or `None` if the
/// design is singular.
struct Solved {
    coefficients: Vec<f64>,
    covariance: Vec<Vec<f64>>,
}

fn solve(points: &[FitPoint], terms: &[Term], sigma: Option<&[f64]>) -> Option<Solved> {
    let (n, p) = (points.len(), terms.len());
    let w = |k: usize| sigma.map_or(1.0, |s| 1.0 / s[k]);
    // Row-weighted design matrix (column-major) and right-hand side.
    let mut a: Vec<Vec<f64>> =
        terms.iter().map(|t| (0..n).map(|k| w(k) * t.eval(points[k].x, points[k].y)).collect()).collect();
    let mut b: Vec<f64> = (0..n).map(|k| w(k) * points[k].z).collect();
    // Column scaling, so that the rank test compares like with like.
    let scale: Vec<f64> = a.iter().map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt()).collect();
    if scale.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return None;
    }
    for (c, s) in a.iter_mut().zip(&scale) {
        c.iter_mut().for_each(|v| *v /= s);
    }
    // Householder QR: A = Q R, R stored in the upper triangle of `a`.
    let mut diag = vec![0.0; p];
    for j in 0..p {
        let norm = a[j][j..].iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm == 0.0 {
            return None;
        }
        let alpha = if a[j][j] > 0.0 { -norm } else { norm };
        let mut v: Vec<f64> = a[j][j..].to_vec();
        v[0] -= alpha;
        let vv = v.iter().map(|x| x * x).sum::<f64>();
        let reflect = |col: &mut [f64]| {
            let d = v.iter().zip(col.iter()).map(|(x, y)| x * y).sum::<f64>() * 2.0 / vv;
            col.iter_mut().zip(&v).for_each(|(c, x)| *c -= d * x);
        };
        for col in a.iter_mut().skip(j) {
            reflect(&mut col[j..]);
        }
        reflect(&mut b[j..]);
        diag[j] = a[j][j];
    }
    let largest = diag.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    if diag.iter().any(|d| d.abs() <= 1e-10 * largest) {
        return None;
    }
    // R c' = Q^T b, then c = c' / scale.
    let r = |i: usize, j: usize| a[j][i];
    let mut c = vec![0.0; p];
    for i in (0..p).rev() {
        let s: f64 = (i + 1..p).map(|j| r(i, j) * c[j]).sum();
        c[i] = (b[i] - s) / r(i, i);
    }
    // R^-1 (upper triangular), then (A^T W A)^-1 = D^-1 R^-1 R^-T D^-1.
    // Column k of R^-1 solves R u = e_k.
    let mut rinv_cols: Vec<Vec<f64>> = Vec::with_capacity(p);
    for k in 0..p {
        let mut u = vec![0.0; p];
        for i in (0..=k).rev() {
            let e = if i == k { 1.0 } else { 0.0 };
            let s: f64 = (i + 1..=k).map(|j| r(i, j) * u[j]).sum();
            u[i] = (e - s) / r(i, i);
        }
        rinv_cols.push(u);
    }
    let covariance = (0..p)
        .map(|i| (0..p).map(|j| rinv_cols.iter().map(|u| u[i] * u[j]).sum::<f64>() / (scale[i] * scale[j])).collect())
        .collect();
    let coefficients = c.iter().zip(&scale).map(|(c, s)| c / s).collect();
    Some(Solved { coefficients, covariance })
}

fn finish(points: &[FitPoint], requested: u32, degree: u32, terms: Vec<Term>, s: Solved, sigma: Option<&[f64]>) -> Fit {
    let (n, p) = (points.len(), terms.len());
    let mut f = Fit {
        degree_requested: requested,
        degree,
        terms,
        coefficients: s.coefficients,
        standard_errors: Vec::new(),
        residuals: Vec::new(),
        weighted: sigma.is_some(),
        dof: n - p,
        chi_square: None,
        p_value: None,
        rms_residual: 0.0,
    };
    f.residuals = points.iter().map(|q| q.z - f.eval(q.x, q.y)).collect();
    let rss: f64 = f.residuals.iter().map(|r| r * r).sum();
    f.rms_residual = (rss / n as f64).sqrt();
    let variance_scale = match sigma {
        Some(sig) => {
            let chi2: f64 = f.residuals.iter().zip(sig).map(|(r, s)| (r / s) * (r / s)).sum();
            f.chi_square = Some(chi2);
            f.p_value = ChiSquared::new(f.dof as f64).ok().filter(|_| f.dof > 0).map(|d| 1.0 - d.cdf(chi2));
            Some(1.0)
        }
        None => (f.dof > 0).then(|| rss / f.dof as f64),
    };
    f.standard_errors = (0..p).map(|i| variance_scale.map(|v| (v * s.covariance[i][i]).sqrt())).collect();
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terms_follow_what_the_data_determine() {
        let names = |d, dx, dy| terms(d, dx, dy).iter().map(Term::name).collect::<Vec<_>>().join(" ");
        assert_eq!(names(2, 5, 5), "1 x y x^2 x*y y^2 V/V0");
        assert_eq!(names(2, 5, 2), "1 x y x^2 x*y V/V0");
        assert_eq!(names(2, 3, 1), "1 x x^2");
        assert_eq!(names(1, 3, 2), "1 x y V/V0");
        assert_eq!(names(1, 1, 1), "1");
    }

    #[test]
    fn exact_data_give_their_coefficients_and_zero_residuals() {
        let truth = [0.3, -0.02, 0.05, 0.004, -0.003, 0.01, 0.07];
        let mut pts = Vec::new();
        for v in [0.1f64, 0.3, 1.0, 3.0, 10.0] {
            for t in [0.5f64, 1.0, 2.0, 4.0] {
                let (x, y) = (v.ln(), 1.0 / t - 1.0);
                let z: f64 = terms(2, 9, 9).iter().zip(truth).map(|(tm, c)| c * tm.eval(x, y)).sum();
                pts.push(FitPoint { x, y, z, sigma: Some(0.01) });
            }
        }
        let f = fit(&pts, 2).unwrap();
        assert_eq!(f.degree, 2);
        for (c, t) in f.coefficients.iter().zip(truth) {
            assert!((c - t).abs() < 1e-12, "{c} against {t}");
        }
        assert!(f.chi_square.unwrap() < 1e-20 && f.dof == 13);
    }

    #[test]
    fn a_design_that_cannot_hold_the_degree_is_lowered() {
        // Three points on a line x = y: degree 2 asks for 1, x, y, x^2, xy, y^2 (6 terms > 3
        // points), degree 1 for 1, x, y, V/V0 (4 > 3); degree 0 is 1 and V/V0.
        let pts: Vec<FitPoint> =
            (0..3).map(|k| FitPoint { x: k as f64, y: k as f64, z: 1.0 + (k as f64).exp(), sigma: None }).collect();
        let f = fit(&pts, 2).unwrap();
        assert_eq!((f.degree, f.dof), (0, 1));
        assert_eq!(f.terms.iter().map(Term::name).collect::<Vec<_>>(), ["1", "V/V0"]);
        assert!((f.coefficients[0] - 1.0).abs() < 1e-12 && (f.coefficients[1] - 1.0).abs() < 1e-12);
        assert!(f.standard_errors.iter().all(Option::is_some) && f.chi_square.is_none());
        // A collinear design is singular and lowered too: x and y equal, degree 1 without V.
        let f = fit(&pts[..2], 1).unwrap();
        assert_eq!(f.degree, 0);
        assert_eq!(fit(&[], 2), Err(FitError::NoPoints));
    }
}
