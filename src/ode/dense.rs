//! Dense output (continuous extension of order 7) over the last accepted step: Hairer's
//! `CONTD8`, and event location on it.
//!
//! After an accepted step from `(t_old, y_old)` of size `h`, eight coefficient vectors
//! `cont[0..8]` are stored (see `Dop853::commit_dense` in the stepper) and, with
//! `s = (t - t_old) / h`, `s1 = 1 - s`,
//! ```text
//! conpar = cont4 + s (cont5 + s1 (cont6 + s cont7))
//! y(t)   = cont0 + s (cont1 + s1 (cont2 + s (cont3 + s1 conpar)))
//! ```
//! `cont0..cont3` are the cubic Hermite interpolant of `y_old, y_new, f_old, f_new`;
//! `cont4..cont7` the 7th-order correction from the twelve stages, the FSAL stage and the three
//! extra stages. The ends are returned exactly: `t_old` gives `y_old` and `t_new` gives the
//! accepted `y_new` (not `cont0 + cont1`, which may differ in the last bit), so that a level
//! reached exactly at a step end is seen as reached.

use super::root::first_crossing;
use super::stepper::Dop853;
use super::system::OdeError;

/// Where a time falls in the last step.
#[derive(Clone, Copy, Debug)]
pub(super) enum DensePoint {
    Start,
    End,
    Inside(f64),
}

/// Evaluates component `i` of the continuous extension at `s` in (0, 1).
#[inline]
pub(super) fn contd8(cont: &[f64], n: usize, i: usize, s: f64) -> f64 {
    let s1 = 1.0 - s;
    let c = |r: usize| cont[r * n + i];
    let conpar = c(4) + s * (c(5) + s1 * (c(6) + s * c(7)));
    c(0) + s * (c(1) + s1 * (c(2) + s * (c(3) + s1 * conpar)))
}

impl Dop853 {
    /// Maps `t` to a point of the last accepted step. Times within `4 eps max(|t_old|,
    /// |t_new|)` outside the step are taken as its ends.
    pub(super) fn dense_point(&self, t: f64) -> Result<DensePoint, OdeError> {
        let (t_old, t_new, h) = self.dense_interval().ok_or(OdeError::NoDenseOutput)?;
        let slack = 4.0 * f64::EPSILON * t_old.abs().max(t_new.abs());
        if !(t >= t_old - slack && t <= t_new + slack) {
            return Err(OdeError::OutsideDenseInterval { t, t_old, t_new });
        }
        Ok(if t <= t_old {
            DensePoint::Start
        } else if t >= t_new {
            DensePoint::End
        } else {
            DensePoint::Inside(((t - t_old) / h).clamp(0.0, 1.0))
        })
    }

    #[inline]
    pub(super) fn dense_component_at(&self, i: usize, p: DensePoint) -> f64 {
        let n = self.dim();
        match p {
            DensePoint::Start => self.cont[i],
            DensePoint::End => self.y_end[i],
            DensePoint::Inside(s) => contd8(&self.cont, n, i, s),
        }
    }

    /// The whole state at `t` in the last accepted step `[t_old, t_new]` (7th-order dense
    /// output; exact `y_old`, `y_new` at the ends).
    pub fn dense(&self, t: f64, out: &mut [f64]) -> Result<(), OdeError> {
        self.check_len(out.len())?;
        let p = self.dense_point(t)?;
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.dense_component_at(i, p);
        }
        Ok(())
    }

    /// Component `i` of the state at `t` in the last accepted step.
    pub fn dense_component(&self, i: usize, t: f64) -> Result<f64, OdeError> {
        if i >= self.dim() {
            return Err(OdeError::DimensionMismatch { expected: self.dim(), got: i });
        }
        let p = self.dense_point(t)?;
        Ok(self.dense_component_at(i, p))
    }

    /// First time in the last accepted step where `f(t, y(t))` crosses from `< 0` to `>= 0`,
    /// `y(t)` being the dense output.
    ///
    /// Detection: `f` is evaluated at both step ends and at `event_samples - 1` equally spaced
    /// interior points (no monotonicity assumed); the first sub-interval with a sign change
    /// from `< 0` to `>= 0` is refined with Brent's method to a bracket of ~`1e-15` relative
    /// in `t`, and the upper end of that bracket (where `f >= 0`) is returned. A value
    /// `>= 0` already at `t_old` is not a crossing: check the state before stepping. Two
    /// crossings within one sampling sub-interval may be missed (see `docs/ode.md`).
    ///
    /// Errors: no step yet; `f` returned a non-finite value.
    pub fn locate<F: FnMut(f64, &[f64]) -> f64>(&mut self, mut f: F) -> Result<Option<f64>, OdeError> {
        let (t_old, t_new, _) = self.dense_interval().ok_or(OdeError::NoDenseOutput)?;
        self.ensure_work();
        let mut buf = std::mem::take(&mut self.work.y_dense);
        let n_sub = self.config().event_samples;
        let res = first_crossing(t_old, t_new, n_sub, |t| {
            // `t` is always inside the step here, so `dense_point` cannot fail.
            match self.dense_point(t) {
                Ok(p) => {
                    for (i, o) in buf.iter_mut().enumerate() {
                        *o = self.dense_component_at(i, p);
                    }
                    f(t, &buf)
                }
                Err(_) => f64::NAN,
            }
        });
        self.work.y_dense = buf;
        res
    }

    /// First time in the last accepted step where component `i` reaches `level` from below:
    /// `y_i(t) - level` crosses from `< 0` to `>= 0`. Same detection as [`Dop853::locate`],
    /// but cheaper (one component of the dense output per evaluation) and `&self`.
    pub fn locate_component(&self, i: usize, level: f64) -> Result<Option<f64>, OdeError> {
        if i >= self.dim() {
            return Err(OdeError::DimensionMismatch { expected: self.dim(), got: i });
        }
        let (t_old, t_new, _) = self.dense_interval().ok_or(OdeError::NoDenseOutput)?;
        first_crossing(t_old, t_new, self.config().event_samples, |t| match self.dense_point(t) {
            Ok(p) => self.dense_component_at(i, p) - level,
            Err(_) => f64::NAN,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `y_old + (y_new - y_old)` is not `y_new` when `y_new` is below the last bit of
    /// `y_old`; the dense output must still return `y_new` at `t_new`, so that a level equal
    /// to the accepted state is reached at the step end.
    #[test]
    fn step_end_returns_the_accepted_state_exactly() {
        let mut ode = Dop853::new(1, 1e-10, 1e-12).unwrap();
        let (y_old, y_new) = ([0.3], [1e-20]);
        assert_ne!(y_old[0] + (y_new[0] - y_old[0]), y_new[0]);
        ode.set_last_step_for_test(1.0, &y_old, 1.5, &y_new);
        assert_eq!(ode.dense_component(0, 1.5).unwrap(), 1e-20);
        assert_eq!(ode.dense_component(0, 1.0).unwrap(), 0.3);
        // Falling to exactly 1e-20 at the end: the downward crossing of level 1e-20 is t_new.
        assert_eq!(ode.locate(|_, y| 1e-20 - y[0]).unwrap(), Some(1.5));
        assert!((ode.dense_component(0, 1.25).unwrap() - 0.15).abs() < 1e-15);
    }
}
