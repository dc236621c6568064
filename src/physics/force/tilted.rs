//! The letter's eq. 3: a spring of rest length `l0` across a gap `l0`, tilted by `x`.

use serde::{Deserialize, Serialize};

use super::hypot;
use super::law::{ForceLaw, LawParams, ParamError, Series, SeriesLaw, check_kappa};

/// The letter's eq. 3: a spring of rest length `l0` across a gap `l0`, tilted by `x`:
/// `l = sqrt(x^2 + l0^2)`, `f = kappa (l - l0)`, `f^x = f x / l`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tilted {
    pub kappa: f64,
    pub l0: f64,
}

impl Tilted {
    /// `l - l0 = x^2 / (l + l0)`, free of cancellation for small `x`.
    #[inline]
    fn stretch(&self, x: f64) -> (f64, f64) {
        let l = x.hypot(self.l0);
        (x * x / (l + self.l0), l)
    }
}

impl Tilted {
    /// `one` of every element of `xs`, in place, four at a time: `l` from
    /// [`hypot::common4`] (the C library's bits, vectorised) and then `with_l(x, l)`, the
    /// same operations as `one`. A group of four with an argument outside `hypot`'s common
    /// range, the remainder, and every element under a C library whose `hypot` differs
    /// ([`hypot::matches_library`]) are done one at a time.
    #[inline(always)]
    fn four_at_a_time(&self, xs: &mut [f64], one: impl Fn(f64) -> f64, with_l: impl Fn(f64, f64) -> f64) {
        if !hypot::matches_library() {
            for x in xs {
                *x = one(*x);
            }
            return;
        }
        let mut groups = xs.chunks_exact_mut(4);
        for group in &mut groups {
            let group: &mut [f64; 4] = group.try_into().unwrap();
            let x = *group;
            let (l, in_range) = hypot::common4(x, self.l0);
            for i in 0..4 {
                group[i] = with_l(x[i], l[i]);
            }
            if !in_range {
                for i in 0..4 {
                    group[i] = one(x[i]);
                }
            }
        }
        for x in groups.into_remainder() {
            *x = one(*x);
        }
    }
}

impl ForceLaw for Tilted {
    const NAME: &'static str = "tilted";
    const STIFFNESS_NOTE: &'static str = "the tilted law's junction stiffness never exceeds kappa";
    type Exact = Series;

    fn new(p: &LawParams) -> Result<Tilted, ParamError> {
        let kappa = check_kappa(p)?;
        if !(p.l0.is_finite() && p.l0 > 0.0) {
            return Err(ParamError { field: "l0", value: p.l0, allowed: "must be a finite number > 0".into() });
        }
        Ok(Tilted { kappa, l0: p.l0 })
    }
    #[inline]
    fn tension(&self, x: f64) -> f64 {
        self.kappa * self.stretch(x).0
    }
    #[inline]
    fn force_x(&self, x: f64) -> f64 {
        self.tension_and_force_x(x).1
    }
    #[inline]
    fn tension_and_force_x(&self, x: f64) -> (f64, f64) {
        let (s, l) = self.stretch(x);
        let f = self.kappa * s;
        (f, f * (x / l))
    }
    /// [`ForceLaw::force_x`] four at a time (`l` from the vectorised `hypot::common4`, the same bits).
    #[inline]
    fn force_x_many(&self, xs: &mut [f64]) {
        self.four_at_a_time(xs, |x| self.force_x(x), |x, l| self.kappa * (x * x / (l + self.l0)) * (x / l));
    }
    /// [`ForceLaw::tension`] four at a time (`l` from the vectorised `hypot::common4`, the same bits).
    #[inline]
    fn tension_many(&self, xs: &mut [f64]) {
        self.four_at_a_time(xs, |x| self.tension(x), |x, l| self.kappa * (x * x / (l + self.l0)));
    }
    /// `d/dx [kappa x (1 - l0/l)] = kappa (1 - l0^3 / l^3)`.
    #[inline]
    fn stiffness_x(&self, x: f64) -> f64 {
        let l = x.hypot(self.l0);
        let r = self.l0 / l;
        self.kappa * (1.0 - r * r * r)
    }
    /// `f = kappa (l - l0) <= kappa |x|` since `l <= |x| + l0`.
    fn thinning_slope(&self) -> f64 {
        self.kappa
    }
    /// `kappa (1 - (l0/l)^3)` lies in `[0, kappa)`.
    fn stiffness_range(&self) -> (f64, f64) {
        (0.0, self.kappa)
    }
}

impl SeriesLaw for Tilted {
    #[inline]
    fn tilted_form(&self) -> LawParams {
        LawParams { kappa: self.kappa, l0: self.l0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::force::law::check_law;

    #[test]
    fn tilted_law_matches_geometry() {
        let law = Tilted { kappa: 0.1, l0: 1.0 };
        for &x in &[-3.0, -0.5, 0.0, 1e-9, 0.7, 40.0] {
            let l = (x * x + 1.0f64).sqrt();
            let f = 0.1 * (l - 1.0);
            assert!((law.tension(x) - f).abs() <= 1e-15 * (1.0 + f.abs()), "x = {x}");
            assert!((law.force_x(x) - f * x / l).abs() <= 1e-15 * (1.0 + f.abs()));
            let h = 1e-6;
            let numeric = (law.force_x(x + h) - law.force_x(x - h)) / (2.0 * h);
            assert!((law.stiffness_x(x) - numeric).abs() < 1e-8, "x = {x}");
        }
        // Small extensions: f = kappa x^2 / (2 l0) to leading order, with no cancellation.
        assert!((law.tension(1e-9) / (0.1 * 1e-18 / 2.0) - 1.0).abs() < 1e-12);
        check_law(&law, &[-3.0, -0.5, 0.0, 1e-9, 0.7, 40.0, 1e6]).unwrap();
        assert_eq!(Tilted::new(&LawParams { kappa: 0.1, l0: 0.0 }).unwrap_err().field, "l0");
    }
}
