//! A scene's force law and bond kind, built: [`with_force_law`] (the law table is in
//! `physics::force`, beside the laws: adding a law is one file there and one line of that
//! table, docs/engines.md, "Adding a force law") and [`with_bond`] (the table of bond kinds
//! is in `physics::bond`). The fixed engine, the exact engine, validation and the stability analysis
//! all go through them. Also the one place where physics values are built from a scene.

use super::params::{JunctionParams, Scene};
use crate::physics::{
    Bond, BondParams, ExactMethod, ForceLaw, Formation, LawParams, Linear, ParamError, Plate, Strong, Tilted, Weak,
    exact_method,
};
pub use crate::physics::{BondKind, BondVisitor, ForceLawKind, LawVisitor};

/// Builds the scene's bond kind and hands it to `visitor` (`physics::bond::with_bond_kind`).
pub fn with_bond<V: BondVisitor>(j: &JunctionParams, visitor: V) -> Result<V::Output, ParamError> {
    crate::physics::bond::with_bond_kind(j.bond, &bond_params(j), visitor)
}

/// Builds the scene's force law and hands it to `visitor` (`physics::force::with_law`).
pub fn with_force_law<V: LawVisitor>(j: &JunctionParams, visitor: V) -> Result<V::Output, ParamError> {
    crate::physics::force::with_law(j.force_law, &law_params(j), visitor)
}

/// The numbers a force law is built from.
pub fn law_params(j: &JunctionParams) -> LawParams {
    LawParams { kappa: j.kappa, l0: j.l0 }
}

/// The numbers a bond kind is built from.
pub fn bond_params(j: &JunctionParams) -> BondParams {
    BondParams { k0: j.k0, dx: j.dx, temperature: j.temperature }
}

/// What validation and the stability analysis need to know about the scene's force law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LawInfo {
    pub name: &'static str,
    pub exact: ExactMethod,
    /// `c` with `f(x) <= c |x|`.
    pub thinning_slope: f64,
    /// `[lo, hi]` containing every junction stiffness `d f^x/dx`.
    pub stiffness: (f64, f64),
    /// Why `hi` bounds the stiffness, in words.
    pub stiffness_note: &'static str,
}

struct Info;

impl LawVisitor for Info {
    type Output = LawInfo;
    fn visit<L: ForceLaw>(self, law: L) -> LawInfo {
        LawInfo {
            name: L::NAME,
            exact: exact_method::<L>(),
            thinning_slope: law.thinning_slope(),
            stiffness: law.stiffness_range(),
            stiffness_note: L::STIFFNESS_NOTE,
        }
    }
}

/// The scene's force law, described.
pub fn law_info(j: &JunctionParams) -> Result<LawInfo, ParamError> {
    with_force_law(j, Info)
}

struct Check;

impl BondVisitor for Check {
    type Output = ();
    fn visit<B: Bond>(self, _bond: B) {}
}

/// Builds the scene's force law and bond kind once, so that their own checks run at
/// validation; the error names the scene's field (`junctions.<field>`).
pub fn check(j: &JunctionParams) -> Result<LawInfo, (&'static str, ParamError)> {
    let field = |e: ParamError| (scene_field(e.field), e);
    with_bond(j, Check).map_err(field)?;
    law_info(j).map_err(field)
}

/// The scene's key of a law's or bond's parameter.
fn scene_field(field: &str) -> &'static str {
    match field {
        "kappa" => "junctions.kappa",
        "l0" => "junctions.l0",
        "k0" => "junctions.k0",
        "dx" => "junctions.dx",
        "temperature" => "junctions.temperature",
        _ => "junctions.force_law",
    }
}

// Physics values of a validated scene (the same numbers the dispatch builds from).

impl Plate {
    pub fn from_scene(s: &Scene) -> Plate {
        Plate { mass: s.plate.mass, eta: s.plate.eta, k: s.plate.k, v: s.plate.v }
    }
}

impl Formation {
    pub fn from_scene(s: &Scene) -> Formation {
        Formation { kon0: s.junctions.kon0, v0: s.junctions.v0() }
    }
}

impl Linear {
    pub fn from_scene(s: &Scene) -> Linear {
        Linear { kappa: s.junctions.kappa }
    }
}

impl Tilted {
    pub fn from_scene(s: &Scene) -> Tilted {
        Tilted { kappa: s.junctions.kappa, l0: s.junctions.l0 }
    }
}

impl Strong {
    pub fn from_scene(s: &Scene) -> Strong {
        Strong { k0: s.junctions.k0 }
    }
}

impl Weak {
    pub fn from_scene(s: &Scene) -> Weak {
        Weak { k0: s.junctions.k0, beta_dx: s.junctions.beta_dx() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The serde name of every table entry is its type's `NAME`.
    #[test]
    fn serde_names_are_the_types_names() {
        for k in ForceLawKind::ALL {
            assert_eq!(serde_json::to_value(k).unwrap(), serde_json::Value::from(k.name()));
        }
        for k in BondKind::ALL {
            assert_eq!(serde_json::to_value(k).unwrap(), serde_json::Value::from(k.name()));
        }
    }

    /// The two laws' descriptions: both bounded by `kappa`, the methods of docs/engines.md.
    #[test]
    fn law_info_of_the_bundled_laws() {
        let mut j = crate::test_scenes::fig1().junctions;
        j.kappa = 0.3;
        let tilted = law_info(&j).unwrap();
        assert_eq!(
            (tilted.name, tilted.exact, tilted.thinning_slope, tilted.stiffness),
            ("tilted", ExactMethod::Series, 0.3, (0.0, 0.3))
        );
        j.force_law = ForceLawKind::Linear;
        let linear = law_info(&j).unwrap();
        assert_eq!(
            (linear.name, linear.exact, linear.thinning_slope, linear.stiffness),
            ("linear", ExactMethod::ClosedForm, 0.3, (0.3, 0.3))
        );
        j.kappa = f64::NAN;
        assert_eq!(check(&j).unwrap_err().0, "junctions.kappa");
        j.kappa = 0.3;
        j.bond = BondKind::Weak;
        j.temperature = 0.0;
        assert_eq!(check(&j).unwrap_err().0, "junctions.temperature");
    }
}
