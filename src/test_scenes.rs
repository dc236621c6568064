//! The letter's Fig. 1 for the unit tests in `src/`, read from the bundled
//! `scenarios/fig1.toml` (the scene the test kit, `testkit/`, gives the other tests; the kit
//! itself cannot be used here: it depends on this crate).

use crate::scene::Scene;

/// Fig. 1 with `overrides` (`section.key=value`) applied.
pub(crate) fn fig1_with(overrides: &[&str]) -> Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(include_str!("../scenarios/fig1.toml"), "testkit", "fig1", &o)
        .unwrap_or_else(|e| panic!("fig1 scene: {e}"))
}

/// The letter's Fig. 1 scene.
pub(crate) fn fig1() -> Scene {
    fig1_with(&[])
}
