//! The whole fit: the optimum (Nelder–Mead from the scene's values, restarted once from its
//! best point, and again from a lower point a profile finds), the goodness of fit, the
//! profile interval of every free parameter (the 2p sides of the profiles followed at the
//! same time), and the band of the fitted curve.

use statrs::distribution::{ChiSquared, ContinuousCDF, FisherSnedecor};

use super::intervals::{Interval, Side, interval, side};
use super::model::{Evaluation, FitError, Objective, Stage};
use super::optimise::{Settings, minimise};

/// Nelder–Mead iterations per free parameter, for each search of the optimum.
pub const ITERS_PER_PARAMETER: u64 = 80;

/// A profile point this far (chi2 units) below the optimum, and beyond the misfit's
/// simulation noise, restarts the search for the optimum from it (the report's flag "the
/// optimum may be local" uses the same level).
pub const RESTART_RISE: f64 = 0.5;

/// Restarts of the search for the optimum, at most.
pub const RESTARTS: usize = 2;

/// The optimiser's tolerance is at least this many times the misfit's simulation noise
/// ([`super::model::Problem::score_noise`]): a simplex at the bottom of a misfit with
/// independent noise of standard deviation `s` at each vertex has misfits whose sample
/// standard deviation is about `s`, so a smaller tolerance is met only by chance.
pub const NOISE_TOLERANCE: f64 = 1.0;

/// What a fit found.
#[derive(Clone, Debug)]
pub struct FitResult {
    /// The optimum in unit coordinates, and its evaluation.
    pub best_y: Vec<f64>,
    pub best: Evaluation,
    /// The minimised score (chi2, or SSR without sigma).
    pub score: f64,
    /// Sigma estimated from the residuals (no sigma column), `sqrt(SSR_min / (n - p))`.
    pub sigma_estimate: Option<f64>,
    /// `chi2` at the optimum (with sigma estimated: `n - p` by construction).
    pub chi2: f64,
    pub dof: usize,
    /// `P(chi2_dof >= chi2)`; `None` with sigma estimated or no degrees of freedom.
    pub p_value: Option<f64>,
    /// The rise of chi2 that bounds a one-parameter 95 % interval.
    pub threshold: f64,
    /// The rise of chi2 that bounds the joint 95 % region (for the band).
    pub band_threshold: f64,
    pub intervals: Vec<Interval>,
    /// Per data point, the least and greatest simulated friction over the evaluations in
    /// the joint 95 % region.
    pub band: Vec<(f64, f64)>,
    /// The simulation's noise beside the data's at the optimum: the largest `se_i / sigma_i`
    /// (sigma given or estimated). Well below 1 for intervals at their nominal coverage.
    pub noise_ratio: f64,
    pub evaluations: usize,
    /// Of `evaluations`, those the search for the optimum asked for (the others are the
    /// profiles').
    pub search_evaluations: usize,
}

/// A `noise_ratio` above this is reported: raise the replicas or the runs' length.
pub const NOISE_RATIO_WARN: f64 = 0.5;

fn quantile95(d: impl ContinuousCDF<f64, f64>) -> f64 {
    d.inverse_cdf(0.95)
}

/// Runs the fit on `obj`.
pub fn fit(obj: &Objective<'_>) -> Result<FitResult, FitError> {
    let prob = obj.problem;
    let (n, p) = (prob.data.len(), prob.free.len());
    let has_sigma = prob.data.has_sigma;
    let stopped = || obj.take_error().unwrap_or(FitError::Stopped { done: obj.evaluations() });
    // The lowest misfit asked for so far and its point (ties to the lesser point, so that
    // the record does not depend on which profile side asked first).
    let lowest = std::sync::Mutex::new((f64::INFINITY, Vec::new()));
    let score_y = |y: &[f64]| -> Option<f64> {
        let values: Vec<f64> = prob.free.iter().zip(y).map(|(f, &v)| f.value(v)).collect();
        let s = obj.score(&values)?;
        let mut low = lowest.lock().unwrap_or_else(|p| p.into_inner());
        if s < low.0 || (s == low.0 && y.partial_cmp(&low.1[..]) == Some(std::cmp::Ordering::Less)) {
            *low = (s, y.to_vec());
        }
        Some(s)
    };
    let start: Vec<f64> = prob.free.iter().map(|f| f.unit(f.start)).collect();
    // The misfit's unit before sigma is estimated: a sum of squares is compared with the
    // data's mean square.
    let mean_square = prob.data.points.iter().map(|q| q.friction * q.friction).sum::<f64>() / n as f64;
    let first_unit = if has_sigma { 1.0 } else { 1e-4 * mean_square.max(f64::MIN_POSITIVE) };
    let iters = ITERS_PER_PARAMETER * p as u64;
    // A search stops when its simplex's misfits spread less than the tolerance, never set
    // below NOISE_TOLERANCE times the misfit's simulation noise where the search starts:
    // below that, the simplex would only follow the noise.
    let noise_at = |y: &[f64]| -> Result<f64, FitError> {
        let values: Vec<f64> = prob.free.iter().zip(y).map(|(f, &v)| f.value(v)).collect();
        Ok(NOISE_TOLERANCE * prob.score_noise(&obj.evaluate(&values)?))
    };
    let tolerance = 1e-2 * first_unit;
    let s1 = Settings { step: 0.1, tolerance: tolerance.max(noise_at(&start)?), max_iters: iters, unit: first_unit };
    let (y1, v1) = minimise(&score_y, &start, s1).ok_or_else(stopped)?;
    let dof = n - p;
    let unit_of = |score: f64| if has_sigma { 1.0 } else { (score / dof as f64).max(f64::MIN_POSITIVE) };
    // The second search, and a restart's: from `from`, the better of its result and `from`.
    let refine = |from: Vec<f64>, at: f64| -> Result<(Vec<f64>, f64), FitError> {
        let unit = unit_of(at);
        let s2 = Settings { step: 0.05, tolerance: (1e-3 * unit).max(noise_at(&from)?), max_iters: iters, unit };
        let (y, v) = minimise(&score_y, &from, s2).ok_or_else(stopped)?;
        Ok(if at < v { (from, at) } else { (y, v) })
    };
    let (mut best_y, mut score) = refine(y1, v1)?;
    let mut search_evaluations = obj.asked();
    let (threshold, band_threshold) = if has_sigma {
        (quantile95(ChiSquared::new(1.0).expect("1 > 0")), quantile95(ChiSquared::new(p as f64).expect("p > 0")))
    } else {
        let d = dof as f64;
        (
            quantile95(FisherSnedecor::new(1.0, d).expect("dof > 0")),
            p as f64 * quantile95(FisherSnedecor::new(p as f64, d).expect("dof > 0")),
        )
    };
    let mut restarts = 0;
    let (intervals, unit) = loop {
        obj.set_stage(Stage::Profiles);
        let unit = unit_of(score);
        let noise = noise_at(&best_y)?;
        // The 2p sides of the profiles are independent searches: each on its own thread, so
        // that their evaluations run side by side (on the pool, or on a cluster). Each
        // side's evaluations, and so the intervals, do not depend on what runs next to it.
        let sides: Vec<Option<Side>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..p)
                .flat_map(|j| [(j, -1.0), (j, 1.0)])
                .map(|(j, dir)| {
                    let (score_y, best_y) = (&score_y, &best_y);
                    s.spawn(move || side(score_y, best_y, score, unit, threshold, j, dir, noise))
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap_or(None)).collect()
        });
        let mut intervals = Vec::with_capacity(p);
        let mut sides = sides.into_iter();
        for &y in &best_y {
            let (low, high) = (sides.next().flatten(), sides.next().flatten());
            let (Some(low), Some(high)) = (low, high) else { return Err(stopped()) };
            intervals.push(interval(y, threshold, low, high));
        }
        // A profile that found a misfit lower than the optimum by more than the noise (and
        // than RESTART_RISE) shows that the search stopped short: it is restarted there,
        // and the profiles are followed again from its result.
        let (low_score, low_y) = lowest.lock().unwrap_or_else(|p| p.into_inner()).clone();
        if restarts == RESTARTS || low_score >= score - (RESTART_RISE * unit).max(noise) {
            break (intervals, unit);
        }
        restarts += 1;
        obj.set_stage(Stage::Search);
        let asked = obj.asked();
        (best_y, score) = refine(low_y, low_score)?;
        search_evaluations += obj.asked() - asked;
    };
    let values: Vec<f64> = prob.free.iter().zip(&best_y).map(|(f, &v)| f.value(v)).collect();
    let best = obj.evaluate(&values)?;
    let all = obj.all();
    let band = (0..n)
        .map(|i| {
            all.iter()
                .filter(|e| (prob.score(e) - score) / unit <= band_threshold)
                .map(|e| e.mean[i])
                .fold((best.mean[i], best.mean[i]), |(lo, hi), m| (lo.min(m), hi.max(m)))
        })
        .collect();
    let noise_ratio =
        prob.data.points.iter().zip(&best.se).map(|(q, se)| se / q.sigma.unwrap_or(unit.sqrt())).fold(0.0, f64::max);
    let chi2 = score / unit;
    let p_value = (has_sigma && dof > 0).then(|| 1.0 - ChiSquared::new(dof as f64).expect("dof > 0").cdf(chi2));
    Ok(FitResult {
        best_y,
        best,
        score,
        sigma_estimate: (!has_sigma).then(|| unit.sqrt()),
        chi2,
        dof,
        p_value,
        threshold,
        band_threshold,
        intervals,
        band,
        noise_ratio,
        evaluations: obj.evaluations(),
        search_evaluations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::data::DataSet;
    use crate::fit::free::FreeParam;
    use crate::fit::model::{Problem, Simulator};
    use crate::scene::Scene;

    /// A deterministic misfit of `kappa` alone: with three data points of friction 0 and
    /// sigma 1, and the simulated friction `sqrt(chi2(kappa) / 3)` at each, the fit's
    /// `chi2` is `chi2(kappa)` exactly.
    struct Misfit(fn(f64) -> f64);

    impl Simulator for Misfit {
        fn friction_per_junction(&self, scenes: &[Scene]) -> Result<Vec<f64>, String> {
            Ok(scenes.iter().map(|s| ((self.0)(s.junctions.kappa) / 3.0).sqrt()).collect())
        }
    }

    /// A broad basin around the start (`kappa = 1.2`, `chi2 = 10`) and a deeper, narrow one
    /// at the lower bound (`chi2` about 2.8 at `kappa = 1`) that the first search does not
    /// reach but the low side's profile steps into.
    fn two_basins(kappa: f64) -> f64 {
        let y = kappa - 1.0;
        10.0 + 96.0 * (y - 0.2) * (y - 0.2) - 11.0 * (-(y / 0.04).powi(2)).exp()
    }

    fn fit_of(misfit: fn(f64) -> f64) -> (FitResult, f64) {
        let base = crate::test_scenes::fig1_with(&["junctions.kappa=1.2"]);
        let data = DataSet::parse("plate.v,friction,sigma\n0.5,0,1\n1,0,1\n2,0,1\n", "d.csv", &base, 1.0).unwrap();
        let free = vec![FreeParam { field: "junctions.kappa".into(), low: 1.0, high: 2.0, log: false, start: 1.2 }];
        let problem = Problem::new(base, data, free, 1).unwrap();
        let sim = Misfit(misfit);
        let obj = Objective::new(&problem, &sim, Vec::new(), None, None, 10_000);
        let r = fit(&obj).unwrap();
        let lowest = obj.all().iter().map(|e| problem.score(e)).fold(f64::INFINITY, f64::min);
        (r, lowest)
    }

    /// The optimum is the lowest misfit the fit evaluated, to within the restart's level:
    /// the first search stops in the broad basin, the low side's profile finds the deeper
    /// one, and the search restarts there. (Without the restart the reported optimum is
    /// the broad basin's `chi2` near 10, more than 7 above points the profile evaluated.)
    #[test]
    fn the_optimum_is_the_lowest_misfit_found() {
        let (r, lowest) = fit_of(two_basins);
        assert!(r.score <= lowest + RESTART_RISE, "optimum {} while the fit evaluated {lowest}", r.score);
        let kappa = 1.0 + r.best_y[0];
        assert!((kappa - 1.0).abs() < 0.01 && r.chi2 < 3.0, "kappa {kappa}, chi2 {}", r.chi2);
        // The interval is the deeper basin's (to its bound), not the broad one's.
        let i = &r.intervals[0];
        assert!(i.low.at_bound && i.high.y < 0.05, "{i:?}");
        // The restart is counted as the search's, after the first profiles.
        assert!(r.search_evaluations < r.evaluations, "{} of {}", r.search_evaluations, r.evaluations);
    }

    /// A single basin: no restart, the optimum at its bottom, the interval where the
    /// parabola crosses the threshold (`96 d^2 = 3.84`, `d = 0.2`).
    #[test]
    fn one_basin_gives_its_bottom_and_its_parabola_interval() {
        let (r, lowest) = fit_of(|kappa| 10.0 + 96.0 * (kappa - 1.4) * (kappa - 1.4));
        assert!(r.score <= lowest + 1e-6, "{} vs {lowest}", r.score);
        assert!((1.0 + r.best_y[0] - 1.4).abs() < 0.01 && (r.chi2 - 10.0).abs() < 0.01, "{r:?}");
        let i = &r.intervals[0];
        assert!((i.low.y - 0.2).abs() < 0.01 && (i.high.y - 0.6).abs() < 0.01, "{i:?}");
    }
}
