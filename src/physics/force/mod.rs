//! Junction force laws (docs/model.md, "Equations", item 3): one file per law, each a type
//! implementing [`ForceLaw`], and the one table of laws below (`force_laws!`): adding a law
//! is its file plus its line in the table (docs/engines.md, "Adding a force law").
//!
//! A law states how the exact engine moves the plate under it ([`ForceLaw::Exact`]): the
//! direct method works for every law; the closed form and the series only for a law that
//! implements what they need ([`LinearLaw`], [`SeriesLaw`]), so a law can never be run with
//! another law's physics. [`MethodVisitor`] hands the law to the engine's code for its method
//! with that capability in its type (physics names the methods; the engines implement them).

pub mod hypot;
mod method;

pub use method::{
    ClosedForm, Direct, ExactMethod, ExactMethodOf, LinearLaw, MethodVisitor, Series, SeriesLaw, exact_method,
};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// Something to do with a force law once its type is known.
pub trait LawVisitor {
    type Output;
    fn visit<L: ForceLaw>(self, law: L) -> Self::Output;
}

/// The table of force laws: for each, `Variant => file::Type` (the variant, in kebab case, is
/// the scene's name `junctions.force_law`; a unit test checks it is the type's `NAME`).
/// Generates the law modules and their re-exports, the scene's name enum [`ForceLawKind`]
/// (`ALL`, `name()`) and [`with_law`], which builds the type a name stands for and hands it
/// to a visitor.
macro_rules! force_laws {
    ($( $(#[$vmeta:meta])* $Variant:ident => $file:ident::$Type:ident, )+) => {
        $( mod $file; pub use $file::$Type; )+

        /// Junction force law, as a scene names it (docs/model.md, "Equations", item 3).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
        #[serde(rename_all = "kebab-case")]
        pub enum ForceLawKind {
            $( $(#[$vmeta])* $Variant, )+
        }

        impl ForceLawKind {
            /// Every law, in the table's order.
            pub const ALL: [ForceLawKind; [$(stringify!($Variant)),+].len()] = [$(ForceLawKind::$Variant),+];
            /// The scene's name of this law.
            pub fn name(self) -> &'static str {
                match self {
                    $(ForceLawKind::$Variant => <$Type as ForceLaw>::NAME,)+
                }
            }
        }

        /// Builds the law `kind` names from `p` and hands it to `visitor`; the type is fixed
        /// from here on, so everything the visitor runs is specialised to it.
        pub fn with_law<V: LawVisitor>(kind: ForceLawKind, p: &LawParams, visitor: V) -> Result<V::Output, ParamError> {
            match kind {
                $(ForceLawKind::$Variant => Ok(visitor.visit(<$Type as ForceLaw>::new(p)?)),)+
            }
        }
    };
}

force_laws! {
    /// The letter's eq. 3: a spring of rest length `l0` spanning the gap `l0`.
    Tilted => tilted::Tilted,
    /// Hookean shear spring `f^x = kappa x`.
    Linear => linear::Linear,
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
