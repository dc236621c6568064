//! Statistics across the replicas of a study: means, spreads and 95 % Student-t intervals.
//!
//! Sums run in replica order, so the same replicas give the same bytes whatever the number
//! of threads that produced them.

use statrs::distribution::{ContinuousCDF, StudentsT};

/// Two-sided 95 % Student-t quantile `t_{0.975, df}`; the normal one (1.96) when `df` is not
/// a usable number (not finite or not > 0).
pub fn t_quantile(df: f64) -> f64 {
    match StudentsT::new(0.0, 1.0, df) {
        Ok(t) if df.is_finite() && df > 0.0 => t.inverse_cdf(0.975),
        _ => 1.959_963_984_540_054,
    }
}

/// Mean of `x` and the half-width of its two-sided 95 % Student-t confidence interval,
/// `t_{0.975, n-1} sqrt(s^2 / n)` with `s^2` the sample variance (`NaN` for a single value).
pub fn mean_ci95(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    if x.len() < 2 {
        return (m, f64::NAN);
    }
    let var = x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (n - 1.0);
    (m, t_quantile(n - 1.0) * (var / n).sqrt())
}

/// Mean, standard deviation and standard error of one quantity over replicas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReplicaStats {
    /// Number of replicas.
    pub n: usize,
    pub mean: f64,
    /// Standard deviation of one replica's value (`NaN` for a single replica).
    pub sd: f64,
    /// Standard error of the mean, `sd / sqrt(n)`.
    pub se: f64,
}

impl ReplicaStats {
    /// Over `values`; if any replica lacks the value (`None`: a weak-bond run without a
    /// rupture in its window) every field is NaN and `n` is 0.
    pub fn of(values: impl Iterator<Item = Option<f64>>) -> ReplicaStats {
        let v: Option<Vec<f64>> = values.collect();
        let Some(v) = v else { return ReplicaStats { n: 0, mean: f64::NAN, sd: f64::NAN, se: f64::NAN } };
        let n = v.len();
        let mean = v.iter().sum::<f64>() / n as f64;
        let sd = if n > 1 {
            (v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n as f64 - 1.0)).sqrt()
        } else {
            f64::NAN
        };
        ReplicaStats { n, mean, sd, se: sd / (n as f64).sqrt() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn student_t_quantile() {
        assert!((t_quantile(f64::INFINITY) - 1.96).abs() < 1e-3);
        assert!((t_quantile(10.0) - 2.228).abs() < 1e-3);
        assert_eq!(t_quantile(f64::NAN), t_quantile(0.0));
    }

    #[test]
    fn ci_of_known_sample() {
        // t_{0.975, 3} = 3.182446305284263
        let (m, c) = mean_ci95(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(m, 2.5);
        let s = (5.0f64 / 3.0).sqrt();
        assert!((c - 3.182446305284263 * s / 2.0).abs() < 1e-12);
        assert!(mean_ci95(&[1.0]).1.is_nan());
    }

    #[test]
    fn replica_stats_of_known_sample() {
        let s = ReplicaStats::of([1.0, 2.0, 3.0, 4.0].into_iter().map(Some));
        assert_eq!((s.n, s.mean), (4, 2.5));
        assert!((s.sd - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!((s.se - s.sd / 2.0).abs() < 1e-15);
        let missing = ReplicaStats::of([Some(1.0), None].into_iter());
        assert_eq!(missing.n, 0);
        assert!(missing.mean.is_nan() && missing.se.is_nan());
        assert!(ReplicaStats::of(std::iter::once(Some(3.0))).sd.is_nan());
    }
}
