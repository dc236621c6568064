//! Low-velocity creep: the thermally activated (Bell) theory that `examples/creep.rs` and
//! `tests/suite/creep.rs` compare the exact engine with.
//!
//! A weak junction that forms unstretched and is loaded at a constant rate `r` (force per
//! time; `r = kappa V` when the plate slides at `V`) ruptures at rate
//! `k0 exp(f / f_b)`, `f_b = temperature / dx`. Its rupture force `f` has the survival
//! function `S(f) = exp(-(k0 f_b / r) (exp(f / f_b) - 1))`, so with `a = k0 f_b / r`
//! `E[f] = f_b e^a E1(a) ~ f_b (ln(r / (k0 f_b)) - gamma)` for `a << 1`: the rupture force
//! grows by `f_b` per e-fold of the loading rate, `f_b ln 10` per decade of velocity.
//!
//! With re-formation at rate `kon0` (unstretched, `g = 1` below `V0`) each junction runs
//! through cycles of one attached life (tension rising linearly from 0 to `f`, duration
//! `f / r`) and one detached wait (`1 / kon0` on average). By renewal-reward the mean
//! tension per junction is `E[f^2] / (2 r) / (E[f] / r + 1 / kon0)`, and the mean friction
//! per junction adds the viscous part `eta V / N`. For `a << 1`,
//! `E[f^2] = E[f]^2 + (pi^2 / 6) f_b^2` (a Gumbel law), so the friction per junction grows
//! as `(f_b / 2) ln V` plus a slowly varying correction.

use stickslip::Scene;

/// Weight of node `k` of the composite Simpson rule on `n` (even) intervals, before the
/// factor `h/3`: 1 at the ends, 4 at odd nodes, 2 at even inner nodes.
pub fn simpson_weight(k: usize, n: usize) -> f64 {
    if k == 0 || k == n {
        1.0
    } else if k % 2 == 1 {
        4.0
    } else {
        2.0
    }
}

/// `(E[f], E[f^2])` of the rupture force of one junction loaded at rate `r` from `f = 0`,
/// with rupture rate `k0 exp(f / f_b)`; by quadrature of `E[f^n] = n int f^(n-1) S(f) df`.
pub fn bell_moments(r: f64, k0: f64, f_b: f64) -> (f64, f64) {
    let a = k0 * f_b / r;
    let survival = |f: f64| (-a * (f / f_b).exp_m1()).exp();
    // S falls from ~1 to ~0 around f* = f_b ln(1/a); beyond f* + 40 f_b it is below 1e-300.
    let top = f_b * ((1.0 / a).ln().max(0.0) + 40.0);
    let n = 200_000;
    let h = top / n as f64;
    // Composite Simpson.
    let (mut m1, mut m2) = (0.0, 0.0);
    for k in 0..=n {
        let f = k as f64 * h;
        let w = simpson_weight(k, n);
        let s = survival(f);
        m1 += w * s;
        m2 += w * 2.0 * f * s;
    }
    (m1 * h / 3.0, m2 * h / 3.0)
}

/// The Bell theory of a creep scene at its driving velocity `plate.v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CreepTheory {
    /// Loading rate `kappa V`.
    pub loading_rate: f64,
    /// Mean rupture force `E[f]`.
    pub rupture_force: f64,
    /// Mean friction per junction (bond part by renewal-reward, plus `eta V / N`).
    pub friction_per_junction: f64,
    /// Mean attached life `E[f] / r`.
    pub lifetime: f64,
}

/// The theory for a scene with weak bonds, the linear law and `reattach = "unstretched"`.
pub fn theory(scene: &Scene) -> CreepTheory {
    let j = &scene.junctions;
    let r = j.kappa * scene.plate.v;
    let f_b = 1.0 / j.beta_dx();
    let (m1, m2) = bell_moments(r, j.k0, f_b);
    let lifetime = m1 / r;
    let tension = m2 / (2.0 * r) / (lifetime + 1.0 / j.kon0);
    CreepTheory {
        loading_rate: r,
        rupture_force: m1,
        friction_per_junction: tension + scene.plate.eta * scene.plate.v / j.n as f64,
        lifetime,
    }
}
