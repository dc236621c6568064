//! Extreme cases (the table is docs/stability.md): stiff and free plates,
//! exactly critical and zero damping, no drive and a drive 1000 V0, one and very many
//! junctions, rates from 1e-12 to 1e9, every junction attached throughout, lambda = 0 and
//! 1e9, weak bonds whose rate overflows, a run to t = 1e12 and a run shifted by 1e12 in time
//! and position.
//!
//! Every case checks: no NaN or infinity in samples, segments, events or statistics; the
//! invariants (friction = K (V t - X), attached count in [0, N] and consistent with the event
//! log, segments tiling time); and the limiting answer known for the case, with an exact
//! identity or a tolerance from statistics (`common::ALPHA`).
//!
//! Strong bonds with the plate slower than `V0` (`g = 1`) have a junction process that does
//! not depend on the plate at all (rupture rate `k0`, formation rate `kon0`, the random
//! stream used the same way): two runs with the same seed and different plate parameters
//! have the same event times and junctions. Several cases use that to compare plates exactly.

use crate::common;

use common::*;
use stickslip::Scene;
use stickslip::engine::{Counters, Engine, EngineError, EngineVisitor, with_engine};
use stickslip::observe::stats::WindowStats;
use stickslip::observe::{EventKind, Recorder, Sample};
use stickslip::runner::{OutputGrid, Recording, drive};
use stickslip_testkit::{BONDS, FIG1, LAWS, law_bond_pairs, scene};

/// `V0 = alpha / tau0` of the Fig. 1 parameters.
const V0: f64 = 0.5;

struct Run {
    rec: Recorder,
    stats: WindowStats,
    counters: Counters,
}

fn try_run(s: &Scene) -> Result<Run, EngineError> {
    let r = stickslip::runner::record(s);
    if let Some(e) = r.error {
        return Err(e);
    }
    let Recording { samples, segments, events, core: (stats, _), counters, .. } = r;
    Ok(Run { rec: Recorder { events, segments, samples }, stats, counters })
}

fn run(s: &Scene) -> Run {
    let r = try_run(s).unwrap_or_else(|e| panic!("run failed: {e}"));
    check(s, &r);
    r
}

/// An exact-engine scene on the Fig. 1 parameters with `law`, `bond` and `extra` overrides.
fn exact(law: &str, bond: &str, extra: &[&str]) -> Scene {
    let mut o = vec![
        "run.engine=exact".to_string(),
        format!("junctions.force_law={law}"),
        format!("junctions.bond={bond}"),
        "output.sample_dt=0.5".to_string(),
    ];
    o.extend(extra.iter().map(|s| s.to_string()));
    let o: Vec<&str> = o.iter().map(String::as_str).collect();
    scene(FIG1, &o)
}

fn finite_sample(s: &Sample) -> bool {
    [s.t, s.x, s.v, s.friction, s.bond_force].iter().all(|v| v.is_finite())
}

/// No NaN or infinity anywhere, and the invariants of every run.
fn check(s: &Scene, r: &Run) {
    let n = s.junctions.n as u64;
    let (k, v) = (s.plate.k, s.plate.v);
    assert!(!r.rec.samples.is_empty());
    for smp in &r.rec.samples {
        assert!(finite_sample(smp), "non-finite sample {smp:?}");
        assert!(smp.attached <= n);
        let f = k * (v * smp.t - smp.x);
        assert!(
            (smp.friction - f).abs() <= 1e-9 * k * (smp.x.abs() + v * smp.t + 1.0),
            "friction {} vs K (V t - X) = {f}",
            smp.friction
        );
    }
    let mut t = r.rec.segments.first().map_or(0.0, |g| g.t0);
    for g in &r.rec.segments {
        assert!(
            [g.t0, g.t1, g.friction, g.friction_m2, g.bond_force, g.viscous].iter().all(|x| x.is_finite()),
            "{g:?}"
        );
        assert!((g.t0 - t).abs() <= 1e-12 * (1.0 + t.abs()), "segments tile time: {} after {t}", g.t0);
        assert!(g.t1 >= g.t0 && g.friction_m2 >= 0.0 && g.attached <= n);
        t = g.t1;
    }
    assert!((t - r.rec.samples.last().unwrap().t).abs() <= 1e-9 * (1.0 + t.abs()));
    // Replay the event log from the first sample's count.
    let mut count = r.rec.samples[0].attached as i64;
    let mut last = f64::NEG_INFINITY;
    for e in &r.rec.events {
        assert!(e.t >= last && e.t.is_finite(), "event times never decrease: {} after {last}", e.t);
        last = e.t;
        assert!(e.extension.is_finite() && e.tension.is_finite() && e.tension >= 0.0, "{e:?}");
        count += if e.kind == EventKind::Formation { 1 } else { -1 };
        assert!((0..=n as i64).contains(&count));
    }
    assert_eq!(count, r.rec.samples.last().unwrap().attached as i64, "the event log replays to the last sample");
    assert_eq!(r.rec.events.len() as u64, r.counters.ruptures + r.counters.formations);
    let st = &r.stats;
    for x in
        [st.friction_mean(), st.friction_std(), st.bond_force_mean(), st.viscous_mean(), st.attached_fraction_mean()]
    {
        assert!(x.is_finite(), "non-finite statistic {x}");
    }
}

/// Largest `|a - b|` of plate positions over two runs sampled on the same grid.
fn max_dx(a: &Run, b: &Run) -> f64 {
    assert_eq!(a.rec.samples.len(), b.rec.samples.len());
    a.rec.samples.iter().zip(&b.rec.samples).map(|(p, q)| (p.x - q.x).abs()).fold(0.0, f64::max)
}

fn sup(r: &Run, f: impl Fn(&Sample) -> f64) -> f64 {
    r.rec.samples.iter().map(|s| f(s).abs()).fold(0.0, f64::max)
}

/// Same junction events (times to round-off, junctions, kinds).
fn same_events(a: &Run, b: &Run) {
    assert_eq!(a.rec.events.len(), b.rec.events.len(), "same number of events");
    for (p, q) in a.rec.events.iter().zip(&b.rec.events) {
        assert!(p.junction == q.junction && p.kind == q.kind && (p.t - q.t).abs() <= 1e-9 * (1.0 + p.t), "{p:?} {q:?}");
    }
}

/// Time averages of `f` over `seeds` replicas: (mean, CI half-width at ALPHA).
fn replicas(seeds: u64, make: impl Fn(u64) -> Scene, f: impl Fn(&Scene, &Run) -> f64) -> (f64, f64) {
    let x: Vec<f64> = (1..=seeds)
        .map(|seed| {
            let s = make(seed);
            f(&s, &run(&s))
        })
        .collect();
    mean_ci(&x, ALPHA)
}

/// `n* = kon / (kon + k0)`.
fn n_star(kon: f64, k0: f64) -> f64 {
    kon / (kon + k0)
}

// ---------------------------------------------------------------------------------------
// Plates

/// `M/eta` from 1 down to 1e-12: the trajectory tends to the overdamped one (`M = 0`). With
/// `tau_m = M/eta`, `tau_m Xdd + Xd = G/eta`, so `X_M = X_0 - tau_m Xd_0 + O(tau_m^2)` away
/// from events, and a velocity jump `dv` of the overdamped plate is followed within
/// `tau_m |dv| <= 2 tau_m sup|Xd|`: `sup |X_M - X_0| <= 2 tau_m sup|Xd_0|` plus round-off
/// (linear law) or the integrator's tolerance (tilted law).
#[test]
fn stiff_plates_tend_to_the_overdamped_limit() {
    for (law, ratios, slack) in [("linear", &[1e-3, 1e-6, 1e-9, 1e-12][..], 1e-12), ("tilted", &[1e-2, 1e-3][..], 1e-8)]
    {
        let base = ["junctions.n=100", "plate.v=0.2", "run.t_end=100", "plate.eta=75"];
        let with = |m: &str| exact(law, "strong", &[&base[..], &[m]].concat());
        let s0 = with("plate.mass=0");
        let r0 = run(&s0);
        let vmax = sup(&r0, |s| s.v);
        assert!(vmax <= V0, "precondition g = 1: the plate stays below V0 ({vmax})");
        let xmax = sup(&r0, |s| s.x);
        for &ratio in ratios {
            let s = with(&format!("plate.mass={}", 75.0 * ratio));
            let r = run(&s);
            same_events(&r0, &r);
            let d = max_dx(&r0, &r);
            let bound = 2.0 * ratio * vmax + slack * (1.0 + xmax);
            assert!(d <= bound, "{law} M/eta = {ratio}: sup |X_M - X_0| = {d:e} > {bound:e}");
        }
        // M/eta = 1 (the letter's plate) runs through the same checks.
        run(&with("plate.mass=75"));
    }
}

/// Driving spring `K = 1e9`: the plate moves at exactly `V`, where an exact fact holds
/// (docs/model.md, "Exact facts used as checks", item 5): mean bond force per junction
/// `kappa n* (V/k0)(1 + kon/lambda)` (strong bonds, linear law, residual re-attachment;
/// `kon = kon0` below `V0`). Replicas over seeds give a Student-t interval.
#[test]
fn stiff_driving_spring_gives_the_constant_velocity_bond_force() {
    let (kappa, k0, kon0, lambda, v) = (0.1, 0.1, 0.1, 0.1, 0.2);
    let expected = kappa * n_star(kon0, k0) * (v / k0) * (1.0 + kon0 / lambda);
    let (m, hw) = replicas(
        12,
        |seed| {
            exact(
                "linear",
                "strong",
                &[
                    "plate.k=1e9",
                    "plate.v=0.2",
                    "junctions.initial=stationary",
                    "run.t_end=1100",
                    "run.t_warmup=100",
                    "output.sample_dt=1",
                    &format!("run.seed={seed}"),
                ],
            )
        },
        |s, r| r.stats.bond_force_mean() / s.junctions.n as f64,
    );
    assert!((m - expected).abs() <= hw, "bond force per junction {m} +- {hw}, expected {expected}");
}

/// Bond stiffness far above `K` (`kappa N = 3e4 K`): junctions pin the plate; the window
/// force balance `<F> = <F_b> + <eta Xd> + M dXd/T` holds exactly, and the plate keeps up
/// with the drive on average: `<Xd> = (X(t1) - X(t0))/T`, an identity checked on the
/// viscous mean.
#[test]
fn bond_stiffness_far_above_k_keeps_the_force_balance() {
    for law in LAWS.iter().map(|l| l.name()) {
        let s = exact(law, "strong", &["junctions.kappa=15000", "junctions.n=300", "run.t_end=100", "run.t_warmup=10"]);
        let r = run(&s);
        balance(&s, &r);
    }
}

/// `<F> = <F_b> + <eta Xd> + M (Xd(t1) - Xd(t0)) / T` and `<eta Xd> = eta (X(t1) - X(t0)) / T`.
fn balance(s: &Scene, r: &Run) {
    let t0 = s.run.t_warmup;
    let at = |t: f64| *r.rec.samples.iter().find(|p| (p.t - t).abs() <= 1e-9 * (1.0 + t)).expect("sample at t");
    let (a, b) = (at(t0), at(s.run.t_end));
    let tt = s.run.t_end - t0;
    let st = &r.stats;
    let scale = st.friction_mean().abs() + st.bond_force_mean().abs() + st.viscous_mean().abs() + 1.0;
    let resid = st.friction_mean() - st.bond_force_mean() - st.viscous_mean() - s.plate.mass * (b.v - a.v) / tt;
    assert!(resid.abs() <= 1e-7 * scale, "force balance residual {resid}");
    let visc = s.plate.eta * (b.x - a.x) / tt;
    assert!((st.viscous_mean() - visc).abs() <= 1e-7 * (visc.abs() + 1.0), "{} vs {visc}", st.viscous_mean());
}

/// Exactly critical damping `eta^2 = 4 K M` with `kappa = 0`: the closed form
/// `X = V t - eta V/K + (A + B t) e^(-w t)`, `A = eta V/K`, `B = w A - V`, `w = sqrt(K/M)`.
/// With junctions (`kappa > 0`, critical only while none is attached) the run lies between
/// its neighbours `eta (1 +- 1e-6)` (continuity across the branch of the closed form).
#[test]
fn critical_damping_matches_its_closed_form_and_its_neighbours() {
    let (m, k, v) = (75.0f64, 150.0f64, 0.2);
    let eta = 2.0 * (k * m).sqrt();
    let s =
        exact("linear", "strong", &["junctions.kappa=0", "plate.v=0.2", &format!("plate.eta={eta}"), "run.t_end=50"]);
    let r = run(&s);
    let w = (k / m).sqrt();
    let a = eta * v / k;
    let b = w * a - v;
    for p in &r.rec.samples {
        let x = v * p.t - a + (a + b * p.t) * (-w * p.t).exp();
        assert!((p.x - x).abs() <= 1e-12 * (1.0 + x.abs()), "t = {}: X = {} vs {x}", p.t, p.x);
    }
    let with = |e: f64| exact("linear", "strong", &["plate.v=0.2", &format!("plate.eta={e}"), "run.t_end=100"]);
    let (rc, rp, rm) = (run(&with(eta)), run(&with(eta * (1.0 + 1e-6))), run(&with(eta * (1.0 - 1e-6))));
    same_events(&rc, &rp);
    same_events(&rc, &rm);
    let xmax = sup(&rc, |p| p.x);
    for ((c, p), q) in rc.rec.samples.iter().zip(&rp.rec.samples).zip(&rm.rec.samples) {
        let mid = 0.5 * (p.x + q.x);
        assert!((c.x - mid).abs() <= (p.x - q.x).abs() + 1e-12 * (1.0 + xmax), "t = {}: {} vs {mid}", c.t, c.x);
    }
}

/// `eta = 0`: no viscous force at all, the force balance without it, and (`kappa = 0`)
/// the undamped closed form `X = V t - (V/w) sin(w t)`. With junctions, continuity in `eta`:
/// the run with `eta = d = 1e-9` differs by at most `d T^2 sup|Xd| / M` (the perturbation
/// `-d Xd` integrated twice, no restoring force assumed) plus round-off.
#[test]
fn undamped_plate() {
    let (m, k, v) = (75.0f64, 150.0f64, 0.2);
    let s = exact("linear", "strong", &["junctions.kappa=0", "plate.v=0.2", "plate.eta=0", "run.t_end=50"]);
    let r = run(&s);
    let w = (k / m).sqrt();
    for p in &r.rec.samples {
        let x = v * p.t - (v / w) * (w * p.t).sin();
        assert!((p.x - x).abs() <= 1e-12 * (1.0 + x.abs()), "t = {}: X = {} vs {x}", p.t, p.x);
    }
    for law in LAWS.iter().map(|l| l.name()) {
        let s = exact(law, "strong", &["plate.v=0.2", "plate.eta=0", "run.t_end=100", "run.t_warmup=20"]);
        let r = run(&s);
        assert_eq!(r.stats.viscous_mean(), 0.0);
        balance(&s, &r);
        if law == "linear" {
            let d = 1e-9;
            let r2 = run(&exact(
                law,
                "strong",
                &["plate.v=0.2", &format!("plate.eta={d}"), "run.t_end=100", "run.t_warmup=20"],
            ));
            let bound = d * 100.0 * 100.0 * sup(&r, |p| p.v) / m + 1e-12 * (1.0 + sup(&r, |p| p.x));
            let dx = max_dx(&r, &r2);
            assert!(dx <= bound, "eta 0 vs 1e-9: {dx:e} > {bound:e}");
        }
    }
}

/// `K = 0` and `V = 0`: nothing pulls the plate, every extension stays 0: `X`, `F` and `F_b`
/// are exactly 0 at every sample, for both laws and bond kinds (weak bonds then rupture at
/// `k0`). The attached fraction is the two-state chain's `n* = kon0/(kon0 + k0)`: replicas
/// of the time average (stationary start) give a Student-t interval.
#[test]
fn no_drive_leaves_the_plate_at_rest_and_the_junctions_at_equilibrium() {
    for law in LAWS.iter().map(|l| l.name()) {
        for bond in BONDS.iter().map(|b| b.name()) {
            for what in ["plate.k=0", "plate.v=0"] {
                let (m, hw) = replicas(
                    8,
                    |seed| {
                        exact(
                            law,
                            bond,
                            &[
                                what,
                                "junctions.n=100",
                                "junctions.initial=stationary",
                                "run.t_end=500",
                                "output.sample_dt=5",
                                &format!("run.seed={seed}"),
                            ],
                        )
                    },
                    |_, r| {
                        // Linear law: exactly at rest. Tilted law (series engine): the bond
                        // force is the series' sum of zero extensions, exact up to its stated
                        // error bound `exact.rtol kappa l0 N` (1e-9 here); a force that small
                        // moves the plate by at most `F t / eta` (`F / K` with the spring),
                        // and the lag coordinates round `X = u + V t` by a few ulps of `V t`.
                        let f_tol = if law == "tilted" { 1e-10 * 0.1 * 1.0 * 100.0 } else { 0.0 };
                        for p in &r.rec.samples {
                            let x_tol = f_tol * p.t / 75.0 + 4.0 * f64::EPSILON * 0.5 * p.t;
                            let x_tol = if law == "tilted" { x_tol } else { 0.0 };
                            assert!(p.bond_force.abs() <= f_tol, "{law} {bond} {what}: {p:?}");
                            assert!(p.x.abs() <= x_tol, "{law} {bond} {what}: {p:?}");
                            assert!(p.friction.abs() <= 150.0 * x_tol, "{law} {bond} {what}: {p:?}");
                        }
                        r.stats.attached_fraction_mean()
                    },
                );
                assert!((m - 0.5).abs() <= hw, "{law} {bond} {what}: attached fraction {m} +- {hw}, expected 0.5");
            }
        }
    }
}

/// `V = 1000 V0`: formation fades to `g = sin(pi V0 / (2 V))`; with `K = 1e9` the plate
/// moves at exactly `V`, so the attached fraction is `n* = kon0 g / (kon0 g + k0)`.
#[test]
fn fast_drive_fades_formation() {
    let v = 1000.0 * V0;
    let g = (std::f64::consts::FRAC_PI_2 * V0 / v).sin();
    let expected = n_star(0.1 * g, 0.1);
    let (m, hw) = replicas(
        10,
        |seed| {
            exact(
                "linear",
                "strong",
                &[
                    "plate.k=1e9",
                    &format!("plate.v={v}"),
                    "junctions.n=1000",
                    "run.t_end=10000",
                    "run.t_warmup=100",
                    "output.sample_dt=10",
                    &format!("run.seed={seed}"),
                ],
            )
        },
        |_, r| r.stats.attached_fraction_mean(),
    );
    assert!((m - expected).abs() <= hw, "attached fraction {m} +- {hw}, expected {expected}");
    // The tilted law at the letter's plate: runs, and the force balance holds.
    let s = exact("tilted", "strong", &[&format!("plate.v={v}"), "run.t_end=100", "run.t_warmup=10"]);
    balance(&s, &run(&s));
}

/// `N = 1`: one junction is a two-state Markov chain, attached a fraction `n* = 1/2` of the
/// time (strong bonds, `g = 1`).
#[test]
fn single_junction_is_a_two_state_chain() {
    for law in LAWS.iter().map(|l| l.name()) {
        let (m, hw) = replicas(
            12,
            |seed| {
                exact(
                    law,
                    "strong",
                    &[
                        "junctions.n=1",
                        "plate.v=0.2",
                        "junctions.initial=stationary",
                        "run.t_end=1000",
                        "output.sample_dt=10",
                        &format!("run.seed={seed}"),
                    ],
                )
            },
            |_, r| {
                assert!(sup(r, |p| p.v) <= V0);
                r.stats.attached_fraction_mean()
            },
        );
        assert!((m - 0.5).abs() <= hw, "{law}: attached fraction {m} +- {hw}");
    }
}

/// Many junctions (scaled Fig. 1 physics, strong bonds, stationary start, `V < V0`): at any
/// time the attached count is Binomial(N, 1/2), so `|count - N/2| <= z sqrt(N/4)`.
fn many_junctions(n: usize) {
    let s = stickslip_testkit::scaled_linear(n, "strong")
        .with_overrides(&["plate.v=0.2".into(), "run.t_end=1".into(), "output.sample_dt=0.5".into()])
        .unwrap();
    let r = try_run(&s).unwrap();
    let z = chi2_critical(1, ALPHA).sqrt();
    for p in &r.rec.samples {
        assert!(finite_sample(p));
        let d = (p.attached as f64 - 0.5 * n as f64).abs();
        assert!(d <= z * (0.25 * n as f64).sqrt(), "t = {}: {} attached of {n}", p.t, p.attached);
    }
}

#[test]
fn many_junctions_ci_size() {
    many_junctions(100_000);
}

/// Full size: `cargo test --release --test suite extreme:: -- --ignored` (docs/stability.md).
#[test]
#[ignore]
fn many_junctions_full_size() {
    many_junctions(10_000_000);
}

// ---------------------------------------------------------------------------------------
// Rates

/// Rates from 1e-12 to 1e9. With an expected count `mu` of some event, Markov's inequality
/// bounds the chance of seeing one by `mu`; every bound below has `mu < 1e-4`.
#[test]
fn rates_from_1e_minus_12_to_1e9() {
    for law in LAWS.iter().map(|l| l.name()) {
        let base = ["plate.v=0.2", "run.t_end=400", "run.t_warmup=200"];
        // k0 = 1e-12: expected ruptures N k0 T = 1.2e-7; every junction forms (P(one has not
        // by t = 200) = N e^-20 = 6e-7): all attached from then on.
        let r = run(&exact(law, "strong", &[&base[..], &["junctions.k0=1e-12"]].concat()));
        assert_eq!(r.counters.ruptures, 0);
        assert!(r.stats.attached_fraction_mean() >= 1.0 - 1e-12, "{}", r.stats.attached_fraction_mean());
        // kon0 = 1e-12 from all detached: expected formations 1.2e-7.
        let r = run(&exact(law, "strong", &[&base[..], &["junctions.kon0=1e-12"]].concat()));
        assert_eq!(r.counters.formations, 0);
        assert_eq!(r.stats.attached_fraction_mean(), 0.0);
        // k0 = 1e9: attached fraction n* = 1e-10; P(window mean > 1e-6) <= 1e-4.
        let s = exact(law, "strong", &[&base[..], &["junctions.k0=1e9"]].concat());
        let r = run(&s);
        assert!(r.stats.attached_fraction_mean() <= 1e-6, "{}", r.stats.attached_fraction_mean());
        balance(&s, &r);
        // kon0 = 1e9: detached fraction 1e-10 after a start-up of ~1e-9.
        let s = exact(law, "strong", &[&base[..], &["junctions.kon0=1e9", "run.t_end=250"]].concat());
        let r = run(&s);
        assert!(1.0 - r.stats.attached_fraction_mean() <= 1e-6, "{}", r.stats.attached_fraction_mean());
        balance(&s, &r);
    }
}

/// Every junction attached throughout (`initial = attached`, `k0 = 0`: no rupture): the
/// attached fraction's average is exactly 1, in the fixed engine (the letter's scene at a
/// stable step) and in the exact engine with either law, through the runner (the linear law
/// summing its pieces in stretches) and through the recorder (piece by piece), on grids whose
/// pieces' lengths round differently.
#[test]
fn every_junction_attached_throughout_gives_a_fraction_of_exactly_one() {
    let grid = ["output.sample_dt=0.3", "run.t_warmup=3.3"];
    let cases: [&[&str]; 6] = [
        &["fixed.dt=0.1"],
        &["fixed.dt=0.1", "plate.kinematic=true", "junctions.bond=weak"],
        &["run.engine=exact", grid[0], grid[1]],
        &["run.engine=exact", "junctions.force_law=linear", grid[0], grid[1]],
        &["run.engine=exact", "junctions.force_law=linear", "output.sample_dt=0.7", grid[1], "junctions.n=7"],
        &["run.engine=exact", "junctions.force_law=linear", "plate.kinematic=true", grid[0], grid[1]],
    ];
    for extra in cases {
        let s = scene(FIG1, &[&["junctions.initial=attached", "junctions.k0=0"][..], extra].concat());
        let summary = stickslip::run_scene(&s, None).unwrap_or_else(|e| panic!("{extra:?}: {e}"));
        assert_eq!(summary.attached_fraction_mean, 1.0, "{extra:?}");
        // Not `run`: its check reads the friction as `K (V t - X)`, not a kinematic plate's.
        let r = try_run(&s).unwrap_or_else(|e| panic!("{extra:?}: {e}"));
        assert_eq!(r.counters.ruptures, 0, "{extra:?}");
        assert_eq!(r.stats.attached_fraction_mean(), 1.0, "{extra:?}");
    }
}

/// `lambda = 0`: a detached junction keeps its extension, so every formation (residual
/// re-attachment) has the extension of the same junction's last rupture. `lambda = 1e9`:
/// the residual extension is `x e^(-1e9 dt)`, zero for any gap above 1e-6: the run equals
/// the `reattach = "unstretched"` run with the same seed.
#[test]
fn relaxation_rates_zero_and_1e9() {
    for law in LAWS.iter().map(|l| l.name()) {
        let base = ["plate.v=0.2", "run.t_end=100", "junctions.n=100"];
        let r = run(&exact(law, "strong", &[&base[..], &["junctions.lambda=0"]].concat()));
        let mut last = vec![None; 100];
        let mut checked = 0;
        for e in &r.rec.events {
            let j = e.junction as usize;
            match e.kind {
                EventKind::Rupture => last[j] = Some(e.extension),
                EventKind::Formation => {
                    if let Some(x) = last[j] {
                        assert!((e.extension - x).abs() <= 1e-9 * (1.0 + x.abs()), "{law}: {e:?} after {x}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 100, "{checked}");
        let fast = run(&exact(law, "strong", &[&base[..], &["junctions.lambda=1e9"]].concat()));
        let fresh = run(&exact(
            law,
            "strong",
            &[&base[..], &["junctions.lambda=1e9", "junctions.reattach=unstretched"]].concat(),
        ));
        same_events(&fast, &fresh);
        let d = max_dx(&fast, &fresh);
        assert!(d <= 1e-12 * (1.0 + sup(&fast, |p| p.x)), "{law}: {d:e}");
    }
}

/// Weak bonds whose rate `k0 exp(beta f dx)` overflows at any tension (`dx = 1e300`,
/// `temperature = 1e-300`, `kappa = 1e300`, and `a = beta dx kappa = inf`): every
/// junction ruptures as soon as it is stretched (docs/model.md, "Equations", item 6), so no
/// bond force is carried and the friction is the viscous `eta V` of a free plate. Formation
/// is unaffected (30 per time unit), so the engine must stay fast and finite.
#[test]
fn overflowing_weak_bonds_rupture_at_once() {
    let cases: &[(&str, &[&str])] = &[
        ("linear", &["junctions.dx=1e300"]),
        ("tilted", &["junctions.dx=1e300"]),
        ("linear", &["junctions.temperature=1e-300"]),
        ("linear", &["junctions.kappa=1e300"]),
        ("linear", &["junctions.kappa=1e300", "junctions.dx=1e300"]),
    ];
    for (law, extra) in cases {
        let s = exact(law, "weak", &[&["run.t_end=200", "run.t_warmup=100"][..], extra].concat());
        let r = run(&s);
        let st = &r.stats;
        let eta_v = s.plate.eta * s.plate.v;
        assert!(r.counters.formations > 3000, "{law} {extra:?}: {}", r.counters.formations);
        assert!(st.attached_fraction_mean() <= 1e-6, "{law} {extra:?}: {}", st.attached_fraction_mean());
        assert!((st.friction_mean() - eta_v).abs() <= 1e-6 * eta_v, "{law} {extra:?}: {}", st.friction_mean());
    }
}

/// Tilted weak bonds far below the reference temperature (`temperature = 0.001` on the
/// Fig. 2 scene, `a l0 = beta dx kappa l0 = 100`): the thinning envelope `exp(a |x|)`
/// exceeds the rate `exp(a (sqrt(x^2 + l0^2) - l0))` by up to `e^100`, so nearly every
/// candidate is rejected. The run stops with `ThinningStalled` once its candidates pass the
/// stall limit, instead of running without end; a temperature the envelope fits finishes
/// with about one candidate per event.
#[test]
fn a_stalled_thinning_is_reported() {
    let fig2 = include_str!("../../scenarios/fig2.toml");
    let at = |t: &str, end: &str| {
        scene(
            fig2,
            &[
                "junctions.bond=weak",
                "junctions.force_law=tilted",
                t,
                "run.t_warmup=0",
                end,
                "output.trace=false",
                "output.plot=false",
            ],
        )
    };
    match try_run(&at("junctions.temperature=0.001", "run.t_end=1.5")) {
        Err(EngineError::ThinningStalled { candidates, events, .. }) => {
            assert!(stickslip::engine::exact::rupture::stalled(candidates, events), "{candidates} for {events}");
        }
        Err(e) => panic!("another error: {e}"),
        Ok(r) => panic!("finished: {:?}", r.counters),
    }
    let r = run(&at("junctions.temperature=1", "run.t_end=50"));
    let (cands, events) = (r.counters.candidates.unwrap(), r.counters.events.unwrap());
    assert!(events > 1000 && cands < 2 * events, "{cands} candidates for {events} events");
}

// ---------------------------------------------------------------------------------------
// Long runs

/// `t_end = 1e12` with rare events (`k0 = kon0 = 1e-10`, about 1000 events): time and
/// positions re-base, every sample is finite and consistent, and the attached fraction is
/// the two-state chain's: the time average of `N` independent chains with rates `a = b`
/// has variance `2 a b / ((a + b)^3 T N)` (asymptotic, `T (a + b) = 200`), so the tolerance
/// is `z` standard deviations. `kappa = 0` keeps `g = 1` (no stuck plate that jumps).
#[test]
fn very_long_run_with_rare_events() {
    let (rate, t, n) = (1e-10f64, 1e12f64, 10.0f64);
    let s = exact(
        "linear",
        "strong",
        &[
            "junctions.k0=1e-10",
            "junctions.kon0=1e-10",
            "junctions.kappa=0",
            "junctions.n=10",
            "junctions.initial=stationary",
            "plate.v=0.2",
            "run.t_end=1e12",
            "output.sample_dt=1e9",
        ],
    );
    let r = run(&s);
    assert!(r.counters.rebases.unwrap() > 0);
    let sd = (2.0 * rate * rate / ((2.0 * rate).powi(3) * t * n)).sqrt();
    let z = chi2_critical(1, ALPHA).sqrt();
    let m = r.stats.attached_fraction_mean();
    assert!((m - 0.5).abs() <= z * sd, "attached fraction {m}, sd {sd}");
    // With junction forces (kappa = 0.1): stuck-and-released plate, still finite and balanced.
    let s = exact(
        "linear",
        "strong",
        &["junctions.k0=1e-10", "junctions.kon0=1e-10", "junctions.n=10", "run.t_end=1e12", "output.sample_dt=1e9"],
    );
    let r = run(&s);
    balance(&s, &r);
}

/// A run whose time origin is shifted by `T0 = 1e12` and its position by the driver's `V T0`
/// (engine state moved by its serialised frame: `epoch += T0`, `x_ref += V T0`, lag
/// `X - V t` unchanged, so the physics is the same) gives the same
/// events, samples and statistics as the unshifted run. Statistics are integrals weighted
/// by segment lengths computed from absolute times, each rounded to `ulp(T0)`: the means
/// may differ by at most `n_seg ulp(T0) max|f - <f>| / T`.
#[test]
fn shifted_coordinates_give_the_same_statistics() {
    const T0: f64 = 1e12;
    /// Both runs continue one engine state after `t = 2`, passed through JSON text. JSON
    /// cannot hold the infinite next time of a channel clock with rate 0, nor a strong-bond
    /// series' infinite `max_spread` (serde_json writes `null`): both texts carry `1e308`
    /// instead, so both runs see the same state.
    struct Shifted<'a>(&'a Scene, f64);
    impl EngineVisitor for Shifted<'_> {
        type Output = (Run, Run);
        fn visit<E: Engine>(self, mut e: E) -> (Run, Run) {
            let (s, t0) = (self.0, self.1);
            e.advance(2.0, &mut stickslip::observe::Nothing).unwrap();
            // The generator's u128 state has no serde_json::Value: edit the text. Frame is
            // the only object serialised under the key "frame", and it is flat.
            let mut text = serde_json::to_string(&e).expect("engine serialises");
            // Infinite times (a clock with rate 0) are `null` in JSON, as fields `"next":null`
            // and as array elements; an absent index (`Option<usize>`) is also `null` and kept.
            text = text
                .replace("\"next\":null", "\"next\":1e308")
                .replace("\"max_spread\":null", "\"max_spread\":1e308")
                .replace("[null", "[1e308")
                .replace(",null", ",1e308");
            let start = text.find("\"frame\":{").expect("a frame") + "\"frame\":".len();
            let end = start + text[start..].find('}').expect("end of frame") + 1;
            let mut f: std::collections::BTreeMap<String, f64> = serde_json::from_str(&text[start..end]).unwrap();
            *f.get_mut("epoch").unwrap() += t0;
            *f.get_mut("x_ref").unwrap() += s.plate.v * t0;
            let shifted = format!("{}{}{}", &text[..start], serde_json::to_string(&f).unwrap(), &text[end..]);
            let go = |text: &str, t0: f64| {
                let mut e: E = serde_json::from_str(text).unwrap_or_else(|err| panic!("engine deserialises: {err}"));
                let grid = OutputGrid {
                    sample_dt: s.output.sample_dt,
                    t_warmup: t0 + s.run.t_warmup,
                    t_end: t0 + s.run.t_end,
                };
                let mut obs = (Recorder::default(), WindowStats::new(grid.t_warmup, grid.t_end, s.junctions.n as u64));
                drive(&mut e, &grid, &mut obs).expect("run");
                Run { rec: obs.0, stats: obs.1, counters: e.counters() }
            };
            (go(&text, 0.0), go(&shifted, t0))
        }
    }
    for (law, bond) in law_bond_pairs().map(|(l, b)| (l.name(), b.name())) {
        let s = exact(law, bond, &["run.t_end=100", "run.t_warmup=10", "junctions.n=100"]);
        let (a, b) = with_engine(&s, Shifted(&s, T0)).unwrap();
        assert_eq!(a.rec.events.len(), b.rec.events.len(), "{law} {bond}");
        for (p, q) in a.rec.events.iter().zip(&b.rec.events) {
            assert!(p.junction == q.junction && p.kind == q.kind, "{law} {bond}");
            assert!(((q.t - T0) - p.t).abs() <= 2.0 * T0 * f64::EPSILON, "{law} {bond}: {} vs {}", q.t - T0, p.t);
            assert!((p.tension - q.tension).abs() <= 1e-9 * (1.0 + p.tension), "{law} {bond}");
        }
        assert_eq!(a.rec.samples.len(), b.rec.samples.len());
        for (p, q) in a.rec.samples.iter().zip(&b.rec.samples) {
            assert!(finite_sample(p));
            assert!(finite_sample(q));
            assert!((p.friction - q.friction).abs() <= 1e-9 * (1.0 + p.friction.abs()), "{law} {bond}: {p:?} {q:?}");
            let shift = s.plate.v * T0;
            assert!(((q.x - shift) - p.x).abs() <= 4.0 * shift * f64::EPSILON + 1e-9 * p.x.abs(), "{p:?} {q:?}");
            assert_eq!(p.attached, q.attached);
        }
        let nseg = b.rec.segments.len() as f64;
        let ulp = T0 * f64::EPSILON;
        let tt = s.run.t_end - s.run.t_warmup;
        let spread = |f: fn(&Sample) -> f64| {
            let m = a.rec.samples.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
            let n = a.rec.samples.iter().map(f).fold(f64::INFINITY, f64::min);
            m - n
        };
        let tol = |range: f64, mean: f64| nseg * ulp * range / tt + 1e-9 * (1.0 + mean.abs());
        let (sa, sb) = (&a.stats, &b.stats);
        let fr = spread(|p| p.friction);
        assert!((sa.friction_mean() - sb.friction_mean()).abs() <= tol(fr, sa.friction_mean()), "{law} {bond}");
        let fb = spread(|p| p.bond_force);
        assert!((sa.bond_force_mean() - sb.bond_force_mean()).abs() <= tol(fb, sa.bond_force_mean()), "{law} {bond}");
        assert!(
            (sa.attached_fraction_mean() - sb.attached_fraction_mean()).abs() <= tol(1.0, 1.0),
            "{law} {bond}: {} vs {}",
            sa.attached_fraction_mean(),
            sb.attached_fraction_mean()
        );
    }
}

// ---------------------------------------------------------------------------------------
// The fixed-step engine at the extremes

/// Stiff plates in the fixed-step scheme: `K = 1e9` or `M/eta = 1e-12` at `dt = 1` are far
/// beyond every integrator's limit (docs/stability.md): the run stops with
/// `EngineError::Diverged` naming the step, never a NaN sample. Below the computed limit
/// (`dt = dt_limit / 2`) the same plates run with finite output.
#[test]
fn fixed_step_stiff_plates_diverge_with_an_error_or_run_below_the_limit() {
    for plate in [["plate.k=1e9", "plate.mass=75"], ["plate.k=150", "plate.mass=75e-12"]] {
        for integ in ["semi-implicit-euler", "explicit-euler", "velocity-verlet"] {
            let over = [plate[0], plate[1], "run.t_end=50", &format!("fixed.integrator={integ}")];
            let s = scene(FIG1, &over);
            match try_run(&s) {
                Err(EngineError::Diverged { step, t, value, .. }) => {
                    assert!((1..=50).contains(&step) && t.is_finite(), "{plate:?} {integ}: step {step} t {t}");
                    assert!(value.abs() > 1e100 || !value.is_finite(), "{value}");
                }
                Err(e) => panic!("{plate:?} {integ}: {e}"),
                Ok(_) => panic!("{plate:?} {integ}: no divergence at dt = 1"),
            }
            let lim = stickslip::engine::fixed::stability::analyse(&s).selected().dt_stable;
            let dt = 0.5 * lim;
            let s = scene(
                FIG1,
                &[
                    &over[..3],
                    &[
                        over[3],
                        &format!("fixed.dt={dt}"),
                        &format!("run.t_end={}", 200.0 * dt),
                        &format!("output.sample_dt={}", 10.0 * dt),
                    ],
                ]
                .concat(),
            );
            let r = try_run(&s).unwrap_or_else(|e| panic!("{plate:?} {integ} dt {dt}: {e}"));
            assert!(r.rec.samples.iter().all(finite_sample));
        }
    }
}

/// Item 2, confirmed by runs: for each integrator at the Fig. 1 plate with no junction
/// stiffness (`kappa = 0`, so `k = K` exactly), a run at `0.98 dt_limit` stays bounded for
/// `n` steps and one at `1.02 dt_limit` diverges within them (the error names the step),
/// with `n = 2 ln(1e102 / scale) / ln |eig|` from the computed spectral radius at
/// `1.02 dt_limit`: twice the steps a growing mode needs to pass the divergence threshold
/// `1e100`. Bounded: the lag `X - V t` never exceeds ten times its scale `V/w + eta V/K`.
#[test]
fn computed_stability_limits_are_confirmed_by_runs() {
    for (integ, mass) in [
        ("semi-implicit-euler", 75.0),
        ("explicit-euler", 75.0),
        ("velocity-verlet", 75.0),
        ("semi-implicit-euler", 0.0),
    ] {
        let base =
            scene(FIG1, &["junctions.kappa=0", &format!("plate.mass={mass}"), &format!("fixed.integrator={integ}")]);
        let lim = stickslip::engine::fixed::stability::analyse(&base).selected().dt_stable;
        assert_eq!(
            lim,
            stickslip::engine::fixed::stability::analyse(&base).selected().dt_unstable,
            "kappa = 0: one limit"
        );
        let (k, eta, v) = (150.0f64, 75.0, 0.5);
        let scale = if mass > 0.0 { v / (k / mass).sqrt() } else { 0.0 } + eta * v / k;
        let over = base.with_overrides(&[format!("fixed.dt={}", 1.02 * lim)]).unwrap();
        let rho = stickslip::engine::fixed::stability::analyse(&over).selected().radius_none;
        assert!(rho > 1.0);
        let steps = (2.0 * (1e102 / scale).ln() / rho.ln()).ceil();
        for (factor, stable) in [(0.98, true), (1.02, false)] {
            let dt = factor * lim;
            let s = base
                .with_overrides(&[
                    format!("fixed.dt={dt}"),
                    format!("run.t_end={}", steps * dt),
                    format!("output.sample_dt={}", 10.0 * dt),
                ])
                .unwrap();
            match (try_run(&s), stable) {
                (Ok(r), true) => {
                    let lag = sup(&r, |p| p.x - v * p.t);
                    assert!(lag <= 10.0 * scale, "{integ} M={mass} dt={dt}: lag {lag}");
                }
                (Err(EngineError::Diverged { step, .. }), false) => assert!(step as f64 <= steps),
                (r, _) => panic!("{integ} M={mass} at {factor} dt_limit: {:?}", r.err()),
            }
        }
    }
}
