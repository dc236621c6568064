//! Linear stability of the fixed-step plate update, used to flag points whose `dt` lies
//! beyond it.
//!
//! With the junction states frozen, the plate equation is linear in the lag `u = X - V t`
//! with stiffness `k = K + kappa N_att` (attached junctions move with the plate; the
//! `tilted` law's stiffness `d f^x / d x = kappa (1 - l0^3 / l^3)` never exceeds `kappa`).
//! One step maps `(u, Xd)` by a 2x2 matrix; its spectral radius is the factor by which a
//! plate oscillation grows per step. The study evaluates it in the stiffest state, every
//! junction attached (`k = K + kappa N`): above 1 the scheme amplifies the plate's
//! oscillation whenever enough junctions hold. The analysis itself is [`crate::stability`].

use crate::engine::fixed::Integrator;
use crate::scene::Scene;
use crate::stability::{Oscillator, radius};

/// Growth factor per step of the scene's fixed-step plate update at step `dt`, with every
/// junction attached: the spectral radius of the engine's own step
/// ([`crate::stability::amplification`]) for `k = K + kappa N`.
pub fn plate_growth(scene: &Scene, dt: f64) -> f64 {
    let p = &scene.plate;
    let k = p.k + scene.junctions.kappa * scene.junctions.n as f64;
    radius(Integrator::new(scene.fixed.integrator, p.mass), Oscillator { mass: p.mass, eta: p.eta, k }, dt)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::fig1_with;

    #[test]
    fn fig1_is_unstable_at_dt_1_and_stable_at_half() {
        // Fig. 1, every junction attached: w2 = (150 + 30)/75 = 2.4, c = 1; at dt = 1 the
        // semi-implicit Euler matrix is [[-1.4, 0], [-2.4, 0]], radius 1.4.
        let s = fig1_with(&[]);
        assert!((plate_growth(&s, 1.0) - 1.4).abs() < 1e-12);
        assert!((plate_growth(&s, 0.5) - 0.5f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn growth_matches_iterating_the_integrator() {
        // The radius is the asymptotic growth of the actual plate step, for each integrator.
        use crate::engine::fixed::integrator::{Integrator, PlateState};
        use crate::physics::Plate;
        for kind in ["semi-implicit-euler", "explicit-euler", "velocity-verlet"] {
            for dt in [0.3, 0.9, 1.2] {
                let s = fig1_with(&[&format!("fixed.integrator={kind}"), "plate.v=0", "junctions.kappa=0"]);
                let p = Plate { mass: s.plate.mass, eta: s.plate.eta, k: s.plate.k, v: 0.0 };
                let integ = Integrator::new(s.fixed.integrator, s.plate.mass);
                let steps = 400;
                // Mean log growth per step over the second half of the run (renormalised).
                let (mut x, mut v, mut log_growth) = (1.0, 0.3, 0.0);
                for n in 0..steps {
                    let st = PlateState { t: n as f64 * dt, t_next: (n + 1) as f64 * dt, x, v, bond_force: 0.0 };
                    let out = integ.step(&p, dt, st, |_| 0.0);
                    let norm = out.x.abs().max(out.v.abs());
                    if n >= steps / 2 {
                        log_growth += (norm / x.abs().max(v.abs())).ln();
                    }
                    (x, v) = (out.x / norm, out.v / norm);
                }
                let measured = (log_growth / (steps / 2) as f64).exp();
                let predicted = plate_growth(&s, dt);
                assert!((measured - predicted).abs() < 0.02 * predicted, "{kind} dt {dt}: {measured} vs {predicted}");
            }
        }
    }
}
