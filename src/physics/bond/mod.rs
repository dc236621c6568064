//! Bond kinds (docs/model.md, "Equations", item 6): one file per kind, each a type
//! implementing [`Bond`], and the table of kinds below ([`BondKind`], the scene's
//! `junctions.bond`, and [`with_bond_kind`], which builds the type it names).

mod strong;
mod weak;

pub use strong::Strong;
pub use weak::Weak;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::force::ParamError;

/// The scene's numbers a bond kind is built from (plain numbers: physics never reads a scene).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BondParams {
    /// Spontaneous rupture rate `k0` (>= 0).
    pub k0: f64,
    /// Barrier distance `dx` (>= 0) of the weak-bond rate.
    pub dx: f64,
    /// Temperature in units of the reference `kB T` (> 0); `beta = 1/temperature`.
    pub temperature: f64,
}

/// A bond kind, chosen once per run: strong-bond scenes run no weak-bond code.
pub trait Bond: Copy + Send + Sync + std::fmt::Debug + Serialize + DeserializeOwned + 'static {
    /// The scene's name of the bond kind (`junctions.bond`).
    const NAME: &'static str;
    /// `true` when the rupture rate depends on the tension.
    const IS_WEAK: bool;
    /// Builds the bond kind from the scene's numbers, or says which one it refuses.
    fn new(p: &BondParams) -> Result<Self, ParamError>;
    /// Rupture rate `k_off(f)` at tension `f >= 0`. May be `+inf`, never NaN.
    fn k_off(&self, tension: f64) -> f64;
    /// `k0 = k_off(0)`, the rate of an unstretched bond.
    fn k0(&self) -> f64;
    /// `s >= 0` with `k_off(f) = k0 exp(s f)` (0 for a force-independent rate). With a law's
    /// thinning slope `c` (`f <= c |x|`), `k0 exp(s c |x|)` bounds a junction's rupture rate:
    /// the exact engine's weak-bond envelope.
    fn force_sensitivity(&self) -> f64;
}

/// `k0 >= 0` and finite.
pub(crate) fn check_k0(p: &BondParams) -> Result<f64, ParamError> {
    if p.k0.is_finite() && p.k0 >= 0.0 {
        Ok(p.k0)
    } else {
        Err(ParamError { field: "k0", value: p.k0, allowed: "must be a finite number >= 0".into() })
    }
}

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
