//! How the plate of the exact linear engine moves between events, chosen once per run as a
//! type parameter of [`super::ExactLinear`].
//!
//! - [`Dynamic`]: the plate equation `M y'' + eta y' + (K + kappa N_att) y = a + b s`, in
//!   closed form ([`Trajectory`]).
//! - [`Kinematic`] (`plate.kinematic = true`): the plate follows its drive, `y = V tau` in
//!   local coordinates; no plate equation, no propagator, no integrals of it.
//!
//! Why a type parameter and not a kinematic branch inside [`Trajectory`]: the dynamic path is
//! the hot one (every event evaluates the trajectory, its integrals and, for weak bonds, its
//! bounds). A new `Trajectory` branch would add an arm to each of those matches; a type
//! parameter compiles the dynamic engine exactly as before (`M::KINEMATIC` is a constant, its
//! `if` vanishes) and the kinematic engine without any of the propagator's work. The rupture
//! models see the plate through its position and its bounds over a horizon, which both a
//! [`Trajectory`] and a [`Drive`] give.
//!
//! [`Trajectory`]: crate::engine::exact::stepper::linear::propagator::Trajectory

use serde::{Deserialize, Serialize, de::DeserializeOwned};

/// A plate at constant speed: `y(s) = y0 + v s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drive {
    pub y0: f64,
    pub v: f64,
}

impl Drive {
    /// `y(s)`, `s >= 0` measured from the start of the piece.
    #[inline(always)]
    pub fn position(&self, s: f64) -> f64 {
        self.y0 + self.v * s
    }
    /// Proven bounds `(y_lo, y_hi)` of `y` over `[0, h]`: `y` is monotone in `s` (so is its
    /// floating-point evaluation), the end points bound it.
    #[inline(always)]
    pub fn bounds(&self, h: f64) -> (f64, f64) {
        let (a, b) = (self.position(0.0), self.position(h));
        (a.min(b), a.max(b))
    }
}

/// The plate motion of an exact linear engine.
pub trait PlateMotion:
    Clone + Copy + std::fmt::Debug + Default + Serialize + DeserializeOwned + Send + 'static
{
    /// `true`: `X = V t`, no plate equation, friction reported as `F_b`.
    const KINEMATIC: bool;
}

/// The plate obeys its equation of motion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Dynamic;
impl PlateMotion for Dynamic {
    const KINEMATIC: bool = false;
}

/// The plate follows its drive exactly (`plate.kinematic = true`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Kinematic;
impl PlateMotion for Kinematic {
    const KINEMATIC: bool = true;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drive_bounds_contain_every_position() {
        for v in [0.5, -0.25, 0.0] {
            let d = Drive { y0: 3.0, v };
            let (lo, hi) = d.bounds(2.0);
            for i in 0..=100 {
                let y = d.position(0.02 * i as f64);
                assert!(lo <= y && y <= hi, "v = {v}: {y} not in [{lo}, {hi}]");
            }
            assert_eq!((lo.min(hi), hi), (lo, 3.0f64.max(3.0 + 2.0 * v)));
        }
    }
}
