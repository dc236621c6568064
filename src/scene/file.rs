//! The scene file as written by a user: TOML sections whose fields are all optional.
//!
//! Missing fields take the defaults documented in `docs/scenes.md`; unknown fields are
//! refused. Nothing here is checked beyond its type: [`super::validate`] turns a
//! [`SceneFile`] into a [`super::Scene`].

use serde::{Deserialize, Serialize};

use super::params::{
    BondKind, EngineKind, FlipRule, ForceLawKind, Initial, IntegratorKind, Reattach, RngKind, TiltedMethod,
};

/// `[junctions]`.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct JunctionsSection {
    pub n: Option<usize>,
    pub bond: Option<BondKind>,
    pub force_law: Option<ForceLawKind>,
    pub kappa: Option<f64>,
    pub l0: Option<f64>,
    pub lambda: Option<f64>,
    pub reattach: Option<Reattach>,
    pub k0: Option<f64>,
    pub kon0: Option<f64>,
    pub tau0: Option<f64>,
    pub alpha: Option<f64>,
    pub dx: Option<f64>,
    pub temperature: Option<f64>,
    pub initial: Option<Initial>,
    pub e_off: Option<f64>,
    pub e_on: Option<f64>,
    pub kappa_slope: Option<f64>,
}

/// `[plate]`.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PlateSection {
    pub mass: Option<f64>,
    pub eta: Option<f64>,
    pub k: Option<f64>,
    pub v: Option<f64>,
    pub kinematic: Option<bool>,
    pub k_slope: Option<f64>,
    pub eta_slope: Option<f64>,
}

/// `[run]`.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RunSection {
    pub engine: Option<EngineKind>,
    pub t_end: Option<f64>,
    pub t_warmup: Option<f64>,
    pub seed: Option<u64>,
}

/// `[fixed]`.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FixedSection {
    pub dt: Option<f64>,
    pub rng: Option<RngKind>,
    pub flip: Option<FlipRule>,
    pub integrator: Option<IntegratorKind>,
}

/// `[exact]`.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ExactSection {
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
    pub tilted: Option<TiltedMethod>,
}

/// `[output]`.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    pub sample_dt: Option<f64>,
    pub trace: Option<bool>,
    pub events: Option<bool>,
    pub plot: Option<bool>,
}

/// A whole scene file. Every section may be omitted.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    #[serde(default)]
    pub junctions: JunctionsSection,
    #[serde(default)]
    pub plate: PlateSection,
    #[serde(default)]
    pub run: RunSection,
    #[serde(default)]
    pub fixed: FixedSection,
    #[serde(default)]
    pub exact: ExactSection,
    #[serde(default)]
    pub output: OutputSection,
}
