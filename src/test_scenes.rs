//! The letter's Fig. 1 for the unit tests in `src/`, read from the bundled
//! `scenarios/fig1.toml` (the scene the test kit, `testkit/`, gives the other tests; the kit
//! itself cannot be used here: it depends on this crate).

use crate::output::Summary;
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

/// A summary as JSON without its wall time, the one field two runs of a scene differ in.
pub(crate) fn summary_without_wall_time(s: &Summary) -> serde_json::Value {
    let mut v = serde_json::to_value(s).unwrap();
    assert!(v.as_object_mut().unwrap().remove("wall_seconds").is_some());
    v
}
