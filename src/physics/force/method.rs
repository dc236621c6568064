//! How the exact engine moves the plate under a law, chosen by the law's type.
//!
//! A law names its method in [`ForceLaw::Exact`](super::ForceLaw::Exact): [`Direct`], [`ClosedForm`]
//! or [`Series`]. Each method is an [`ExactMethodOf<L>`] only for the laws that have what it
//! needs, so the wrong pairing does not compile:
//!
//! ```compile_fail,E0277
//! use serde::{Deserialize, Serialize};
//! use stickslip::physics::{ClosedForm, ForceLaw, LawParams, ParamError};
//!
//! /// A cubic spring: its bond force is not linear in the plate position.
//! #[derive(Clone, Copy, Debug, Serialize, Deserialize)]
//! struct Cubic {
//!     k: f64,
//! }
//!
//! impl ForceLaw for Cubic {
//!     const NAME: &'static str = "cubic";
//!     const STIFFNESS_NOTE: &'static str = "";
//!     type Exact = ClosedForm; // refused: `Cubic` is not a `LinearLaw`
//!     fn new(p: &LawParams) -> Result<Self, ParamError> {
//!         Ok(Cubic { k: p.kappa })
//!     }
//!     fn tension(&self, x: f64) -> f64 {
//!         (self.k * x * x * x).abs()
//!     }
//!     fn force_x(&self, x: f64) -> f64 {
//!         self.k * x * x * x
//!     }
//!     fn stiffness_x(&self, x: f64) -> f64 {
//!         3.0 * self.k * x * x
//!     }
//!     fn thinning_slope(&self) -> f64 {
//!         f64::INFINITY
//!     }
//!     fn stiffness_range(&self) -> (f64, f64) {
//!         (0.0, f64::INFINITY)
//!     }
//! }
//! ```
//!
//! The same law with `type Exact = Direct;` compiles (and runs on the direct engine), as
//! does `ClosedForm` for a law that implements [`LinearLaw`]:
//!
//! ```
//! use serde::{Deserialize, Serialize};
//! use stickslip::physics::{ClosedForm, ExactMethod, ForceLaw, LawParams, LinearLaw, ParamError};
//!
//! #[derive(Clone, Copy, Debug, Serialize, Deserialize)]
//! struct Hooke {
//!     k: f64,
//! }
//!
//! impl ForceLaw for Hooke {
//!     const NAME: &'static str = "hooke";
//!     const IS_LINEAR: bool = true;
//!     const STIFFNESS_NOTE: &'static str = "each junction adds k";
//!     type Exact = ClosedForm;
//!     fn new(p: &LawParams) -> Result<Self, ParamError> {
//!         Ok(Hooke { k: p.kappa })
//!     }
//!     fn tension(&self, x: f64) -> f64 {
//!         self.k * x.abs()
//!     }
//!     fn force_x(&self, x: f64) -> f64 {
//!         self.k * x
//!     }
//!     fn stiffness_x(&self, _x: f64) -> f64 {
//!         self.k
//!     }
//!     fn thinning_slope(&self) -> f64 {
//!         self.k
//!     }
//!     fn stiffness_range(&self) -> (f64, f64) {
//!         (self.k, self.k)
//!     }
//! }
//!
//! impl LinearLaw for Hooke {
//!     fn slope(&self) -> f64 {
//!         self.k
//!     }
//! }
//!
//! assert_eq!(stickslip::physics::exact_method::<Hooke>(), ExactMethod::ClosedForm);
//! ```

use super::{ForceLaw, Tilted};

/// The exact engine's method for a law, as a value (validation, messages).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExactMethod {
    /// `F_b` linear in the plate position: closed-form plate motion (`ExactLinear`).
    ClosedForm,
    /// A truncated Taylor series of `F_b` updated in O(1) per event (`ExactSeries`), unless
    /// the scene asks for `exact.tilted = "direct"`.
    Series,
    /// Direct summation of `F_b` over the attached junctions, O(N) per evaluation, under
    /// the adaptive DOP853 integrator (`ExactDirect<L, B>`): works for every law.
    Direct,
}

/// The direct method: any law.
#[derive(Clone, Copy, Debug)]
pub struct Direct;
/// The closed form: a [`LinearLaw`] only.
#[derive(Clone, Copy, Debug)]
pub struct ClosedForm;
/// The bond-force series: a [`SeriesLaw`] only.
#[derive(Clone, Copy, Debug)]
pub struct Series;

/// A law whose horizontal force is `f^x(x) = slope x` exactly, with `f = slope |x|`: the bond
/// force is linear in the plate position, so the plate moves in closed form between events.
/// The closed-form engine is built from [`LinearLaw::slope`], never from a scene's numbers.
pub trait LinearLaw: ForceLaw {
    /// `kappa` of `f^x = kappa x`.
    fn slope(&self) -> f64;
}

/// A law of the tilted form `f^x = kappa (x - l0 x / sqrt(x^2 + l0^2))`, the form the series
/// engine's bond-force series (`engine::exact::stepper::series::SeriesSum`: its Taylor coefficients and
/// its proven remainder bound) is written for. The series engine is built from
/// [`SeriesLaw::tilted_form`], never from a scene's numbers.
pub trait SeriesLaw: ForceLaw {
    /// The law's `kappa` and `l0` in the tilted form.
    fn tilted_form(&self) -> Tilted;
}

/// Code for each method of the exact engine, handed a law together with what its method
/// needs (the engine implements it; [`ExactMethodOf::visit`] calls the law's method).
pub trait MethodVisitor<L> {
    type Output;
    fn closed_form(self, law: L) -> Self::Output
    where
        L: LinearLaw;
    fn series(self, law: L) -> Self::Output
    where
        L: SeriesLaw;
    fn direct(self, law: L) -> Self::Output
    where
        L: ForceLaw;
}

/// A method of the exact engine that can run law `L`: implemented for [`Direct`] and every
/// law, for [`ClosedForm`] and every [`LinearLaw`], for [`Series`] and every [`SeriesLaw`].
pub trait ExactMethodOf<L> {
    /// The method as a value.
    const METHOD: ExactMethod;
    /// Calls `visitor`'s code for this method.
    fn visit<V: MethodVisitor<L>>(law: L, visitor: V) -> V::Output;
}

impl<L: ForceLaw> ExactMethodOf<L> for Direct {
    const METHOD: ExactMethod = ExactMethod::Direct;
    #[inline]
    fn visit<V: MethodVisitor<L>>(law: L, visitor: V) -> V::Output {
        visitor.direct(law)
    }
}

impl<L: LinearLaw> ExactMethodOf<L> for ClosedForm {
    const METHOD: ExactMethod = ExactMethod::ClosedForm;
    #[inline]
    fn visit<V: MethodVisitor<L>>(law: L, visitor: V) -> V::Output {
        visitor.closed_form(law)
    }
}

impl<L: SeriesLaw> ExactMethodOf<L> for Series {
    const METHOD: ExactMethod = ExactMethod::Series;
    #[inline]
    fn visit<V: MethodVisitor<L>>(law: L, visitor: V) -> V::Output {
        visitor.series(law)
    }
}

/// The exact engine's method for law `L` ([`ForceLaw::Exact`](super::ForceLaw::Exact)), as a value.
pub fn exact_method<L: ForceLaw>() -> ExactMethod {
    <L::Exact as ExactMethodOf<L>>::METHOD
}
