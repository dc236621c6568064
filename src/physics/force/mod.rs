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
pub mod law;

pub use law::{
    ClosedForm, Direct, ExactMethod, ExactMethodOf, ForceLaw, LawParams, LawVisitor, LinearLaw, MethodVisitor,
    ParamError, Series, SeriesLaw, check_kappa, check_law, exact_method,
};

use serde::{Deserialize, Serialize};

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
