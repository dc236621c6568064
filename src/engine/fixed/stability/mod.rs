//! Stability of the fixed-step scheme (docs/stability.md): pure functions of a scene's
//! parameters, no engine is run.
//!
//! **Plate.** Linearised about any trajectory, the plate of the fixed-step scheme is the
//! damped oscillator `M Xdd + eta Xd + k X = 0` with `k = K + sum_att d f^x/dx`. The junction
//! stiffness lies in the law's `ForceLaw::stiffness_range` `[lo, hi]`: `kappa` (linear law) or
//! `kappa (1 - (l0/l)^3) in [0, kappa)` (tilted law), so `k` lies in `[K, K + kappa N]`: `K` with no junction attached, `K + kappa N` with all of
//! them attached (the stiffest case). One step of an integrator maps `(X, Xd)` linearly,
//! `(X, Xd)_{n+1} = A (X, Xd)_n`; the step is stable when the spectral radius `rho(A) <= 1`
//! (an eigenvalue 1 only for the neutral translation of a plate with `k = 0`). With
//! `c = eta/M`, `w^2 = k/M`, `h = dt` (derivation in docs/stability.md):
//!
//! | integrator | `trace A` | `det A` | largest stable `dt` |
//! | --- | --- | --- | --- |
//! | semi-implicit Euler | `2 - hc - h^2 w^2` | `1 - hc` | `4M / (eta + sqrt(eta^2 + 4kM))` |
//! | explicit Euler | `2 - hc` | `1 - hc + h^2 w^2` | `eta/k` if `eta^2 <= 4kM`, else `4M / (eta + sqrt(eta^2 - 4kM))` |
//! | velocity Verlet (implicit damping) | `2 (1 - h^2 w^2/2) / (1 + hc/2)` | `(1 - hc/2) / (1 + hc/2)` | `2 sqrt(M/k)` |
//! | overdamped Euler (`M = 0`) | `1 - h k/eta` (one eigenvalue) | `0` | `2 eta / k` |
//!
//! **Junctions.** A detached junction relaxes as `x *= 1 - lambda dt`: stable iff
//! `lambda dt <= 2` (bounded; `< 2` decaying), monotone iff `lambda dt <= 1`. A flip with
//! rate `k` has probability `min(1, k dt)` under the linear rule: `k dt > 1` saturates it.
//!
//! Layout: [`oscillator`] (one step as a matrix, its spectral radius, the limits), this
//! module (a scene's analysis: every integrator's limits over the attached counts, the
//! relaxation step, the flip probabilities). The report's text is the command line's
//! (`cli::stability`).

pub mod oscillator;

use crate::engine::fixed::Integrator;
use crate::physics::ExactMethod;
use crate::scene::laws::{self, LawInfo};
use crate::scene::{BondKind, FlipRule, ForceLawKind, JunctionParams, Scene};

pub use oscillator::{
    Matrix, Oscillator, amplification, dt_limit, dt_limit_numeric, is_stable, radius, spectral_radius,
};

/// Relative slack within which a `dt` counts as *at* a limit rather than beyond it.
pub const AT_LIMIT: f64 = 1e-9;

/// Where a scene's `dt` stands against one integrator's limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Below the limit for every attached count: every oscillation decays (or, undamped,
    /// keeps its amplitude as the exact solution does).
    Stable,
    /// Stable for some attached counts, unstable for others.
    Conditional,
    /// At the limit of the most favourable attached count (an eigenvalue of modulus 1: an
    /// oscillation that never decays) and beyond it for the others.
    AtLimit,
    /// Beyond the limit for every attached count: oscillations grow until the run fails.
    Unstable,
}

impl Verdict {
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Stable => "stable",
            Verdict::Conditional => "conditional",
            Verdict::AtLimit => "at the limit",
            Verdict::Unstable => "unstable",
        }
    }
}

/// One integrator's limits at a scene's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlateLimit {
    pub integrator: Integrator,
    /// Stable for every attached count below this `dt`: the minimum of [`dt_limit`] over
    /// `k in [K, K + kappa N]` (for every integrator here, at an end of the range).
    pub dt_stable: f64,
    /// Unstable for every attached count above this `dt`: the maximum of [`dt_limit`] over
    /// the range (explicit Euler: possibly inside it, at critical damping `k = eta^2/(4M)`).
    pub dt_unstable: f64,
    /// `dt_limit` with no junction attached (`k = K`) and with all attached (`K + kappa N`).
    pub dt_none: f64,
    pub dt_all: f64,
    /// `rho(A)` at the scene's `dt` with `k = K` and with `k = K + kappa N`.
    pub radius_none: f64,
    pub radius_all: f64,
    pub verdict: Verdict,
    /// Whether this is the integrator the scene's fixed engine uses.
    pub selected: bool,
}

/// The relaxation step of detached junctions, `x *= 1 - lambda dt`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Relaxation {
    pub lambda_dt: f64,
    /// `|1 - lambda dt| <= 1`, i.e. `lambda dt <= 2`.
    pub stable: bool,
    /// `1 - lambda dt >= 0`, i.e. `lambda dt <= 1`.
    pub monotone: bool,
}

/// The flip probabilities of one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flips {
    pub rule: FlipRule,
    /// `k0 dt` (strong bonds: every rupture; weak bonds: a rupture at zero tension).
    pub k0_dt: f64,
    /// `kon0 dt`, the largest formation `k dt` (`g <= 1`).
    pub kon0_dt: f64,
    /// Weak bonds: the tension at which `k_off dt = 1`, `ln(1/(k0 dt)) / (beta dx)`; above it the
    /// linear rule saturates. `None` for strong bonds or when no such tension exists.
    pub weak_saturation_tension: Option<f64>,
}

impl Flips {
    /// Whether a constant rate of the scene reaches `k dt >= 1`, where the linear rule
    /// saturates (probability 1) and the as-printed rule never flips.
    pub fn saturated(&self) -> bool {
        self.rule != FlipRule::Exponential && (self.k0_dt >= 1.0 || self.kon0_dt >= 1.0)
    }
}

/// The whole analysis of a scene's fixed-step scheme.
#[derive(Clone, Debug, PartialEq)]
pub struct Analysis {
    pub dt: f64,
    pub mass: f64,
    pub eta: f64,
    /// `K` (no junction attached) and `K + kappa N` (all attached).
    pub k_none: f64,
    pub k_all: f64,
    pub n: usize,
    pub force_law: ForceLawKind,
    /// Why every junction stiffness is at most the one `k_all` counts (the law's
    /// `ForceLaw::STIFFNESS_NOTE`).
    pub stiffness_note: &'static str,
    /// The integrators that apply: the three inertial ones for `M > 0`, the overdamped one
    /// for `M = 0`.
    pub plate: Vec<PlateLimit>,
    pub relaxation: Relaxation,
    pub flips: Flips,
}

/// Minimum and maximum of `dt_limit` over `k in [k_none, k_all]`.
fn limit_range(integrator: Integrator, mass: f64, eta: f64, k_none: f64, k_all: f64) -> (f64, f64) {
    let at = |k: f64| dt_limit(integrator, Oscillator { mass, eta, k });
    let (a, b) = (at(k_none), at(k_all));
    let mut hi = a.max(b);
    // Explicit Euler's limit grows with k up to critical damping and falls after it.
    if integrator == Integrator::ExplicitEuler && mass > 0.0 {
        let k_crit = eta * eta / (4.0 * mass);
        if k_crit > k_none && k_crit < k_all {
            hi = hi.max(at(k_crit));
        }
    }
    (a.min(b), hi)
}

fn verdict(dt: f64, dt_stable: f64, dt_unstable: f64) -> Verdict {
    if dt < dt_stable * (1.0 - AT_LIMIT) {
        Verdict::Stable
    } else if dt > dt_unstable * (1.0 + AT_LIMIT) {
        Verdict::Unstable
    } else if dt >= dt_unstable * (1.0 - AT_LIMIT) {
        Verdict::AtLimit
    } else {
        Verdict::Conditional
    }
}

/// The scene's force law described by `scene::laws`. A law that refuses its parameters
/// (only a hand-built scene: validation refuses it) is analysed as a spring whose
/// stiffness lies in `[0, kappa]`.
fn law_info(j: &JunctionParams) -> LawInfo {
    laws::law_info(j).unwrap_or(LawInfo {
        name: j.force_law.name(),
        exact: ExactMethod::Direct,
        thinning_slope: j.kappa,
        stiffness: (0.0, j.kappa),
        stiffness_note: "junction stiffness taken as at most kappa",
    })
}

/// Analyses the fixed-step scheme of `scene` (whatever its `run.engine`).
pub fn analyse(scene: &Scene) -> Analysis {
    let (j, p, dt) = (&scene.junctions, &scene.plate, scene.fixed.dt);
    let law = law_info(j);
    let (lo, hi) = law.stiffness;
    // Softest and stiffest plate: K + min(lo, 0) N and K + max(hi, 0) N (K and K + kappa N
    // for both current laws).
    let k_none = p.k + lo.min(0.0) * j.n as f64;
    let k_all = p.k + hi.max(0.0) * j.n as f64;
    let selected = Integrator::of_scene(scene);
    let candidates: &[Integrator] = if p.kinematic {
        &[Integrator::Kinematic]
    } else if p.mass == 0.0 {
        &[Integrator::Overdamped]
    } else {
        &[Integrator::SemiImplicitEuler, Integrator::ExplicitEuler, Integrator::VelocityVerlet]
    };
    let plate = candidates
        .iter()
        .map(|&integrator| {
            let (dt_stable, dt_unstable) = limit_range(integrator, p.mass, p.eta, k_none, k_all);
            let osc = |k: f64| Oscillator { mass: p.mass, eta: p.eta, k };
            PlateLimit {
                integrator,
                dt_stable,
                dt_unstable,
                dt_none: dt_limit(integrator, osc(k_none)),
                dt_all: dt_limit(integrator, osc(k_all)),
                radius_none: radius(integrator, osc(k_none), dt),
                radius_all: radius(integrator, osc(k_all), dt),
                verdict: verdict(dt, dt_stable, dt_unstable),
                selected: integrator == selected,
            }
        })
        .collect();
    let lambda_dt = j.lambda * dt;
    let k0_dt = j.k0 * dt;
    let beta_dx = j.beta_dx();
    let weak_saturation_tension =
        (j.bond == BondKind::Weak && beta_dx > 0.0 && k0_dt > 0.0 && k0_dt < 1.0).then(|| (1.0 / k0_dt).ln() / beta_dx);
    Analysis {
        dt,
        mass: p.mass,
        eta: p.eta,
        k_none,
        k_all,
        n: j.n,
        force_law: j.force_law,
        stiffness_note: law.stiffness_note,
        plate,
        relaxation: Relaxation { lambda_dt, stable: lambda_dt <= 2.0, monotone: lambda_dt <= 1.0 },
        flips: Flips { rule: scene.fixed.flip, k0_dt, kon0_dt: j.kon0 * dt, weak_saturation_tension },
    }
}

impl Analysis {
    /// Whether the scene's plate is kinematic (no plate equation, no plate limit).
    pub fn kinematic(&self) -> bool {
        self.plate.iter().any(|r| r.integrator == Integrator::Kinematic)
    }

    /// The plate row of the integrator the scene uses.
    pub fn selected(&self) -> &PlateLimit {
        self.plate.iter().find(|r| r.selected).expect("the scene's integrator is analysed")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes as testkit;

    /// A kinematic plate has no plate equation: one row, no limit, at any `dt` and even at
    /// a plate that would be unstable (the letter's Fig. 1 at `dt = 1` is at the limit of
    /// semi-implicit Euler).
    #[test]
    fn kinematic_plate_has_no_limit() {
        for extra in [&[][..], &["plate.mass=0"][..], &["fixed.dt=5"][..]] {
            let mut o = vec!["plate.kinematic=true", "run.engine=fixed"];
            o.extend_from_slice(extra);
            let a = analyse(&testkit::fig1_with(&o));
            assert!(a.kinematic());
            assert_eq!(a.plate.len(), 1, "{extra:?}");
            let r = a.selected();
            assert_eq!((r.integrator, r.verdict), (Integrator::Kinematic, Verdict::Stable));
            assert_eq!((r.dt_stable, r.dt_unstable, r.radius_all), (f64::INFINITY, f64::INFINITY, 0.0));
        }
    }

    #[test]
    fn fig1_limits() {
        let a = analyse(&testkit::fig1());
        let row = |i| *a.plate.iter().find(|r| r.integrator == i).unwrap();
        let si = row(Integrator::SemiImplicitEuler);
        assert!((si.dt_all - 300.0 / (75.0 + 59625f64.sqrt())).abs() < 1e-14);
        assert!((si.dt_none - 1.0).abs() < 1e-15);
        assert_eq!(si.verdict, Verdict::AtLimit);
        assert!((si.radius_none - 1.0).abs() < 1e-12 && (si.radius_all - 1.4).abs() < 1e-12);
        assert!(si.selected);
        let ee = row(Integrator::ExplicitEuler);
        assert!((ee.dt_all - 75.0 / 180.0).abs() < 1e-15 && (ee.dt_none - 0.5).abs() < 1e-15);
        assert_eq!(ee.verdict, Verdict::Unstable);
        let vv = row(Integrator::VelocityVerlet);
        assert!((vv.dt_all - 2.0 * (75.0f64 / 180.0).sqrt()).abs() < 1e-14);
        assert_eq!(vv.verdict, Verdict::Stable);
        assert!((vv.radius_all - (1.0f64 / 3.0).sqrt()).abs() < 1e-12);
        let od = analyse(&testkit::fig1_with(&["plate.mass=0"]));
        assert_eq!(od.plate.len(), 1);
        assert!((od.plate[0].dt_none - 1.0).abs() < 1e-15);
        assert_eq!(od.plate[0].verdict, Verdict::AtLimit);
        assert!(a.relaxation.monotone && !a.flips.saturated());
    }

    #[test]
    fn explicit_euler_can_be_stabilised_by_stiffness() {
        // Heavily damped: c = 100, so dt = 0.03 (h c = 3) is unstable for a free plate and
        // stable near critical damping k = eta^2/(4M) = 2500.
        let s = testkit::fig1_with(&[
            "plate.mass=1",
            "plate.eta=100",
            "plate.k=0",
            "junctions.kappa=10",
            "junctions.n=300",
            "fixed.dt=0.03",
            "fixed.integrator=explicit-euler",
        ]);
        let r = *analyse(&s).selected();
        assert_eq!(r.verdict, Verdict::Conditional);
        assert!(r.dt_unstable > r.dt_none && r.dt_unstable > r.dt_all);
        assert!((r.dt_unstable - 4.0 / 100.0).abs() < 1e-15, "critical damping: 4M/eta");
    }
}
