//! Scenes shared by tests and benches, so both exercise the same models.

use crate::scene::Scene;

/// The letter's Fig. 1 parameters (strong bonds, tilted law), as scene-file text.
pub const FIG1: &str = r#"
[junctions]
n = 300
bond = "strong"
force_law = "tilted"
kappa = 0.1
l0 = 1.0
lambda = 0.1
k0 = 0.1
kon0 = 0.1
tau0 = 2.0
alpha = 1.0
dx = 1.0
[plate]
mass = 75.0
eta = 75.0
k = 150.0
v = 0.5
[run]
engine = "fixed"
t_end = 150.0
seed = 1
[fixed]
dt = 1.0
rng = "park-miller"
[output]
sample_dt = 1.0
"#;

/// Fig. 1 with `overrides` (`section.key=value`) applied.
pub fn fig1_with(overrides: &[&str]) -> Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(FIG1, "testkit", "fig1", &o).unwrap_or_else(|e| panic!("testkit scene: {e}"))
}

/// The letter's Fig. 1 scene.
pub fn fig1() -> Scene {
    fig1_with(&[])
}

/// Fig. 1 physics at `n` junctions with the `linear` law and the exact engine: extensive
/// plate parameters scale with `n` (`K = n/2`, `M = eta = n/4`) so that per-junction forces,
/// rates and the time unit `M/eta` are the letter's at every size. Used by benches and tests.
pub fn scaled_linear(n: usize, bond: &str) -> Scene {
    scaled(n, bond, "linear")
}

/// The twin of [`scaled_linear`] with the letter's `tilted` law (and the exact engine's
/// default `exact.tilted`): Fig. 1 at `n` junctions, `K = n/2`, `M = eta = n/4`.
pub fn scaled_tilted(n: usize, bond: &str) -> Scene {
    scaled(n, bond, "tilted")
}

/// Fig. 1 at `n` junctions with force law `law`, exact engine, stationary start, no trace.
fn scaled(n: usize, bond: &str, law: &str) -> Scene {
    let n_s = n.to_string();
    let k = (0.5 * n as f64).to_string();
    let m = (0.25 * n as f64).to_string();
    fig1_with(&[
        "run.engine=exact",
        &format!("junctions.force_law={law}"),
        &format!("junctions.bond={bond}"),
        &format!("junctions.n={n_s}"),
        &format!("plate.k={k}"),
        &format!("plate.mass={m}"),
        &format!("plate.eta={m}"),
        "junctions.initial=stationary",
        "output.trace=false",
    ])
}
