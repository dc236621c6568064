//! Statistics shared by the statistical tests: every tolerance comes from here, derived
//! from a distribution (KS, chi-square, Student t), never hand-tuned. Scenes and run
//! helpers are the test kit's (`stickslip_testkit`).
#![allow(dead_code)]

pub mod moments;
pub mod renewal;
pub mod svg;

use statrs::distribution::{ChiSquared, ContinuousCDF, StudentsT};

/// Significance level of every statistical test in the suite.
pub const ALPHA: f64 = 1e-3;

/// Kolmogorov–Smirnov statistic `D = sup |F_n - F|` of `samples` against the cdf `f`.
pub fn ks_statistic(samples: &mut [f64], cdf: impl Fn(f64) -> f64) -> f64 {
    samples.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let n = samples.len() as f64;
    samples.iter().enumerate().fold(0.0f64, |d, (i, &x)| {
        let f = cdf(x);
        d.max((i as f64 + 1.0) / n - f).max(f - i as f64 / n)
    })
}

/// Asymptotic KS critical value at level `alpha` for `n` samples: `sqrt(ln(2/alpha)/2)/sqrt(n)`.
pub fn ks_critical(n: usize, alpha: f64) -> f64 {
    ((2.0 / alpha).ln() / 2.0).sqrt() / (n as f64).sqrt()
}

/// Two-sample Kolmogorov–Smirnov statistic `D = sup |F_a - F_b|` of the empirical cdfs.
pub fn ks_two_sample(a: &mut [f64], b: &mut [f64]) -> f64 {
    a.sort_by(|x, y| x.partial_cmp(y).unwrap());
    b.sort_by(|x, y| x.partial_cmp(y).unwrap());
    let (n, m) = (a.len() as f64, b.len() as f64);
    let (mut i, mut j, mut d) = (0, 0, 0.0f64);
    while i < a.len() && j < b.len() {
        let x = a[i].min(b[j]);
        while i < a.len() && a[i] <= x {
            i += 1;
        }
        while j < b.len() && b[j] <= x {
            j += 1;
        }
        d = d.max((i as f64 / n - j as f64 / m).abs());
    }
    d
}

/// Asymptotic two-sample KS critical value at level `alpha` for samples of `n` and `m`:
/// `sqrt(ln(2/alpha)/2) sqrt((n + m)/(n m))`.
pub fn ks_two_sample_critical(n: usize, m: usize, alpha: f64) -> f64 {
    let (n, m) = (n as f64, m as f64);
    ((2.0 / alpha).ln() / 2.0).sqrt() * ((n + m) / (n * m)).sqrt()
}

/// Upper `1 - alpha` quantile of chi-square with `df` degrees of freedom.
pub fn chi2_critical(df: usize, alpha: f64) -> f64 {
    ChiSquared::new(df as f64).unwrap().inverse_cdf(1.0 - alpha)
}

/// Pearson chi-square of `observed` counts against `expected` counts, merging adjacent bins
/// from both ends until each expected count is at least 5. Returns (statistic, df).
pub fn chi_square(observed: &[f64], expected: &[f64]) -> (f64, usize) {
    let mut bins: Vec<(f64, f64)> = Vec::new();
    let (mut o, mut e) = (0.0, 0.0);
    for (&oi, &ei) in observed.iter().zip(expected) {
        o += oi;
        e += ei;
        if e >= 5.0 {
            bins.push((o, e));
            o = 0.0;
            e = 0.0;
        }
    }
    if let Some(last) = bins.last_mut() {
        last.0 += o;
        last.1 += e;
    }
    let stat = bins.iter().map(|(o, e)| (o - e) * (o - e) / e).sum();
    (stat, bins.len() - 1)
}

/// Mean of `x` and the half-width of its two-sided `1 - alpha` Student-t confidence interval.
pub fn mean_ci(x: &[f64], alpha: f64) -> (f64, f64) {
    let (n, m, var) = moments(x);
    (m, t_critical(n - 1.0, alpha) * (var / n).sqrt())
}

/// Size, mean and unbiased variance of the sample `x`.
fn moments(x: &[f64]) -> (f64, f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    (n, m, x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (n - 1.0))
}

/// Two-sided `1 - alpha` critical value of Student's t with `df` degrees of freedom.
fn t_critical(df: f64, alpha: f64) -> f64 {
    StudentsT::new(0.0, 1.0, df).unwrap().inverse_cdf(1.0 - alpha / 2.0)
}

/// Welch's two-sample test of equal means ([`welch`]).
#[derive(Clone, Copy, Debug)]
pub struct Welch {
    /// Difference of the sample means, `mean(x) - mean(y)`.
    pub diff: f64,
    /// Its standard error `sqrt(s_x^2/n_x + s_y^2/n_y)`.
    pub se: f64,
    /// Welch–Satterthwaite degrees of freedom.
    pub df: f64,
    /// Two-sided critical value of `|diff| / se`: the `1 - alpha/2` quantile of Student t(df).
    pub critical: f64,
}

impl Welch {
    /// Whether the means differ significantly: `|diff| > critical se`.
    pub fn rejects(&self) -> bool {
        self.diff.abs() > self.critical * self.se
    }
    /// The true difference this test detects with probability `power` (normal approximation
    /// to the non-central t): `(critical + z_power) se`.
    pub fn detectable(&self, power: f64) -> f64 {
        use statrs::distribution::Normal;
        (self.critical + Normal::new(0.0, 1.0).unwrap().inverse_cdf(power)) * self.se
    }
}

/// Welch's t test of `mean(x) = mean(y)` for independent samples of unequal variances, at
/// two-sided level `alpha`: `t = (mean x - mean y) / sqrt(s_x^2/n_x + s_y^2/n_y)`,
/// `df = (a + b)^2 / (a^2/(n_x - 1) + b^2/(n_y - 1))`, `a = s_x^2/n_x`, `b = s_y^2/n_y`.
pub fn welch(x: &[f64], y: &[f64], alpha: f64) -> Welch {
    let ((nx, mx, vx), (ny, my, vy)) = (moments(x), moments(y));
    let (a, b) = (vx / nx, vy / ny);
    let df = (a + b) * (a + b) / (a * a / (nx - 1.0) + b * b / (ny - 1.0));
    let critical = t_critical(df, alpha);
    Welch { diff: mx - my, se: (a + b).sqrt(), df, critical }
}
