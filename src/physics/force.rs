//! Junction force laws (docs/model.md, "Equations", item 3). Pure functions of the extension `x`.

use serde::{Deserialize, Serialize};

/// A junction force law, chosen once per run so that engines are specialised to it.
pub trait ForceLaw: Copy + Send + Sync + std::fmt::Debug + 'static {
    /// `true` for the Hookean law, whose bond force is linear in the plate position.
    const IS_LINEAR: bool;
    /// Spring tension `f(x) >= 0`.
    fn tension(&self, x: f64) -> f64;
    /// Horizontal force component `f^x(x)`.
    fn force_x(&self, x: f64) -> f64;
    /// `(f(x), f^x(x))` at once.
    #[inline]
    fn tension_and_force_x(&self, x: f64) -> (f64, f64) {
        (self.tension(x), self.force_x(x))
    }
    /// `d f^x / dx`, the junction's horizontal stiffness.
    fn stiffness_x(&self, x: f64) -> f64;
}

/// Hookean shear spring: `f^x = kappa x`, `f = kappa |x|`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Linear {
    pub kappa: f64,
}

impl ForceLaw for Linear {
    const IS_LINEAR: bool = true;
    #[inline]
    fn tension(&self, x: f64) -> f64 {
        self.kappa * x.abs()
    }
    #[inline]
    fn force_x(&self, x: f64) -> f64 {
        self.kappa * x
    }
    #[inline]
    fn stiffness_x(&self, _x: f64) -> f64 {
        self.kappa
    }
}

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

impl ForceLaw for Tilted {
    const IS_LINEAR: bool = false;
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
    /// `d/dx [kappa x (1 - l0/l)] = kappa (1 - l0^3 / l^3)`.
    #[inline]
    fn stiffness_x(&self, x: f64) -> f64 {
        let l = x.hypot(self.l0);
        let r = self.l0 / l;
        self.kappa * (1.0 - r * r * r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_law() {
        let law = Linear { kappa: 0.5 };
        assert_eq!(law.force_x(-2.0), -1.0);
        assert_eq!(law.tension(-2.0), 1.0);
    }

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
    }
}
