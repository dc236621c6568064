//! Minimising the misfit over a box: argmin's Nelder–Mead simplex in unit coordinates
//! (each free parameter's `[0, 1]`, [`super::free`]), deterministic given the objective.
//!
//! The simplex may step outside the box; there the misfit is taken at the nearest point of
//! the box (`clamp(y)`) plus `PENALTY * |y - clamp(y)|^2` times the misfit's unit, which
//! pushes it back without evaluating the model outside the fields' bounds.

use argmin::core::{CostFunction, Error, Executor, State};
use argmin::solver::neldermead::NelderMead;

/// Weight of the squared distance outside the box, in units of the misfit's scale.
const PENALTY: f64 = 1e4;

/// A function of the unit coordinates to minimise: `None` stops the search (an error or a
/// stop, kept by the caller).
pub type Score<'a> = dyn Fn(&[f64]) -> Option<f64> + Sync + 'a;

/// How a search is run.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Size of the initial simplex along each coordinate (unit coordinates).
    pub step: f64,
    /// Stop when the standard deviation of the simplex's misfits is below this.
    pub tolerance: f64,
    /// Most simplex iterations.
    pub max_iters: u64,
    /// The misfit's unit (1 for chi2, sigma^2 for a sum of squares), for the penalty.
    pub unit: f64,
}

struct Boxed<'a, 'b> {
    score: &'b Score<'a>,
    unit: f64,
    /// An evaluation stopped the search: every cost from then on is infinite (argmin's
    /// Nelder–Mead does not take an error from its first simplex), without evaluating.
    stopped: std::sync::atomic::AtomicBool,
}

impl CostFunction for Boxed<'_, '_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, y: &Vec<f64>) -> Result<f64, Error> {
        let clamped: Vec<f64> = y.iter().map(|v| v.clamp(0.0, 1.0)).collect();
        let outside: f64 = y.iter().zip(&clamped).map(|(a, b)| (a - b) * (a - b)).sum();
        use std::sync::atomic::Ordering::Relaxed;
        if self.stopped.load(Relaxed) {
            return Ok(f64::INFINITY);
        }
        match (self.score)(&clamped) {
            Some(s) => Ok(s + PENALTY * self.unit * outside),
            None => {
                self.stopped.store(true, Relaxed);
                Ok(f64::INFINITY)
            }
        }
    }
}

/// Minimises `score` from `start` (unit coordinates); returns the best point (in the box)
/// and its misfit, or `None` if an evaluation stopped the search.
pub fn minimise(score: &Score<'_>, start: &[f64], s: Settings) -> Option<(Vec<f64>, f64)> {
    if start.is_empty() {
        return score(start).map(|v| (Vec::new(), v));
    }
    let mut simplex = vec![start.to_vec()];
    for k in 0..start.len() {
        let mut v = start.to_vec();
        // Step inwards when a step outwards would leave the box.
        v[k] = if v[k] + s.step <= 1.0 { v[k] + s.step } else { v[k] - s.step };
        simplex.push(v);
    }
    let solver = NelderMead::new(simplex).with_sd_tolerance(s.tolerance).ok()?;
    let problem = Boxed { score, unit: s.unit, stopped: false.into() };
    let result = Executor::new(problem, solver).configure(|st| st.max_iters(s.max_iters)).timer(false).run().ok()?;
    if result.problem.problem.as_ref().is_none_or(|p| p.stopped.load(std::sync::atomic::Ordering::Relaxed)) {
        return None;
    }
    let state = result.state();
    let best: Vec<f64> = state.get_best_param()?.iter().map(|v| v.clamp(0.0, 1.0)).collect();
    let value = score(&best)?;
    Some((best, value))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_minimum_of_a_quadratic_and_stays_in_the_box() {
        let f = |y: &[f64]| Some((y[0] - 0.3).powi(2) + 4.0 * (y[1] - 0.6).powi(2));
        let s = Settings { step: 0.1, tolerance: 1e-12, max_iters: 500, unit: 1.0 };
        let (y, v) = minimise(&f, &[0.5, 0.5], s).unwrap();
        assert!((y[0] - 0.3).abs() < 1e-4 && (y[1] - 0.6).abs() < 1e-4 && v < 1e-8, "{y:?}");
        // A minimum outside the box: found on its edge.
        let g = |y: &[f64]| Some((y[0] - 1.5).powi(2));
        let (y, _) = minimise(&g, &[0.5], s).unwrap();
        assert!((y[0] - 1.0).abs() < 1e-6, "{y:?}");
        // An evaluation that stops the search.
        let h = |_: &[f64]| None;
        assert!(minimise(&h, &[0.5], s).is_none());
    }
}
