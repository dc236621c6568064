//! Scenes shared by tests, benches and examples, so that all exercise the same models.

use stickslip::Scene;
use stickslip::scene::{BondKind, ForceLawKind};

/// The letter's Fig. 1 (strong bonds, tilted law, fixed-step engine), as scene-file text:
/// `scenarios/fig1.toml` itself, so the kit and the bundled scenario are one source.
pub const FIG1: &str = include_str!("../../scenarios/fig1.toml");

/// A scene named `test` from TOML `text` with `overrides` (`section.key=value`) applied;
/// panics with the validation error (a test's scene is valid by construction).
pub fn scene(text: &str, overrides: &[&str]) -> Scene {
    parse(text, "test", "test", overrides)
}

/// Fig. 1 (named `fig1`) with `overrides` (`section.key=value`) applied.
pub fn fig1_with(overrides: &[&str]) -> Scene {
    parse(FIG1, "testkit", "fig1", overrides)
}

fn parse(text: &str, source: &str, name: &str, overrides: &[&str]) -> Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(text, source, name, &o).unwrap_or_else(|e| panic!("testkit scene: {e}"))
}

/// The letter's Fig. 1 scene.
pub fn fig1() -> Scene {
    fig1_with(&[])
}

/// Fig. 1 on the fixed engine (`run.engine=fixed`, whatever else `overrides` set first).
pub fn fixed_fig1(overrides: &[&str]) -> Scene {
    let mut o = vec!["run.engine=fixed"];
    o.extend_from_slice(overrides);
    fig1_with(&o)
}

/// Fig. 1 physics at `n` junctions with the `linear` law and the exact engine: extensive
/// plate parameters scale with `n` (`K = n/2`, `M = eta = n/4`) so that per-junction forces,
/// rates and the time unit `M/eta` are the letter's at every size. Used by benches and tests.
pub fn scaled_linear(n: usize, bond: &str) -> Scene {
    scaled(n, ForceLawKind::Linear, bond_kind(bond))
}

/// The twin of [`scaled_linear`] with the letter's `tilted` law (and the exact engine's
/// default `exact.tilted`): Fig. 1 at `n` junctions, `K = n/2`, `M = eta = n/4`.
pub fn scaled_tilted(n: usize, bond: &str) -> Scene {
    scaled(n, ForceLawKind::Tilted, bond_kind(bond))
}

/// Fig. 1 at `n` junctions with force law `law` and bond kind `bond`, exact engine,
/// `K = n/2`, `M = eta = n/4`, stationary start, no trace.
pub fn scaled(n: usize, law: ForceLawKind, bond: BondKind) -> Scene {
    scaled_with(n, law, bond, &[])
}

/// [`scaled`] with `overrides` applied after its own.
pub fn scaled_with(n: usize, law: ForceLawKind, bond: BondKind, overrides: &[&str]) -> Scene {
    let k = (0.5 * n as f64).to_string();
    let m = (0.25 * n as f64).to_string();
    let (law, bond) = (format!("junctions.force_law={}", law.name()), format!("junctions.bond={}", bond.name()));
    let (n, k, m) = (format!("junctions.n={n}"), format!("plate.k={k}"), format!("plate.mass={m}"));
    let eta = m.replace("mass", "eta");
    let mut o =
        vec!["run.engine=exact", &law, &bond, &n, &k, &m, &eta, "junctions.initial=stationary", "output.trace=false"];
    o.extend_from_slice(overrides);
    fig1_with(&o)
}

/// The bond kind whose scene-file name is `name`, if any.
pub fn bond_named(name: &str) -> Option<BondKind> {
    BondKind::ALL.into_iter().find(|b| b.name() == name)
}

/// The force law whose scene-file name is `name`, if any.
pub fn law_named(name: &str) -> Option<ForceLawKind> {
    ForceLawKind::ALL.into_iter().find(|l| l.name() == name)
}

/// The bond kind named `name` (its scene-file name); panics on an unknown name.
fn bond_kind(name: &str) -> BondKind {
    bond_named(name).unwrap_or_else(|| panic!("testkit: no bond kind {name:?}"))
}
