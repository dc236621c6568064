//! The expected amount of work of a run: steps of the fixed engine, events (ruptures and
//! formations) of either engine, rows of the output files.

use crate::physics::Formation;
use crate::scene::{EngineKind, Initial, Scene};

/// Expected work of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct Work {
    /// Fixed engine: steps, `ceil(t_end / dt)`.
    pub steps: Option<u64>,
    /// Expected junction events (ruptures + formations) over `[0, t_end]`.
    pub events: f64,
    /// Rows of `trace.csv` (output samples).
    pub samples: u64,
}

/// Expected events of `n` junctions over `[0, t]`, each a two-state Markov chain that
/// ruptures at `k_off` and forms at `k_on`, attached at `t = 0` with probability `p0`:
/// `n (2 r t + (p0 - p*) (k_off - k_on) (1 - exp(-s t)) / s)` with `s = k_on + k_off`,
/// `p* = k_on / s`, `r = k_on k_off / s` (exact for constant rates).
pub fn two_state_events(n: f64, k_off: f64, k_on: f64, p0: f64, t: f64) -> f64 {
    let s = k_on + k_off;
    // NaN counts as not positive.
    let positive = |v: f64| v > 0.0;
    if !positive(s) || !positive(t) {
        return 0.0;
    }
    let p_star = k_on / s;
    let r = k_on * k_off / s;
    // (1 - exp(-s t)) / s without cancellation for small s t.
    let relax = -(-s * t).exp_m1() / s;
    n * (2.0 * r * t + (p0 - p_star) * (k_off - k_on) * relax).max(0.0)
}

/// The expected work of `scene`. Events use the rates at zero force and at the drive
/// velocity, `k_off = k0`, `k_on = kon0 g(V)`: exact in expectation for strong bonds on a
/// kinematic plate, an approximation otherwise (weak bonds rupture faster under load; a
/// stick-slip plate moves slower than `V`, then faster).
pub fn expected(scene: &Scene) -> Work {
    let j = &scene.junctions;
    let run = &scene.run;
    let k_on = Formation::from_scene(scene).k_on(scene.plate.v);
    let p0 = match j.initial {
        Initial::Detached => 0.0,
        Initial::Attached => 1.0,
        Initial::Stationary => j.kon0 / (j.kon0 + j.k0),
    };
    let events = two_state_events(j.n as f64, j.k0, k_on, p0, run.t_end);
    let (steps, sample_dt) = match run.engine {
        EngineKind::Fixed => {
            let dt = scene.fixed.dt;
            // The fixed engine rounds the output interval to whole steps.
            (Some(scene.fixed.steps_for(run.t_end)), (scene.output.sample_dt / dt).round().max(1.0) * dt)
        }
        EngineKind::Exact => (None, scene.output.sample_dt),
    };
    let samples = (run.t_end / sample_dt).floor().min(u64::MAX as f64) as u64 + 1;
    Work { steps, events, samples }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_state_events_limits() {
        // Stationary start: 2 r t per junction.
        let (koff, kon) = (0.3, 0.1);
        let p = kon / (kon + koff);
        let r = kon * koff / (kon + koff);
        assert!((two_state_events(10.0, koff, kon, p, 5.0) - 10.0 * 2.0 * r * 5.0).abs() < 1e-12);
        // No formation: every attached junction ruptures once, eventually.
        let all = two_state_events(1000.0, 2.0, 0.0, 1.0, 1e3);
        assert!((all - 1000.0).abs() < 1e-9, "{all}");
        let some = two_state_events(1000.0, 2.0, 0.0, 1.0, 0.5);
        assert!((some - 1000.0 * (1.0 - (-1.0f64).exp())).abs() < 1e-9, "{some}");
        assert_eq!(two_state_events(5.0, 0.0, 0.0, 0.5, 1.0), 0.0);
    }
}
