//! Validated, typed scene parameters: the *problem* every engine solves.
//!
//! A [`Scene`] can only be obtained through validation (`Scene::from_file`,
//! `Scene::from_toml_str`, or `SceneFile::validate`), so every value in it has been
//! checked against the ranges documented in `docs/scenes.md`. Units are the letter's:
//! length `l0`, time `M/eta`, velocity `l0 eta/M`, force `kB T/l0`.

use serde::{Deserialize, Serialize};

pub use crate::physics::{BondKind, ForceLawKind};

/// What a junction's extension is when it re-forms (docs/model.md, "Equations", item 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Reattach {
    /// Keeps the (relaxed) extension it had when it formed.
    Residual,
    /// Starts at `x = 0`.
    Unstretched,
}

/// Initial junction states (the plate always starts at rest at `X = 0`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Initial {
    /// All detached, `x_i = 0`.
    Detached,
    /// All attached, `x_i = 0`.
    Attached,
    /// Each attached with probability `kon0 / (kon0 + k0)`, `x_i = 0`.
    Stationary,
}

/// Which engine advances the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EngineKind {
    /// Event-driven kinetic Monte Carlo, no time step.
    Exact,
    /// The letter's fixed-step scheme (eq. 5).
    Fixed,
}

/// Random-number generator of the fixed-step engine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RngKind {
    /// Park–Miller "minimal standard" `s <- 16807 s mod (2^31 - 1)`.
    ParkMiller,
    /// PCG (`rand_pcg::Pcg64`, seeded with `seed_from_u64`).
    Pcg,
}

/// Flip rule of the fixed-step engine (docs/engines.md, "The fixed-step engine", step 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FlipRule {
    /// Flip when `xi < min(1, k dt)`.
    Linear,
    /// Flip when `xi < 1 - exp(-k dt)`.
    Exponential,
    /// Flip when `xi > k dt`, exactly as the letter typesets `theta(xi - dt k)`.
    AsPrinted,
}

/// Plate integrator of the fixed-step engine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum IntegratorKind {
    /// `Xd += dt a(X, Xd); X += dt Xd`.
    SemiImplicitEuler,
    /// `X += dt Xd; Xd += dt a(X_old, Xd_old)`.
    ExplicitEuler,
    /// Velocity Verlet with the velocity-dependent damping treated explicitly.
    VelocityVerlet,
}

/// Junction population and its kinetics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JunctionParams {
    /// Number of junctions `N` (>= 1).
    pub n: usize,
    pub bond: BondKind,
    pub force_law: ForceLawKind,
    /// Junction spring constant `kappa` (>= 0).
    pub kappa: f64,
    /// Gap and rest length `l0` (> 0).
    pub l0: f64,
    /// Relaxation rate `lambda` of detached junctions (>= 0).
    pub lambda: f64,
    pub reattach: Reattach,
    /// Spontaneous rupture rate `k0` (>= 0).
    pub k0: f64,
    /// Formation rate of a stationary contact `kon0` (>= 0).
    pub kon0: f64,
    /// Critical contact age `tau0` (> 0).
    pub tau0: f64,
    /// Contact length scale `alpha` (> 0); `V0 = alpha / tau0`.
    pub alpha: f64,
    /// Barrier distance `dx` (>= 0) of the weak-bond rate.
    pub dx: f64,
    /// Temperature in units of the reference `kB T` (> 0); `beta = 1/temperature`, and
    /// `k0`, `kon0` and `kappa` above are the values in force at it (`scene::thermal`).
    pub temperature: f64,
    pub initial: Initial,
    /// Activation energy of rupture (units of `kB T_ref`, >= 0): `k0(T) = k0 exp(-e_off (1/T - 1))`.
    #[serde(default)]
    pub e_off: f64,
    /// Activation energy of formation (units of `kB T_ref`, >= 0): `kon0(T) = kon0 exp(-e_on (1/T - 1))`.
    #[serde(default)]
    pub e_on: f64,
    /// Relative slope of `kappa` per unit of `T`: `kappa(T) = kappa (1 + kappa_slope (T - 1))`.
    #[serde(default)]
    pub kappa_slope: f64,
}

impl JunctionParams {
    /// Critical velocity `V0 = alpha / tau0` above which formation fades.
    pub fn v0(&self) -> f64 {
        self.alpha / self.tau0
    }
    /// `beta dx = dx / temperature`, the force sensitivity of the weak-bond rate.
    pub fn beta_dx(&self) -> f64 {
        self.dx / self.temperature
    }
}

/// The driven top plate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlateParams {
    /// Plate mass `M` (>= 0; 0 is the overdamped limit).
    pub mass: f64,
    /// Viscous damping `eta` (>= 0; > 0 when `mass = 0`).
    pub eta: f64,
    /// Driving spring constant `K` (>= 0).
    pub k: f64,
    /// Driving velocity `V` (>= 0).
    pub v: f64,
    /// Kinematic drive: the plate follows `X = V t` exactly (no plate equation; `mass`, `eta`
    /// and `k` are not used) and the friction is the junctions' force `F_b`.
    #[serde(default)]
    pub kinematic: bool,
    /// Relative slope of `K` per unit of `T`: `K(T) = K (1 + k_slope (T - 1))`.
    #[serde(default)]
    pub k_slope: f64,
    /// Relative slope of `eta` per unit of `T`: `eta(T) = eta (1 + eta_slope (T - 1))`.
    #[serde(default)]
    pub eta_slope: f64,
}

/// Run control.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunParams {
    pub engine: EngineKind,
    /// End of the simulated interval (> 0).
    pub t_end: f64,
    /// Start of the averaging window (>= 0, < t_end).
    pub t_warmup: f64,
    /// Seed of the engine's random generator.
    pub seed: u64,
}

/// Options of the fixed-step engine.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FixedParams {
    /// Time step (> 0).
    pub dt: f64,
    pub rng: RngKind,
    pub flip: FlipRule,
    pub integrator: IntegratorKind,
}

impl FixedParams {
    /// The fixed engine's slack, in steps: it steps while `n dt < t_stop - STEP_SLACK dt`, so
    /// that `t_end = 150, dt = 1` is 150 steps, not 151.
    pub const STEP_SLACK: f64 = 1e-9;

    /// Number of steps the fixed engine takes to cover `[0, t_end]`: `ceil(t_end/dt)`,
    /// with a relative slack of [`Self::STEP_SLACK`].
    pub fn steps_for(&self, t_end: f64) -> u64 {
        let ratio = t_end / self.dt;
        let r = ratio.round();
        if (ratio - r).abs() <= Self::STEP_SLACK * r.max(1.0) { r as u64 } else { ratio.ceil() as u64 }
    }

    /// The time up to which the engine, advancing to `t_stop` in steps of `dt`, takes its
    /// steps: it stops at the first `n dt` at or past it.
    pub fn step_limit(dt: f64, t_stop: f64) -> f64 {
        t_stop - Self::STEP_SLACK * dt
    }
}

/// Options of the exact engine.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExactParams {
    /// Relative tolerance of the adaptive plate integrator (tilted law only).
    pub rtol: f64,
    /// Absolute tolerance of the adaptive plate integrator (tilted law only).
    pub atol: f64,
    /// How the exact engine evaluates the tilted law's bond force.
    #[serde(default)]
    pub tilted: TiltedMethod,
}

/// How the exact engine evaluates the tilted law's bond force `F_b(X) = sum_i f^x(X - c_i)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TiltedMethod {
    /// A truncated Taylor series about a base point, updated in O(1) per event, with a
    /// rigorous remainder bound (docs/engines.md); the default.
    #[default]
    Series,
    /// Direct summation over the attached junctions, O(N) per evaluation (the reference).
    Direct,
}

/// What a run writes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutputParams {
    /// Interval of the output grid (> 0); the fixed engine rounds it to whole steps.
    pub sample_dt: f64,
    /// Write `trace.csv`.
    pub trace: bool,
    /// Write `events.csv`.
    pub events: bool,
    /// Write `trace.svg`.
    pub plot: bool,
}

/// A validated scene: one simulation, fully specified.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// Name of the scene (the file stem), reported in `summary.json`.
    pub name: String,
    pub junctions: JunctionParams,
    pub plate: PlateParams,
    pub run: RunParams,
    pub fixed: FixedParams,
    pub exact: ExactParams,
    pub output: OutputParams,
    /// The reference values (at `T = 1`, as the scene file gives them) of the
    /// temperature-dependent parameters, when the scene has a temperature dependence (any of
    /// `e_off`, `e_on`, `kappa_slope`, `k_slope`, `eta_slope` not 0); `None` otherwise, and
    /// then the values in force are the reference ones ([`Scene::reference_values`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<super::thermal::Reference>,
}

impl Scene {
    /// The temperature-dependent parameters at `T = 1`, as the scene file gives them.
    pub fn reference_values(&self) -> super::thermal::Reference {
        self.reference.unwrap_or_else(|| self.in_force())
    }

    /// The temperature-dependent parameters in force at `junctions.temperature` (the values
    /// the engines read from `junctions` and `plate`).
    pub fn in_force(&self) -> super::thermal::Reference {
        let (j, p) = (&self.junctions, &self.plate);
        super::thermal::Reference { k0: j.k0, kon0: j.kon0, kappa: j.kappa, k: p.k, eta: p.eta }
    }
}
