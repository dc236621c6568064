//! The force-law contract: [`ForceLaw`], the numbers a law is built from ([`LawParams`]),
//! why it refuses them ([`ParamError`]), the checks every law passes ([`check_law`]), and
//! how the exact engine moves the plate under a law, chosen by the law's type.
//!
//! A law names its method in [`ForceLaw::Exact`]: [`Direct`], [`ClosedForm`]
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

use serde::Serialize;
use serde::de::DeserializeOwned;

/// Something to do with a force law once its type is known.
pub trait LawVisitor {
    type Output;
    fn visit<L: ForceLaw>(self, law: L) -> Self::Output;
}

/// The scene's junction numbers a law is built from: plain numbers, so physics never reads
/// a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LawParams {
    /// Junction spring constant `kappa` (>= 0).
    pub kappa: f64,
    /// Gap and rest length `l0` (> 0).
    pub l0: f64,
}

/// Why a law refuses its parameters: the field (relative to `junctions.`), its value and
/// what is allowed. Validation turns it into the scene's one-line error.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("junctions.{field} = {value}: {allowed}")]
pub struct ParamError {
    pub field: &'static str,
    pub value: f64,
    pub allowed: String,
}

/// A junction force law, chosen once per run so that engines are specialised to it.
///
/// Besides the force itself a law states the two bounds the rest of the crate relies on:
/// its **thinning slope** `c` with `f(x) <= c |x|` (the weak-bond rupture envelope
/// `k0 exp(beta dx c |x|)`) and its **stiffness range** `[lo, hi]` containing every
/// `d f^x/dx` (the plate's stiffest configuration, `K + hi N`, for the stability analysis
/// and the exact engine's step cap).
pub trait ForceLaw: Copy + Send + Sync + std::fmt::Debug + Serialize + DeserializeOwned + 'static {
    /// The scene's name of the law (`junctions.force_law`).
    const NAME: &'static str;
    /// `true` when `f^x(x) = kappa x` exactly, so `sum_i f^x(x_i) = f^x(sum_i x_i)`: the fixed
    /// engine then sums extensions instead of forces.
    const IS_LINEAR: bool = false;
    /// How the exact engine moves the plate under this law: [`Direct`] (any law),
    /// [`ClosedForm`] (only a [`LinearLaw`]) or [`Series`] (only a [`SeriesLaw`]).
    type Exact: ExactMethodOf<Self>;
    /// Why `hi` of [`ForceLaw::stiffness_range`] bounds a junction's stiffness, in words
    /// (`stickslip stability` prints it).
    const STIFFNESS_NOTE: &'static str;

    /// Builds the law from the scene's junction numbers, or says which one it refuses.
    fn new(p: &LawParams) -> Result<Self, ParamError>;
    /// Spring tension `f(x) >= 0`.
    fn tension(&self, x: f64) -> f64;
    /// Horizontal force component `f^x(x)`.
    fn force_x(&self, x: f64) -> f64;
    /// `(f(x), f^x(x))` at once.
    #[inline]
    fn tension_and_force_x(&self, x: f64) -> (f64, f64) {
        (self.tension(x), self.force_x(x))
    }
    /// Replaces every `x` of `xs` by `f^x(x)`: bit for bit [`ForceLaw::force_x`] one by one
    /// (a law may evaluate several at once).
    #[inline]
    fn force_x_many(&self, xs: &mut [f64]) {
        for x in xs {
            *x = self.force_x(*x);
        }
    }
    /// [`ForceLaw::tension`] of every element of `xs`, in place, with the bits of one at a
    /// time (a law may compute several at once, as [`ForceLaw::force_x_many`]).
    #[inline]
    fn tension_many(&self, xs: &mut [f64]) {
        for x in xs {
            *x = self.tension(*x);
        }
    }
    /// `d f^x / dx`, the junction's horizontal stiffness.
    fn stiffness_x(&self, x: f64) -> f64;
    /// `c >= 0` with `f(x) <= c |x|` for every `x`.
    fn thinning_slope(&self) -> f64;
    /// `[lo, hi]` with `lo <= d f^x/dx (x) <= hi` for every `x`.
    fn stiffness_range(&self) -> (f64, f64);
}

/// Numerical checks every law must pass: `stiffness_x` is the derivative of `force_x`,
/// `f <= c |x|`, the stiffness stays in its range, `(f, f^x)` agree with the separate calls.
/// Used by each law's unit test and by tests/suite/law_extension.rs.
pub fn check_law<L: ForceLaw>(law: &L, xs: &[f64]) -> Result<(), String> {
    let c = law.thinning_slope();
    let (lo, hi) = law.stiffness_range();
    for &x in xs {
        let (f, fx) = law.tension_and_force_x(x);
        if f != law.tension(x) || fx != law.force_x(x) {
            return Err(format!("{}: tension_and_force_x({x}) disagrees with tension/force_x", L::NAME));
        }
        if !(f >= 0.0 && f <= c * x.abs() * (1.0 + 1e-15)) {
            return Err(format!("{}: f({x}) = {f} is not in [0, c |x|] with c = {c}", L::NAME));
        }
        let (mut many_f, mut many_fx) = ([x; 5], [x; 5]);
        law.tension_many(&mut many_f);
        law.force_x_many(&mut many_fx);
        if many_f.iter().any(|v| v.to_bits() != f.to_bits()) || many_fx.iter().any(|v| v.to_bits() != fx.to_bits()) {
            return Err(format!("{}: tension_many or force_x_many at {x} disagrees with tension/force_x", L::NAME));
        }
        let k = law.stiffness_x(x);
        if !(k >= lo - 1e-15 * lo.abs() && k <= hi + 1e-15 * hi.abs()) {
            return Err(format!("{}: stiffness_x({x}) = {k} outside [{lo}, {hi}]", L::NAME));
        }
        // Central difference: error O(h^2 f''') + O(eps |f^x| / h).
        let h = 1e-5 * (1.0 + x.abs());
        let numeric = (law.force_x(x + h) - law.force_x(x - h)) / (2.0 * h);
        let tol = 1e-6 * (hi.abs() + lo.abs() + 1.0);
        if (k - numeric).abs() > tol {
            return Err(format!("{}: stiffness_x({x}) = {k}, numerical derivative {numeric}", L::NAME));
        }
    }
    Ok(())
}

/// `kappa >= 0` and finite: the check both current laws make (validation has already made
/// it for scenes; a law built by hand goes through it too).
pub fn check_kappa(p: &LawParams) -> Result<f64, ParamError> {
    if p.kappa.is_finite() && p.kappa >= 0.0 {
        Ok(p.kappa)
    } else {
        Err(ParamError { field: "kappa", value: p.kappa, allowed: "must be a finite number >= 0".into() })
    }
}

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
    /// The law's `kappa` and `l0` in the tilted form (the numbers of a `Tilted` law).
    fn tilted_form(&self) -> LawParams;
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

/// The exact engine's method for law `L` ([`ForceLaw::Exact`]), as a value.
pub fn exact_method<L: ForceLaw>() -> ExactMethod {
    <L::Exact as ExactMethodOf<L>>::METHOD
}
