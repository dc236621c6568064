//! The regime criterion against the `N -> infinity` moment equations of strong linear bonds
//! (`tests/suite/common/moments.rs`), on the scene of `scenarios/limit-cycle.toml`: per-junction plate `m = M/N =
//! 0.25`, `e = eta/N = 0.05`, `k = K/N = 0.1`, `kappa = 0.1`, `k0 = 1`, `kon0 = 0.2`,
//! `lambda = 0.01`, `V0 = 0.5`, all junctions detached at `t = 0`, window `[700, 1500]`.
//!
//! - The moment equations: steady sliding is unstable exactly for `0.570 < V < 1.597`
//!   (Hopf points by bisection on the leading eigenvalue); `V = 1` has a limit cycle,
//!   `V = 0.3` (below `V0`: every rate constant, a linear system) and `V = 2`, `V = 5`
//!   settle to steady sliding. `V = 2` lies close to the upper Hopf point (damping rate 0.029
//!   per time unit at frequency 0.59): its noise is strongly periodic (coherence above 1/2),
//!   the hard case for a criterion.
//! - The detector fed the moment equations' own trajectory (`N = infinity`) and the engines'
//!   runs at `N = 1e3 .. 1e5` call `V = 1` stick-slip and the others smooth: the exact engine
//!   and the fixed-step engine at `dt = 0.01`.
//! - The exact engine's friction mean and standard deviation per junction, and the
//!   oscillation's period and amplitude, extrapolated to `N = infinity` from replicas at two
//!   sizes (the `O(1/N)` finite-size term eliminated: Richardson), agree with the moment
//!   equations within the 99.9 % Student-t interval of the extrapolation.
//!
//! The largest sizes are `#[ignore]`d (minutes): `cargo test --release --test suite regime:: --
//! --ignored` (docs/model.md, "Regime criterion", lists the commands and times).

use crate::common;

use common::mean_ci;
use common::moments::MomentModel;
use stickslip::Scene;
use stickslip::observe::Observer;
use stickslip::observe::regime::{Regime, RegimeDetector, Verdict};
use stickslip::studies::seeds::{Role, pcg_seed};
use stickslip_testkit::verdict_of as verdict;

/// Velocities of the test and whether the moment equations oscillate there.
const CASES: [(f64, Regime); 4] =
    [(0.3, Regime::Smooth), (1.0, Regime::StickSlip), (2.0, Regime::Smooth), (5.0, Regime::Smooth)];

/// The limit-cycle scene at velocity `v` with `n` junctions (plate scaled with `N`), exact engine
/// unless `extra` says otherwise.
fn issue(v: f64, n: usize, extra: &[&str]) -> Scene {
    let text = format!(
        r#"
[junctions]
n = {n}
bond = "strong"
force_law = "linear"
kappa = 0.1
lambda = 0.01
k0 = 1.0
kon0 = 0.2
[plate]
mass = {m}
eta = {e}
k = {k}
v = {v}
[run]
engine = "exact"
t_end = 1500.0
t_warmup = 700.0
[output]
sample_dt = 0.1
trace = false
"#,
        m = 0.25 * n as f64,
        e = 0.05 * n as f64,
        k = 0.1 * n as f64
    );
    stickslip_testkit::scene(&text, extra)
}

/// The detector's verdict on the moment equations' trajectory (`N -> infinity`).
fn verdict_at_infinity(scene: &Scene) -> Verdict {
    let mut d = RegimeDetector::for_scene(scene);
    MomentModel::of(scene).samples(scene).iter().for_each(|s| d.sample(s));
    d.verdict()
}

#[test]
fn the_moment_equations_have_a_limit_cycle_between_two_smooth_ranges() {
    let m = MomentModel::of(&issue(1.0, 1000, &[]));
    let b = m.stability_boundaries(0.05, 20.0, 400);
    assert_eq!(b.len(), 2, "{b:?}");
    assert!((b[0] - 0.5704).abs() < 1e-3 && (b[1] - 1.5967).abs() < 1e-3, "{b:?}");
    for (v, regime) in CASES {
        let mv = m.with_v(v);
        let s = issue(v, 1000, &[]);
        let cycle = mv.limit_cycle(mv.initial(&s), 1500.0);
        match regime {
            Regime::StickSlip => {
                assert!(!mv.stable() && b[0] < v && v < b[1], "V = {v}");
                let (period, half) = cycle.expect("a limit cycle");
                // The friction swings by +-64 % of its steady value.
                assert!((period - 10.80).abs() < 0.01 && half > 0.6 * mv.steady_friction(), "{period} {half}");
            }
            Regime::Smooth => {
                assert!(mv.stable() && !(b[0] < v && v < b[1]), "V = {v}");
                assert!(cycle.is_none(), "V = {v}: {cycle:?}");
            }
            Regime::Unstable => unreachable!("the cases are physical regimes"),
        }
        // The detector on the N -> infinity trajectory.
        let d = verdict_at_infinity(&s);
        assert_eq!(d.regime, regime, "V = {v}: {d:?}");
    }
    // V = 2: the least damped mode, the one noise excites, decays by only
    // e^{-0.029 x 10.6} = 0.73 per period.
    let ev = m.with_v(2.0).eigenvalues();
    let slow_oscillation = ev.iter().find(|e| e.1.abs() > 0.1).unwrap();
    assert!((slow_oscillation.0 + 0.029).abs() < 0.001, "{ev:?}");
}

/// Runs every case at `n` junctions with `seeds` seeds and checks the regime.
fn agrees(n: usize, seeds: u64, extra: &[&str]) {
    for (k, (v, regime)) in CASES.into_iter().enumerate() {
        for r in 0..seeds {
            let mut s = issue(v, n, extra);
            s.run.seed = match s.run.engine {
                stickslip::scene::EngineKind::Exact => pcg_seed(11, Role::Exact, k as u64, r),
                stickslip::scene::EngineKind::Fixed => 1 + r,
            };
            let d = verdict(&s);
            assert_eq!(d.regime, regime, "N = {n}, V = {v}, seed {}, {extra:?}: {d:?}", s.run.seed);
        }
    }
}

#[test]
fn the_exact_engine_agrees_at_n_1e3() {
    agrees(1000, 3, &[]);
}

#[test]
fn the_exact_engine_agrees_at_n_1e4() {
    agrees(10_000, 1, &[]);
}

#[test]
#[ignore = "slow; the three ignored tests take 90 s: cargo test --release --test suite regime:: -- --ignored"]
fn the_exact_engine_agrees_at_n_1e5() {
    agrees(100_000, 1, &[]);
}

#[test]
fn the_fixed_step_engine_agrees_at_n_1e3() {
    agrees(1000, 1, &["run.engine=fixed", "fixed.dt=0.01"]);
}

#[test]
#[ignore = "slow; the three ignored tests take 90 s: cargo test --release --test suite regime:: -- --ignored"]
fn the_fixed_step_engine_agrees_at_n_1e4() {
    agrees(10_000, 1, &["run.engine=fixed", "fixed.dt=0.01"]);
}

/// What one replica measures: friction mean and standard deviation per junction, and the
/// oscillation's period and amplitude per junction.
fn measure(v: f64, n: usize, replica: u64) -> [f64; 4] {
    let mut s = issue(v, n, &[]);
    s.run.seed = pcg_seed(23, Role::Exact, n as u64, replica);
    let sum = stickslip::run_scene(&s, None).unwrap();
    let nf = n as f64;
    [
        sum.friction_per_junction,
        sum.friction_std / nf,
        sum.oscillation.oscillation_period.unwrap_or(f64::NAN),
        sum.oscillation.oscillation_amplitude / nf,
    ]
}

/// Richardson extrapolation to `N = infinity` of replica means at `n1` and `n2 = 10 n1`,
/// assuming `m(N) = m_inf + b/N`: `m_inf = (10 m2 - m1) / 9`, with its standard error. The
/// interval uses the Student-t quantile at level `common::ALPHA` with the smaller of the two
/// samples' degrees of freedom (conservative).
fn extrapolated(n1: usize, replicas: u64) -> Vec<(f64, f64)> {
    let n2 = 10 * n1;
    let runs = |n: usize| (0..replicas).map(|r| measure(1.0, n, r)).collect::<Vec<_>>();
    let (a, b) = (runs(n1), runs(n2));
    (0..4)
        .map(|q| {
            let x1: Vec<f64> = a.iter().map(|m| m[q]).collect();
            let x2: Vec<f64> = b.iter().map(|m| m[q]).collect();
            // mean_ci gives the mean and t * se; recover se with the same t.
            let (m1, h1) = mean_ci(&x1, common::ALPHA);
            let (m2, h2) = mean_ci(&x2, common::ALPHA);
            ((10.0 * m2 - m1) / 9.0, (100.0 * h2 * h2 + h1 * h1).sqrt() / 9.0)
        })
        .collect()
}

/// The moment equations' friction mean and standard deviation per junction over the window,
/// and the detector's period and amplitude per junction on their trajectory.
fn at_infinity() -> [f64; 4] {
    let s = issue(1.0, 1000, &[]);
    let m = MomentModel::of(&s);
    let (mean, sd) = m.friction_stats(m.initial(&s), 700.0, 1500.0);
    let d = verdict_at_infinity(&s);
    [mean, sd, d.oscillation.oscillation_period.unwrap(), d.oscillation.oscillation_amplitude / 1000.0]
}

fn check_extrapolation(n1: usize, replicas: u64) {
    let names = ["friction mean / N", "friction std / N", "period", "amplitude / N"];
    let exact = at_infinity();
    // The moment equations' 0.2121 and 0.1081 (here to more digits).
    assert!((exact[0] - 0.21204).abs() < 1e-5 && (exact[1] - 0.10809).abs() < 1e-5, "{exact:?}");
    for (q, (m, h)) in extrapolated(n1, replicas).into_iter().enumerate() {
        println!("{}: extrapolated {m:.6} +- {h:.6}, moment equations {:.6}", names[q], exact[q]);
        assert!((m - exact[q]).abs() <= h, "{}: {m} +- {h} against {}", names[q], exact[q]);
    }
}

#[test]
fn the_exact_engine_has_the_moment_equations_friction_and_oscillation() {
    check_extrapolation(1000, 16);
}

#[test]
#[ignore = "slow; the three ignored tests take 90 s: cargo test --release --test suite regime:: -- --ignored"]
fn the_exact_engine_has_the_moment_equations_friction_and_oscillation_at_n_1e5() {
    check_extrapolation(10_000, 8);
}

#[test]
fn the_fig2_scene_agrees_with_its_moment_equations() {
    // scenarios/fig2.toml (N = 300, plate not scaled with N): steady sliding is unstable
    // for 0.530 < V < 3.473; the detector agrees at velocities on both sides and inside
    // (the docs/figures/fig2-sweep velocities, rounded), two seeds each.
    let fig2 = Scene::from_file(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/fig2.toml"),
        &["output.trace=false".to_string(), "output.plot=false".to_string()],
    )
    .unwrap();
    let m = MomentModel::of(&fig2);
    let b = m.stability_boundaries(0.05, 20.0, 400);
    assert!(b.len() == 2 && (b[0] - 0.5301).abs() < 1e-3 && (b[1] - 3.4730).abs() < 1e-3, "{b:?}");
    for v in [0.2, 0.32, 0.79, 1.26, 2.0, 3.17, 5.0, 8.0] {
        let expected = if b[0] < v && v < b[1] { Regime::StickSlip } else { Regime::Smooth };
        for seed in [1, 2] {
            let mut s = fig2.with_overrides(&[format!("plate.v={v}")]).unwrap();
            s.run.seed = seed;
            let d = verdict(&s);
            assert_eq!(d.regime, expected, "V = {v}, seed {seed}: {d:?}");
        }
    }
}

#[test]
fn the_fig2_stability_table_of_the_results() {
    // docs/results.md ("The roles of K, M = eta, lambda and the kinetic rates"): the range of
    // V where fig2's steady sliding is unstable, with one parameter changed. Printed by
    // `cargo test --release --test suite regime::the_fig2_stability_table -- --nocapture`.
    let fig2 =
        Scene::from_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/fig2.toml"), &[]).unwrap();
    type Row<'a> = (&'a [&'a str], Option<(f64, f64)>);
    let table: [Row; 17] = [
        (&[], Some((0.530, 3.473))),
        (&["plate.k=1.5"], Some((0.528, 3.928))),
        (&["plate.k=5"], Some((0.529, 3.792))),
        (&["plate.k=50"], Some((0.536, 2.782))),
        (&["plate.k=150"], Some((0.556, 1.930))),
        (&["plate.k=500"], Some((0.705, 0.942))),
        (&["plate.k=1500"], None),
        (&["plate.mass=5", "plate.eta=5"], Some((0.511, 5.844))),
        (&["plate.mass=8.33", "plate.eta=8.33"], Some((0.514, 5.223))),
        (&["plate.mass=75", "plate.eta=75"], Some((0.598, 1.784))),
        (&["plate.mass=150", "plate.eta=150"], None),
        (&["junctions.lambda=0.01"], Some((0.509, 6.715))),
        (&["junctions.lambda=0.1"], Some((0.671, 1.309))),
        (&["junctions.lambda=0.3"], None),
        (&["junctions.lambda=1"], None),
        (&["junctions.k0=0.3", "junctions.kon0=0.3"], Some((0.565, 2.122))),
        (&["junctions.k0=3", "junctions.kon0=3"], Some((0.524, 3.988))),
    ];
    for (set, range) in table {
        let o: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        let b = MomentModel::of(&fig2.with_overrides(&o).unwrap()).stability_boundaries(0.05, 20.0, 400);
        println!("{set:?}: unstable for {b:?}");
        match range {
            Some((lo, hi)) => {
                assert!(b.len() == 2 && (b[0] - lo).abs() < 5e-4 && (b[1] - hi).abs() < 5e-4, "{set:?}: {b:?}")
            }
            None => assert!(b.is_empty(), "{set:?}: {b:?}"),
        }
    }
}

#[test]
fn the_bundled_limit_cycle_scene_is_the_scene_of_these_tests() {
    let file =
        Scene::from_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/limit-cycle.toml"), &[])
            .unwrap();
    let mut here = issue(1.0, 10_000, &["output.trace=true", "output.plot=true", "fixed.dt=0.01", "fixed.rng=pcg"]);
    here.name = file.name.clone();
    assert_eq!(MomentModel::of(&file), MomentModel::of(&here));
    assert_eq!(file, here);
}

#[test]
fn beyond_its_upper_instability_fig2_keeps_a_limit_cycle_beside_steady_sliding() {
    // docs/results.md, regime map: at K = 32.3 steady sliding is stable again from V = 3.074,
    // but the cycle of V = 3 continued to V = 3.27 persists (a subcritical Hopf point:
    // bistability), while the start from the scene's initial state settles to steady sliding.
    let fig2 = Scene::from_file(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/fig2.toml"),
        &["plate.k=32.3165".to_string()],
    )
    .unwrap();
    let m = MomentModel::of(&fig2);
    let b = m.stability_boundaries(0.05, 20.0, 400);
    assert!((b[1] - 3.074).abs() < 1e-3, "{b:?}");
    let on_cycle = m.with_v(3.0).integrate(m.initial(&fig2), 1500.0, 1.0, |_, _| {});
    let beyond = m.with_v(3.27165);
    assert!(beyond.stable());
    let (period, half) = beyond.limit_cycle(on_cycle, 1500.0).expect("the cycle persists");
    assert!((period - 7.72).abs() < 0.01 && half > 0.5, "{period} {half}");
    assert!(beyond.limit_cycle(beyond.initial(&fig2), 1500.0).is_none());
}

#[test]
fn fig2_cycles_slow_down_with_a_softer_spring() {
    // docs/results.md, regime map: at V = 0.81 the moment equations' cycle has a period of
    // 18 time units at K = 7, 73 at K = 3.2 and 182 at K = 1.5 (11.5 at fig2's K = 15).
    let fig2 =
        Scene::from_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/fig2.toml"), &[]).unwrap();
    for (k, expected) in [(1.5, 182.1), (3.23165, 72.6), (6.96238, 18.26), (15.0, 11.52)] {
        let s = fig2.with_overrides(&[format!("plate.k={k}"), "plate.v=0.808733".into()]).unwrap();
        let m = MomentModel::of(&s);
        let (period, _) = m.limit_cycle(m.initial(&s), 1500.0).expect("a limit cycle");
        assert!((period - expected).abs() < 0.01 * expected, "K = {k}: period {period}");
    }
}
