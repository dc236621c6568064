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

use crate::engine::fixed::Integrator;
use crate::engine::fixed::integrator::PlateState;
use crate::physics::ExactMethod;
use crate::physics::Plate;
use crate::scene::laws::{self, LawInfo};
use crate::scene::{BondKind, EngineKind, FlipRule, ForceLawKind, JunctionParams, Scene};

/// The linearised plate `M Xdd + eta Xd + k X = 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oscillator {
    pub mass: f64,
    pub eta: f64,
    pub k: f64,
}

/// A 2x2 matrix acting on `(X, Xd)`, row-major.
pub type Matrix = [[f64; 2]; 2];

/// Relative slack within which a `dt` counts as *at* a limit rather than beyond it.
pub const AT_LIMIT: f64 = 1e-9;

/// The amplification matrix of one step of `integrator` for the oscillator `o`, obtained by
/// applying the engine's own plate step ([`Integrator::step`]) to the unit states
/// `(1, 0)` and `(0, 1)` with no driving (`V = 0`) and all stiffness in the spring
/// (`F_b = 0`). Inertial integrators need `M > 0`, the overdamped one `eta > 0`.
pub fn amplification(integrator: Integrator, o: Oscillator, dt: f64) -> Matrix {
    let p = Plate { mass: o.mass, eta: o.eta, k: o.k, v: 0.0 };
    let column = |x: f64, v: f64| {
        let s = integrator.step(&p, dt, PlateState { t: 0.0, t_next: dt, x, v, bond_force: 0.0 }, |_| 0.0);
        (s.x, s.v)
    };
    let (x1, v1) = column(1.0, 0.0);
    let (x2, v2) = column(0.0, 1.0);
    [[x1, x2], [v1, v2]]
}

/// Spectral radius of a real 2x2 matrix: the larger modulus of the roots of
/// `z^2 - tr z + det`.
pub fn spectral_radius(a: Matrix) -> f64 {
    let half = 0.5 * (a[0][0] + a[1][1]);
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    // (tr/2)^2 - det, written as ((a - d)/2)^2 + b c: no cancellation near a double root.
    let diff = 0.5 * (a[0][0] - a[1][1]);
    let disc = diff * diff + a[0][1] * a[1][0];
    if disc >= 0.0 {
        // Real roots half +- sqrt(disc): the larger modulus has the sign of `half`.
        half.abs() + disc.sqrt()
    } else {
        // A complex pair: |z|^2 = det (> half^2 >= 0 here).
        det.sqrt()
    }
}

/// `rho(A)` of one step of `integrator` of size `dt` for `o`.
pub fn radius(integrator: Integrator, o: Oscillator, dt: f64) -> f64 {
    spectral_radius(amplification(integrator, o, dt))
}

/// The largest stable step of `integrator` for `o`, in closed form (docs/stability.md):
/// steps `dt < dt_limit` are stable, `dt = dt_limit` has an eigenvalue of modulus 1, larger
/// steps grow. `+inf` when every step is stable, `0` when none is (explicit Euler on an
/// undamped oscillator).
pub fn dt_limit(integrator: Integrator, o: Oscillator) -> f64 {
    let Oscillator { mass: m, eta, k } = o;
    // 2 sqrt(k M), without forming k M (which could overflow).
    let s = 2.0 * k.sqrt() * m.sqrt();
    match integrator {
        Integrator::SemiImplicitEuler => {
            if k == 0.0 && eta == 0.0 {
                f64::INFINITY
            } else {
                // Root of h^2 k/M + 2 h eta/M = 4, written without cancellation.
                4.0 * m / (eta + eta.hypot(s))
            }
        }
        Integrator::ExplicitEuler => {
            if k == 0.0 {
                if eta == 0.0 { f64::INFINITY } else { 2.0 * m / eta }
            } else if eta <= s {
                // Underdamped: the complex pair leaves the unit circle at det = 1.
                eta / k
            } else {
                // Overdamped: a real eigenvalue reaches -1 first.
                4.0 * m / (eta + ((eta - s) * (eta + s)).sqrt())
            }
        }
        Integrator::VelocityVerlet => {
            if k == 0.0 {
                f64::INFINITY
            } else {
                2.0 * (m.sqrt() / k.sqrt())
            }
        }
        Integrator::Overdamped => {
            if k == 0.0 {
                f64::INFINITY
            } else {
                2.0 * eta / k
            }
        }
        // No plate equation (`X = V t`): nothing to become unstable.
        Integrator::Kinematic => f64::INFINITY,
    }
}

/// Whether a 2x2 amplification matrix is stable, by the Jury (Schur–Cohn) conditions on
/// its characteristic polynomial `z^2 - tr z + det`: both roots in the closed unit disc iff
/// `det <= 1` and `|tr| <= 1 + det`, each up to `tol` (round-off at neutral eigenvalues).
/// Unlike a threshold on [`spectral_radius`] (a square root of a discriminant that vanishes at
/// double roots), these are polynomial in the entries and keep their accuracy at the boundary.
pub fn is_stable(a: Matrix, tol: f64) -> bool {
    let tr = a[0][0] + a[1][1];
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    det <= 1.0 + tol && tr.abs() <= 1.0 + det + tol
}

/// The largest stable step found numerically: the first `dt` on a geometric scan (factor
/// 2, from `1e-300` to `1e100`, beyond which `dt^2` could overflow) whose amplification matrix fails [`is_stable`], refined by
/// bisection to relative precision `1e-13`. A cross-check of [`dt_limit`] that needs only
/// the integrator's step; assumes the stable steps form an interval `(0, dt_limit)`, which
/// holds for every integrator here.
pub fn dt_limit_numeric(integrator: Integrator, o: Oscillator, tol: f64) -> f64 {
    let unstable = |dt: f64| !is_stable(amplification(integrator, o, dt), tol);
    let mut lo = 1e-300;
    if unstable(lo) {
        return 0.0;
    }
    let mut hi = lo;
    loop {
        hi *= 2.0;
        if hi > 1e100 {
            return f64::INFINITY;
        }
        if unstable(hi) {
            break;
        }
        lo = hi;
    }
    while (hi - lo) > 1e-13 * hi {
        let mid = 0.5 * (lo + hi);
        if unstable(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

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

/// The scene-file name of an integrator.
pub fn integrator_name(i: Integrator) -> &'static str {
    match i {
        Integrator::SemiImplicitEuler => "semi-implicit-euler",
        Integrator::ExplicitEuler => "explicit-euler",
        Integrator::VelocityVerlet => "velocity-verlet",
        Integrator::Overdamped => "overdamped-euler",
        Integrator::Kinematic => "kinematic",
    }
}

fn rule_name(r: FlipRule) -> &'static str {
    match r {
        FlipRule::Linear => "linear",
        FlipRule::Exponential => "exponential",
        FlipRule::AsPrinted => "as-printed",
    }
}

/// A number in at most 6 significant digits (`inf` for an unbounded limit).
pub fn num(x: f64) -> String {
    if x.is_infinite() {
        return if x > 0.0 { "inf".into() } else { "-inf".into() };
    }
    if x.is_nan() {
        // Parameters at the edge of the floating-point range (e.g. a subnormal mass) can
        // leave a limit undefined; say so rather than print a number.
        return "undefined".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-4..1e6).contains(&a) {
        let s = format!("{:.*}", (5 - a.log10().floor() as i32).max(0) as usize, x);
        if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
    } else {
        let s = format!("{x:.5e}");
        let (m, e) = s.split_once('e').expect("exponent form");
        let m = if m.contains('.') { m.trim_end_matches('0').trim_end_matches('.') } else { m };
        format!("{m}e{e}")
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

    /// What "all attached" means for the scene's force law.
    fn stiffest(&self) -> String {
        format!("K + kappa N = {} with all {} junctions attached ({})", num(self.k_all), self.n, self.stiffness_note)
    }

    /// The verdict of one row in words.
    pub fn explain(&self, r: &PlateLimit) -> String {
        if r.integrator == Integrator::Kinematic {
            return "no plate equation (plate.kinematic: X = V t): no limit".into();
        }
        let neutral = if self.eta == 0.0 && r.integrator != Integrator::ExplicitEuler {
            " (undamped: oscillations keep their amplitude, as in the exact solution)"
        } else {
            ""
        };
        match r.verdict {
            Verdict::Stable => format!("stable for every attached count{neutral}"),
            Verdict::Unstable => {
                if r.dt_stable == 0.0 && r.dt_unstable == 0.0 {
                    "unstable at every dt (explicit Euler amplifies an undamped oscillation each step)".into()
                } else {
                    "unstable for every attached count: oscillations grow until the run fails".into()
                }
            }
            Verdict::AtLimit => {
                "at the limit: |eig| = 1 with the most favourable attached count (an oscillation that never \
                 decays), > 1 with the others"
                    .into()
            }
            Verdict::Conditional => {
                let which = match (self.dt < r.dt_none, self.dt < r.dt_all) {
                    (true, false) => "few",
                    (false, true) => "many",
                    _ => "some but not too many",
                };
                format!("conditional: stable only while {which} junctions are attached")
            }
        }
    }

    /// The table printed by `stickslip stability`.
    pub fn table(&self, scene_name: &str) -> String {
        let mut out = String::new();
        let push = |out: &mut String, s: String| {
            out.push_str(&s);
            out.push('\n');
        };
        push(
            &mut out,
            format!("# stability of the fixed-step scheme: scene {scene_name}, fixed.dt = {}", num(self.dt)),
        );
        if self.kinematic() {
            push(
                &mut out,
                "# plate.kinematic = true: the plate follows its drive (X = V t), there is no plate equation and so \
                 no plate stability limit"
                    .into(),
            );
        } else {
            push(
                &mut out,
                format!(
                    "# plate linearised as M Xdd + eta Xd + k X = 0 with M = {}, eta = {}, k from K = {} (no junction attached) to {}",
                    num(self.mass),
                    num(self.eta),
                    num(self.k_none),
                    self.stiffest()
                ),
            );
        }
        push(
            &mut out,
            "# dt limit: stable below it whatever the attached count; unstable above: unstable beyond it whatever \
             the attached count; |eig| none / all: spectral radius of one step at the scene's dt with no / all \
             junctions attached"
                .into(),
        );
        let header = ["integrator", "dt limit", "unstable above", "scene dt", "|eig| none", "|eig| all", "verdict"];
        let rows: Vec<[String; 7]> = self
            .plate
            .iter()
            .map(|r| {
                [
                    format!("{}{}", integrator_name(r.integrator), if r.selected { " *" } else { "" }),
                    num(r.dt_stable),
                    num(r.dt_unstable),
                    num(self.dt),
                    num(r.radius_none),
                    num(r.radius_all),
                    self.explain(r),
                ]
            })
            .collect();
        let mut widths = header.map(str::len);
        for row in &rows {
            for (w, c) in widths.iter_mut().zip(row.iter()) {
                *w = (*w).max(c.len());
            }
        }
        let line = |cells: &[&str]| -> String {
            let mut s = String::new();
            for (i, c) in cells.iter().enumerate() {
                if i + 1 == cells.len() {
                    s.push_str(c);
                } else {
                    s.push_str(&format!("{c:<w$}  ", w = widths[i]));
                }
            }
            s
        };
        push(&mut out, line(&header));
        for row in &rows {
            push(&mut out, line(&row.iter().map(String::as_str).collect::<Vec<_>>()));
        }
        push(
            &mut out,
            "(* = the integrator this scene uses; plate.mass = 0 always takes the overdamped Euler step)".into(),
        );
        push(&mut out, self.relaxation_line());
        push(&mut out, self.flips_line());
        out
    }

    /// The relaxation step in one line.
    pub fn relaxation_line(&self) -> String {
        let r = &self.relaxation;
        let verdict = if !r.stable {
            "UNSTABLE: detached extensions grow as |1 - lambda dt|^n"
        } else if !r.monotone {
            "stable but not monotone: detached extensions change sign every step"
        } else {
            "stable and monotone"
        };
        format!(
            "relaxation x *= 1 - lambda dt: lambda dt = {} (stable up to 2, monotone up to 1): {verdict}",
            num(r.lambda_dt)
        )
    }

    /// The flip probabilities in one line.
    pub fn flips_line(&self) -> String {
        let f = &self.flips;
        let mut s =
            format!("flips ({} rule): k0 dt = {}, kon0 dt = {}", rule_name(f.rule), num(f.k0_dt), num(f.kon0_dt));
        s.push_str(match f.rule {
            FlipRule::Linear if f.saturated() => {
                ": SATURATED, k dt >= 1 flips surely (rates above 1/dt are cut to 1/dt)"
            }
            FlipRule::Linear => ": below saturation (k dt < 1)",
            FlipRule::AsPrinted if f.saturated() => ": k dt >= 1 NEVER flips under the as-printed rule",
            FlipRule::AsPrinted => ": the as-printed rule flips with probability 1 - k dt",
            FlipRule::Exponential => ": the exponential rule never saturates (probability 1 - exp(-k dt))",
        });
        if let Some(f_sat) = f.weak_saturation_tension {
            s.push_str(&format!("; weak bonds reach k_off dt = 1 at tension {}", num(f_sat)));
        }
        s
    }

    /// The problems worth a warning before a fixed-step run, in words (empty if none).
    pub fn issues(&self) -> Vec<String> {
        let mut issues = Vec::new();
        let r = self.selected();
        if r.verdict != Verdict::Stable {
            let limit = if r.dt_unstable == 0.0 {
                "no dt is stable for an undamped plate".to_string()
            } else {
                format!(
                    "stable for every attached count only below dt = {} (K + kappa N = {}), unstable for all above {}",
                    num(r.dt_stable),
                    num(self.k_all),
                    num(r.dt_unstable)
                )
            };
            issues.push(format!(
                "fixed.dt = {} is {} for the {} plate step: {limit}; the plate oscillation may grow until the run fails",
                num(self.dt),
                match r.verdict {
                    Verdict::Unstable => "beyond the stability limit",
                    Verdict::AtLimit => "at the stability limit",
                    _ => "beyond the stability limit with junctions attached",
                },
                integrator_name(r.integrator),
            ));
        }
        if !self.relaxation.monotone {
            issues.push(format!(
                "junctions.lambda * fixed.dt = {} > 1: detached extensions change sign every step",
                num(self.relaxation.lambda_dt)
            ));
        }
        if self.flips.saturated() {
            issues.push(format!(
                "k0 dt = {}, kon0 dt = {}: a rate with k dt >= 1 {} under the {} flip rule",
                num(self.flips.k0_dt),
                num(self.flips.kon0_dt),
                if self.flips.rule == FlipRule::AsPrinted { "never flips" } else { "flips surely" },
                rule_name(self.flips.rule)
            ));
        }
        issues
    }

    /// The short block `stickslip validate` prints (comment lines).
    pub fn validate_block(&self, engine: EngineKind) -> Vec<String> {
        let mut lines = vec![format!(
            "# fixed-step stability{} (fixed.dt = {}; `stickslip stability` shows the table):",
            if engine == EngineKind::Fixed { "" } else { " (used only with run.engine = \"fixed\")" },
            num(self.dt)
        )];
        for r in &self.plate {
            lines.push(format!(
                "#   {}{}: dt limit {} (unstable above {}): {}",
                integrator_name(r.integrator),
                if r.selected { " (this scene)" } else { "" },
                num(r.dt_stable),
                num(r.dt_unstable),
                r.verdict.as_str()
            ));
        }
        lines.push(format!("#   {}", self.relaxation_line()));
        lines.push(format!("#   {}", self.flips_line()));
        lines
    }
}

/// The one warning line a fixed-step run of `scene` prints before it starts, if any.
pub fn warning(scene: &Scene) -> Option<String> {
    if scene.run.engine != EngineKind::Fixed {
        return None;
    }
    let issues = analyse(scene).issues();
    (!issues.is_empty()).then(|| format!("warning: {} (see `stickslip stability`)", issues.join("; ")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes as testkit;

    const ALL: [Integrator; 4] =
        [Integrator::SemiImplicitEuler, Integrator::ExplicitEuler, Integrator::VelocityVerlet, Integrator::Overdamped];

    fn osc(mass: f64, eta: f64, k: f64) -> Oscillator {
        Oscillator { mass, eta, k }
    }

    /// Brute force: `||A^n||^(1/n)` tends to `rho(A)` (Gelfand), here with `n = 2^20` by
    /// repeated squaring and rescaling (no overflow).
    fn gelfand(a: Matrix) -> f64 {
        let mul = |a: Matrix, b: Matrix| -> Matrix {
            [
                [a[0][0] * b[0][0] + a[0][1] * b[1][0], a[0][0] * b[0][1] + a[0][1] * b[1][1]],
                [a[1][0] * b[0][0] + a[1][1] * b[1][0], a[1][0] * b[0][1] + a[1][1] * b[1][1]],
            ]
        };
        let norm = |a: Matrix| a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut m = a;
        // log rho = sum of the log-scales / 2^levels.
        let mut log = 0.0;
        let levels = 20;
        for level in 0..levels {
            let s = norm(m);
            if s == 0.0 {
                return 0.0;
            }
            m = m.map(|r| r.map(|v| v / s));
            log += s.ln() / f64::from(1u32 << level);
            m = mul(m, m);
        }
        let s = norm(m);
        if s == 0.0 {
            return 0.0;
        }
        (log + s.ln() / f64::from(1u32 << levels)).exp()
    }

    /// `spectral_radius` (roots of the characteristic polynomial) against Gelfand's formula
    /// on hand-picked matrices and on the integrators' amplification matrices.
    #[test]
    fn spectral_radius_matches_brute_force_powers() {
        let cases = [
            [[1.0, 0.5], [-0.3, 0.8]],
            [[0.0, 1.0], [-1.0, 0.0]],
            [[2.0, 0.0], [0.0, -3.0]],
            [[-1.2, 0.3], [0.1, -0.9]],
            [[1.0, 1.0], [0.0, 1.0]],
            [[0.5, 10.0], [-0.001, 0.2]],
        ];
        for a in cases {
            let (r, g) = (spectral_radius(a), gelfand(a));
            // Gelfand's formula converges like n^(-1/n) for a defective matrix; 2^-20 otherwise.
            assert!((r - g).abs() <= 2e-5 * r.max(1e-300), "{a:?}: {r} vs {g}");
        }
        for i in ALL {
            for (m, eta, k, dt) in [(75.0, 75.0, 180.0, 1.0), (1.0, 0.1, 3.0, 0.7), (2.0, 5.0, 1.0, 0.3)] {
                let m = if i == Integrator::Overdamped { 0.0 } else { m };
                let a = amplification(i, osc(m, eta, k), dt);
                let (r, g) = (spectral_radius(a), gelfand(a));
                assert!((r - g).abs() <= 2e-5 * r, "{i:?}: {r} vs {g}");
            }
        }
    }

    /// The closed-form trace and determinant of each amplification matrix (module docs).
    #[test]
    fn amplification_matrices_have_the_derived_invariants() {
        let (m, eta, k, h) = (2.0, 0.7, 5.0, 0.31);
        let (c, w2) = (eta / m, k / m);
        let tr_det = |a: Matrix| (a[0][0] + a[1][1], a[0][0] * a[1][1] - a[0][1] * a[1][0]);
        let close = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-14 && (a.1 - b.1).abs() < 1e-14;
        let o = osc(m, eta, k);
        let si = tr_det(amplification(Integrator::SemiImplicitEuler, o, h));
        assert!(close(si, (2.0 - h * c - h * h * w2, 1.0 - h * c)), "{si:?}");
        let ee = tr_det(amplification(Integrator::ExplicitEuler, o, h));
        assert!(close(ee, (2.0 - h * c, 1.0 - h * c + h * h * w2)), "{ee:?}");
        let g = h * c / 2.0;
        let vv = tr_det(amplification(Integrator::VelocityVerlet, o, h));
        assert!(close(vv, (2.0 * (1.0 - h * h * w2 / 2.0) / (1.0 + g), (1.0 - g) / (1.0 + g))), "{vv:?}");
        let od = tr_det(amplification(Integrator::Overdamped, osc(0.0, eta, k), h));
        assert!(close(od, (1.0 - h * k / eta, 0.0)), "{od:?}");
    }

    /// Round-off allowance of the Jury conditions (entries of the matrices are O(1)).
    const TOL: f64 = 1e-13;

    /// How far the numeric limit may sit from the closed form: a round-off `TOL` in the Jury
    /// margin that vanishes at the limit moves the numeric limit by `TOL / slope`, with the
    /// margin's slope in `dt/dt_limit` from the module table: velocity Verlet
    /// `1 + tr + det = (4 - (w dt)^2) / (1 + dt c/2)`, slope `~ 8 / (1 + dt c/2)`; explicit
    /// Euler (underdamped) `1 - det = dt c - (w dt)^2`, slope `dt c`; the others O(1).
    fn rel_tolerance(i: Integrator, o: Oscillator, dt: f64) -> f64 {
        let c = if o.mass > 0.0 { o.eta / o.mass } else { 0.0 };
        let slope = match i {
            Integrator::VelocityVerlet => 1.0 / (1.0 + dt * c / 2.0),
            Integrator::ExplicitEuler => (dt * c).min(1.0),
            _ => 1.0,
        };
        1e-9 + 100.0 * TOL / slope
    }

    /// Closed-form limits against the numeric search on the engine's own step, across
    /// under-, critically and over-damped, undamped, stiff and free plates.
    #[test]
    fn closed_form_limits_match_the_numeric_search() {
        let mut checked = 0;
        for &m in &[1e-12, 1e-3, 1.0, 75.0, 1e6] {
            for &eta in &[0.0, 1e-3, 1.0, 75.0, 1e4] {
                for &k in &[0.0, 1e-6, 1.0, 150.0, 180.0, 1e9] {
                    for i in ALL {
                        let m = if i == Integrator::Overdamped { 0.0 } else { m };
                        if i == Integrator::Overdamped && eta == 0.0 {
                            continue;
                        }
                        let o = osc(m, eta, k);
                        let closed = dt_limit(i, o);
                        if i == Integrator::ExplicitEuler && eta == 0.0 && k > 0.0 {
                            // |eig| = sqrt(1 + (w dt)^2) > 1 at every dt: no search can find 0.
                            assert_eq!(closed, 0.0);
                            let w = (k / m).sqrt();
                            for wdt in [1e-6, 1e-3, 1.0, 10.0] {
                                let r = radius(i, o, wdt / w);
                                assert!((r / (1.0 + wdt * wdt).sqrt() - 1.0).abs() < 1e-9, "{r}");
                            }
                            continue;
                        }
                        let numeric = dt_limit_numeric(i, o, TOL);
                        let ok = if closed.is_infinite() || closed == 0.0 {
                            numeric == closed
                        } else {
                            (numeric / closed - 1.0).abs() < rel_tolerance(i, o, closed)
                        };
                        assert!(ok, "{i:?} M={m} eta={eta} k={k}: closed {closed} numeric {numeric}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 500);
        // Exactly critical damping: eta^2 = 4 k M (explicit Euler's two branches meet).
        for (m, k) in [(1.0f64, 1.0f64), (0.25, 4.0), (75.0, 3.0)] {
            let eta = 2.0 * (k * m).sqrt();
            let o = osc(m, eta, k);
            for i in [Integrator::SemiImplicitEuler, Integrator::ExplicitEuler, Integrator::VelocityVerlet] {
                let (c, n) = (dt_limit(i, o), dt_limit_numeric(i, o, TOL));
                assert!((n / c - 1.0).abs() < 1e-6, "{i:?} critical: {c} vs {n}");
            }
            assert_eq!(dt_limit(Integrator::ExplicitEuler, o), eta / k);
        }
    }

    /// Just below a limit every eigenvalue is inside the unit circle, just above one is out.
    #[test]
    fn radius_crosses_one_at_the_limit() {
        for i in ALL {
            for (m, eta, k) in [(75.0, 75.0, 180.0), (1.0, 10.0, 1.0), (1.0, 0.01, 100.0)] {
                let m = if i == Integrator::Overdamped { 0.0 } else { m };
                let o = osc(m, eta, k);
                let l = dt_limit(i, o);
                assert!(radius(i, o, 0.999 * l) < 1.0, "{i:?} {o:?}");
                assert!(radius(i, o, 1.001 * l) > 1.0, "{i:?} {o:?}");
            }
        }
    }

    /// A kinematic plate has no plate equation: one row, no limit, no warning about it,
    /// at any `dt` and even at a plate that would be unstable (the letter's Fig. 1 at
    /// `dt = 1` is at the limit of semi-implicit Euler).
    #[test]
    fn kinematic_plate_has_no_limit() {
        for extra in [&[][..], &["plate.mass=0"][..], &["fixed.dt=5"][..]] {
            let mut o = vec!["plate.kinematic=true", "run.engine=fixed"];
            o.extend_from_slice(extra);
            let s = testkit::fig1_with(&o);
            let a = analyse(&s);
            assert!(a.kinematic());
            assert_eq!(a.plate.len(), 1, "{extra:?}");
            let r = a.selected();
            assert_eq!((r.integrator, r.verdict), (Integrator::Kinematic, Verdict::Stable));
            assert_eq!((r.dt_stable, r.dt_unstable, r.radius_all), (f64::INFINITY, f64::INFINITY, 0.0));
            let table = a.table("k");
            assert!(table.contains("no plate stability limit") && table.contains("kinematic *"), "{table}");
            assert!(a.issues().iter().all(|i| !i.contains("plate step")), "{:?}", a.issues());
        }
        assert!(warning(&testkit::fig1_with(&["plate.kinematic=true", "run.engine=fixed"])).is_none());
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
        assert!(warning(&testkit::fig1()).is_some());
        assert!(warning(&testkit::fig1_with(&["fixed.dt=0.5"])).is_none());
        assert!(warning(&testkit::fig1_with(&["run.engine=exact"])).is_none());
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

    #[test]
    fn numbers_print_short() {
        assert_eq!(num(1.0), "1");
        assert_eq!(num(0.9399209), "0.939921");
        assert_eq!(num(1.2909944487), "1.29099");
        assert_eq!(num(2.7e-14), "2.7e-14");
        assert_eq!(num(f64::INFINITY), "inf");
        assert_eq!(num(150.0), "150");
        assert_eq!(num(1e9), "1e9");
    }
}
