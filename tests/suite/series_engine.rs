//! The series engine for the tilted law (`exact.tilted = "series"`): event-log invariants
//! over many seeds (strong and weak bonds, dynamic and kinematic plate), stiff plates at a
//! bounded cost, and agreement with the direct (O(N), DOP853) engine.

use stickslip::Scene;
use stickslip::engine::Counters;
use stickslip::engine::exact::stepper::series::{DIRECT_MAX, SeriesSum};
use stickslip::observe::EventKind;
use stickslip::runner::Recording;
use stickslip_testkit::{BONDS, scene};

fn record(scene: &Scene) -> (Recording, Counters) {
    let r = stickslip::runner::record(scene);
    assert!(r.completed(), "{:?}", r.error);
    let c = r.counters.clone();
    (r, c)
}

/// The event log replays to the sampled attached counts, each junction alternates,
/// times strictly increase, segments tile `[0, t_end]`; friction is `K (V t - X)` for a
/// dynamic plate and the bond force with `X = V t` for a kinematic one.
fn check(s: &Scene, r: &Recording, c: &Counters) {
    let n = s.junctions.n;
    let ruptures = r.events.iter().filter(|e| e.kind == EventKind::Rupture).count() as u64;
    assert_eq!(ruptures, c.ruptures);
    assert_eq!(r.events.len() as u64 - ruptures, c.formations);
    assert_eq!(c.events, Some(c.ruptures + c.formations));
    let mut attached = vec![None::<bool>; n];
    let mut count = r.samples[0].attached as i64;
    let mut last_t = f64::NEG_INFINITY;
    for e in &r.events {
        assert!(e.t >= last_t, "event times increase: {} after {}", e.t, last_t);
        last_t = e.t;
        let j = e.junction as usize;
        let now = e.kind == EventKind::Formation;
        if let Some(was) = attached[j] {
            assert_ne!(was, now, "junction {j} {:?} twice in a row at t = {}", e.kind, e.t);
        }
        attached[j] = Some(now);
        count += if now { 1 } else { -1 };
        assert!((0..=n as i64).contains(&count));
        assert!(e.tension >= 0.0 && e.extension.is_finite());
    }
    assert_eq!(count, r.samples.last().unwrap().attached as i64, "replayed count equals the final sample");
    let (k, v) = (s.plate.k, s.plate.v);
    for smp in &r.samples {
        assert!(smp.attached <= n as u64);
        if s.plate.kinematic {
            assert!((smp.x - v * smp.t).abs() <= 1e-9 * (1.0 + v * smp.t), "X = V t: {} vs {}", smp.x, v * smp.t);
            assert_eq!(smp.friction, smp.bond_force);
            assert_eq!(smp.v, v);
        } else {
            let f = k * (v * smp.t - smp.x);
            assert!((smp.friction - f).abs() <= 1e-9 * k * (smp.x.abs() + v * smp.t + 1.0), "{} vs {f}", smp.friction);
        }
    }
    let mut t = 0.0;
    for seg in &r.segments {
        assert!((seg.t0 - t).abs() <= 1e-12 * (1.0 + t), "segments tile time");
        assert!(seg.t1 >= seg.t0 && seg.friction_m2 >= 0.0 && seg.friction.is_finite());
        if s.plate.kinematic {
            assert_eq!(seg.viscous, 0.0);
            assert_eq!(seg.friction, seg.bond_force);
        }
        t = seg.t1;
    }
    assert!((t - s.run.t_end).abs() < 1e-9);
    assert!(c.series_rebases.is_some() && c.series_error.is_some());
}

#[test]
fn event_log_and_samples_are_consistent() {
    let mut runs = 0;
    for bond in BONDS.iter().map(|b| b.name()) {
        for kinematic in [false, true] {
            for reattach in ["residual", "unstretched"] {
                for seed in 1..=5u64 {
                    let s = scene(
                        stickslip_testkit::FIG1,
                        &[
                            "run.engine=exact",
                            "junctions.force_law=tilted",
                            "junctions.n=40",
                            "junctions.initial=stationary",
                            &format!("junctions.bond={bond}"),
                            &format!("junctions.reattach={reattach}"),
                            &format!("plate.kinematic={kinematic}"),
                            &format!("run.seed={seed}"),
                            "run.t_end=60",
                            "output.sample_dt=0.5",
                        ],
                    );
                    let (r, c) = record(&s);
                    assert!(c.events.unwrap() > 50, "{bond} kinematic={kinematic}: {:?} events", c.events);
                    check(&s, &r, &c);
                    runs += 1;
                }
            }
        }
    }
    assert_eq!(runs, 40);
}

/// Stiff and degenerate plates run at a cost set by the events, not by the stiffness: the
/// accepted integrator steps stay below `STEPS_PER_EVENT` per event plus
/// `STEPS_PER_LENGTH` per junction length `l0` the drive travels (`V t_end / l0`). An
/// explicit integrator would need `t_end / sqrt(M / K)` = 5e10 steps for the first scene.
/// (An underdamped stiff plate, `k = 1e9` with `M = eta = 75`, is not here: its physical
/// oscillation at `omega = 3700`, excited by every event, is resolved to the tolerance.)
#[test]
fn stiff_plates_cost_what_their_events_cost() {
    const STEPS_PER_EVENT: f64 = 12.0;
    const STEPS_PER_LENGTH: f64 = 200.0;
    let cases: [&[&str]; 4] = [
        &["plate.mass=1e-9", "plate.eta=100", "plate.k=1e9"],
        &["plate.mass=0", "plate.eta=75"],
        &["plate.eta=0"],
        &["plate.mass=1e-6", "plate.eta=100", "plate.k=1e9"],
    ];
    for (i, case) in cases.iter().enumerate() {
        for bond in BONDS.iter().map(|b| b.name()) {
            let mut o = vec![
                "run.engine=exact",
                "junctions.force_law=tilted",
                "junctions.n=300",
                "junctions.initial=stationary",
                "run.t_end=50",
                "output.sample_dt=1",
            ];
            let b = format!("junctions.bond={bond}");
            o.push(&b);
            o.extend_from_slice(case);
            let s = scene(stickslip_testkit::FIG1, &o);
            let (r, c) = record(&s);
            check(&s, &r, &c);
            let events = c.events.unwrap() as f64;
            let lengths = s.plate.v * s.run.t_end / s.junctions.l0;
            let steps = c.ode_steps.unwrap() as f64;
            eprintln!("case {i} {bond}: {events} events, {steps} steps, {:?} rejected", c.ode_rejected);
            assert!(events > 100.0);
            assert!(
                steps <= STEPS_PER_EVENT * events + STEPS_PER_LENGTH * lengths,
                "case {i} {bond}: {steps} steps for {events} events"
            );
            assert!(r.samples.iter().all(|s| s.x.is_finite() && s.friction.is_finite()));
        }
    }
}

/// The scaled Fig. 1 scene of the path-by-path comparisons (`K = N/2`, `M = eta = N/4`,
/// tilted law, `t_end = 100`) with `exact.tilted = method` and the `extra` overrides.
fn path_scene(n: usize, seed: u64, method: &str, extra: &[&str]) -> Scene {
    let o = [
        "run.engine=exact".to_string(),
        "junctions.force_law=tilted".into(),
        format!("junctions.n={n}"),
        format!("plate.k={}", 0.5 * n as f64),
        format!("plate.mass={}", 0.25 * n as f64),
        format!("plate.eta={}", 0.25 * n as f64),
        format!("run.seed={seed}"),
        "run.t_end=100".into(),
        format!("exact.tilted={method}"),
    ];
    let mut o: Vec<&str> = o.iter().map(String::as_str).collect();
    o.extend_from_slice(extra);
    scene(stickslip_testkit::FIG1, &o)
}

/// Strong bonds: the series engine and the direct (DOP853, O(N)) engine draw the same
/// random numbers in the same order (initial state, channel clocks, uniform picks, the
/// formation acceptance), so with a few junctions they follow the same path: the same
/// events at the same times, and the plate within the integrators' tolerances. The bound
/// `1e-6 (1 + |X|)` allows the local tolerance `rtol = 1e-10` of each of up to 1e4 steps.
#[test]
fn strong_bonds_follow_the_direct_engine_path_by_path() {
    for n in [3, 30] {
        for seed in 1..=3u64 {
            same_path_as_direct(n, seed, 10);
        }
    }
}

/// Direct mode at the letter's junction count: with `N = 300` (and 100) the series engine
/// keeps its series in direct mode (`N < DIRECT_MAX`: radius `l0/4`, a re-base rebuilds
/// the series from the junctions) and still follows the direct engine (`exact.tilted =
/// "direct"`, DOP853 on the junctions themselves) path by path under a shared seed: the
/// same events at the same times, extensions and plate within the integrators' and the
/// series' tolerances (`1e-6 (1 + |X|)`, as above).
#[test]
fn direct_mode_series_follows_the_direct_engine_path_by_path() {
    for n in [100, 300] {
        let law = stickslip::physics::Tilted { kappa: 0.1, l0: 1.0 };
        assert!(SeriesSum::for_junctions(law, 1e-10, n).is_direct() && n < DIRECT_MAX, "N = {n}: not direct mode");
        for seed in 1..=2u64 {
            same_path_as_direct(n, seed, 5 * n);
        }
    }
}

/// The run's main outputs, the friction mean and standard deviation and the mean bond
/// and viscous forces, from the series engine's piece statistics (dense-output integrals
/// and the force balance) against the direct engine's quadratures, on realisations that
/// coincide path-wise (strong bonds, a few junctions: the same events, see
/// `strong_bonds_follow_the_direct_engine_path_by_path`). They differ by the two integrators' and the series'
/// errors: relative `rtol` per step at most, added over the steps of the longer run.
#[test]
fn statistics_match_the_direct_engine_path_by_path() {
    for n in [3usize, 30] {
        for seed in 1..=2u64 {
            let run = |method: &str| {
                let s = path_scene(n, seed, method, &["output.trace=false"]);
                (stickslip::run_scene(&s, None).unwrap(), s.exact.rtol)
            };
            let ((a, rtol), (b, _)) = (run("series"), run("direct"));
            assert_eq!((a.counters.ruptures, a.counters.formations), (b.counters.ruptures, b.counters.formations));
            let steps = a.counters.ode_steps.unwrap().max(b.counters.ode_steps.unwrap()) as f64;
            let tol = steps * rtol;
            let scale = a.friction_mean.abs().max(a.bond_force_mean.abs());
            for (name, x, y) in [
                ("friction_mean", a.friction_mean, b.friction_mean),
                ("friction_std", a.friction_std, b.friction_std),
                ("bond_force_mean", a.bond_force_mean, b.bond_force_mean),
                ("viscous_force_mean", a.viscous_force_mean, b.viscous_force_mean),
            ] {
                assert!(
                    (x - y).abs() <= tol * scale,
                    "n = {n} seed {seed}: {name} {x} vs {y}, tolerance {tol:.1e} x {scale}"
                );
            }
        }
    }
}

/// The series and direct engines on `path_scene(n, seed)` under a shared seed: more than
/// `min_events` events, the same events at the same times, extensions and plate within
/// `1e-6 (1 + |value|)` (the integrators' and the series' tolerances).
fn same_path_as_direct(n: usize, seed: u64, min_events: usize) {
    let run = |method: &str| record(&path_scene(n, seed, method, &["output.sample_dt=0.5"])).0;
    let (a, b) = (run("series"), run("direct"));
    assert!(a.events.len() > min_events, "n = {n}: {} events", a.events.len());
    assert_eq!(a.events.len(), b.events.len(), "n = {n} seed {seed}: event counts");
    for (x, y) in a.events.iter().zip(&b.events) {
        assert_eq!((x.t, x.junction, x.kind), (y.t, y.junction, y.kind), "n = {n} seed {seed}");
        assert!(
            (x.extension - y.extension).abs() <= 1e-6 * (1.0 + y.extension.abs()),
            "n = {n} seed {seed} t = {}: extension {} vs {}",
            x.t,
            x.extension,
            y.extension
        );
    }
    for (x, y) in a.samples.iter().zip(&b.samples) {
        assert!((x.x - y.x).abs() <= 1e-6 * (1.0 + y.x.abs()), "t = {}: {} vs {}", x.t, x.x, y.x);
        assert!((x.v - y.v).abs() <= 1e-6 * (1.0 + y.v.abs()), "t = {}: {} vs {}", x.t, x.v, y.v);
    }
}
