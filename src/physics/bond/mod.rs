//! Bond kinds (docs/model.md, "Equations", item 6): one file per kind, each a type
//! implementing [`Bond`], and the table of kinds below ([`BondKind`], the scene's
//! `junctions.bond`, and [`with_bond_kind`], which builds the type it names).

pub mod contract;
mod strong;
mod weak;

pub use contract::{Bond, BondParams};
pub use strong::Strong;
pub use weak::Weak;

use serde::{Deserialize, Serialize};

use super::force::ParamError;

/// Something to do with a bond kind once its type is known.
pub trait BondVisitor {
    type Output;
    fn visit<B: Bond>(self, bond: B) -> Self::Output;
}

/// Generates the name enum of bond kinds (`junctions.bond`; serde names: the variant in kebab case,
/// which a test checks against the type's `NAME`), its `ALL` list and `name()`, and the
/// dispatch function that builds the type named by the scene and hands it to a visitor.
macro_rules! table {
    (
        $(#[$meta:meta])*
        enum $Kind:ident, $Trait:ident::new(&$Params:ident), fn $with:ident<$Visitor:ident>;
        $( $(#[$vmeta:meta])* $Variant:ident => $Type:ty, )+
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
        #[serde(rename_all = "kebab-case")]
        pub enum $Kind {
            $( $(#[$vmeta])* $Variant, )+
        }

        impl $Kind {
            /// Every choice, in the table's order.
            pub const ALL: [$Kind; [$(stringify!($Variant)),+].len()] = [$($Kind::$Variant),+];
            /// The scene's name of this choice.
            pub fn name(self) -> &'static str {
                match self {
                    $($Kind::$Variant => <$Type as $Trait>::NAME,)+
                }
            }
        }

        /// Builds the type the scene names and hands it to `visitor`; the type is fixed from
        /// here on, so everything the visitor runs is specialised to it.
        pub fn $with<V: $Visitor>(kind: $Kind, p: &$Params, visitor: V) -> Result<V::Output, ParamError> {
            match kind {
                $($Kind::$Variant => Ok(visitor.visit(<$Type as $Trait>::new(p)?)),)+
            }
        }
    };
}

table! {
    /// Bond kind (docs/model.md, "Equations", item 6).
    enum BondKind, Bond::new(&BondParams), fn with_bond_kind<BondVisitor>;
    /// `k_off = k0`, independent of force.
    Strong => Strong,
    /// `k_off = k0 exp(beta f dx)`.
    Weak => Weak,
}
