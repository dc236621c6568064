//! Rupture models composed with the plate steppers, as docs/engines.md, "Adding a rupture
//! model" promises. Checks:
//!
//! - the worked example's file is `rupture_models/scan.rs` word for word;
//! - `Scan` (the worked example) samples the same process as the crate's sum tree on the
//!   closed-form stepper (linear law) and on the series stepper (tilted law, kinematic plate),
//!   and as the bins on the closed-form stepper (which, like the tree there, keep a
//!   horizon's plan across events where `Scan` plans anew);
//! - the tilted law's weak bonds, on a dynamic plate: the bins and the sum tree sample the
//!   same process; and from `PREFETCH_MIN_N` junctions on, the formations' picks drawn
//!   ahead and drawn at use sample the same process.
//!
//! Each comparison is a two-sample Kolmogorov–Smirnov test (level [`ALPHA`], critical value
//! from the KS distribution) of the mean rupture tension of independent runs, one per seed,
//! the two samples on disjoint seed ranges.

use crate::common::{ALPHA, ks_two_sample, ks_two_sample_critical};
use stickslip::Scene;
use stickslip::engine::Engine;
use stickslip::engine::exact::stepper::series::{DrivenPlate, ExactSeries, PREFETCH_MIN_N, RosenbrockPlate};
use stickslip::engine::exact::{BinnedRupture, DefaultQueue, ExactLinear, TreeRupture};
use stickslip::observe::{EventKind, Nothing, Recorder};
use stickslip::physics::{Linear, Plate, Tilted};
use stickslip_testkit::fig1_with;

/// The worked example of docs/engines.md, "Adding a rupture model", word for word
/// (`the_worked_example_is_this_file`).
mod scan;

use scan::Scan;

const SEEDS: u64 = 100;
const T_WARM: f64 = 50.0;
const T_END: f64 = 150.0;

fn scene(law: &str, seed: u64, extra: &[&str]) -> Scene {
    let mut o = vec![
        "run.engine=exact".to_string(),
        format!("junctions.force_law={law}"),
        "junctions.bond=weak".to_string(),
        format!("run.seed={seed}"),
    ];
    o.extend(extra.iter().map(|s| s.to_string()));
    fig1_with(&o.iter().map(String::as_str).collect::<Vec<_>>())
}

/// The mean tension of the ruptures in `[T_WARM, T_END]`.
fn mean_rupture_tension<E: Engine>(e: E) -> f64 {
    mean_rupture_tension_over(e, T_WARM, T_END)
}

/// The mean tension of the ruptures in `[t_warm, t_end]`.
fn mean_rupture_tension_over<E: Engine>(mut e: E, t_warm: f64, t_end: f64) -> f64 {
    e.advance(t_warm, &mut Nothing).unwrap();
    let mut rec = Recorder::default();
    e.advance(t_end, &mut rec).unwrap();
    let t: Vec<f64> = rec.events.iter().filter(|e| e.kind == EventKind::Rupture).map(|e| e.tension).collect();
    assert!(t.len() > 100, "too few ruptures to test anything: {}", t.len());
    t.iter().sum::<f64>() / t.len() as f64
}

/// The settings that scale the letter's Fig. 1 to `n` junctions: `K = N/2`, `M = eta = N/4`
/// (the plate's time scales those of `N = 300`), stationary start.
fn scaled(n: usize) -> Vec<String> {
    vec![
        format!("junctions.n={n}"),
        format!("plate.k={}", n / 2),
        format!("plate.mass={}", n / 4),
        format!("plate.eta={}", n / 4),
        "junctions.initial=stationary".to_string(),
    ]
}

/// `a = beta dx kappa`, the envelope's exponent.
fn a_of(s: &Scene) -> f64 {
    s.junctions.beta_dx() * s.junctions.kappa
}

/// Two samples of `SEEDS` runs each (seeds `1..` and `1001..`) agree in law.
fn same_law(what: &str, mut a: impl FnMut(u64) -> f64, mut b: impl FnMut(u64) -> f64) {
    let mut x: Vec<f64> = (1..=SEEDS).map(&mut a).collect();
    let mut y: Vec<f64> = (1001..=1000 + SEEDS).map(&mut b).collect();
    let d = ks_two_sample(&mut x, &mut y);
    let crit = ks_two_sample_critical(x.len(), y.len(), ALPHA);
    eprintln!("{what}: D = {d:.3}, critical {crit:.3}");
    assert!(d < crit, "{what}: KS D = {d} >= {crit}");
}

const MARKER: &str = "### Adding a rupture model";

#[test]
fn the_worked_example_is_this_file() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/engines.md")).unwrap();
    let at = doc.find(MARKER).expect("the section");
    let start = doc[at..].find("```rust\n").expect("a rust block") + at + "```rust\n".len();
    let end = doc[start..].find("```\n").expect("its end") + start;
    let file = std::fs::read_to_string(root.join("tests/suite/rupture_models/scan.rs")).unwrap();
    assert_eq!(doc[start..end], file);
}

/// The worked example on the closed-form stepper, against the sum tree.
#[test]
fn the_worked_example_runs_on_the_closed_form_stepper() {
    let run = |seed: u64, tree: bool| {
        let s = scene("linear", seed, &[]);
        let (k0, a, law) = (s.junctions.k0, a_of(&s), Linear::from_scene(&s));
        if tree {
            mean_rupture_tension(ExactLinear::<_, DefaultQueue>::new(&s, &law, |_| TreeRupture::new(k0, a, 300)))
        } else {
            mean_rupture_tension(ExactLinear::<_, DefaultQueue>::new(&s, &law, |_| Scan::new(k0, a)))
        }
    };
    same_law("linear law, scan against tree", |s| run(s, false), |s| run(s, true));
}

/// The linear law's bins and sum tree on the closed-form stepper (dynamic plate), which keep a
/// horizon's plan across events while the plate's widened bounds allow, against the worked
/// example, which plans anew after every event. On the letter's plate one junction moves
/// the plate too much over a horizon for a plan to be kept; on it scaled to `N = 3000` (`K
/// = N/2`, `M = eta = N/4`, the same time scales) nearly every event keeps it.
#[test]
fn linear_weak_bonds_bins_and_tree_keeping_plans_against_the_worked_example() {
    let n = 3000;
    let mut sets = scaled(n);
    sets.push("run.t_end=30".to_string());
    let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
    let run = |seed: u64, model: &str| {
        let s = scene("linear", seed, &sets);
        let (k0, a, law) = (s.junctions.k0, a_of(&s), Linear::from_scene(&s));
        match model {
            "bins" => {
                let binned = |rng: &mut _| BinnedRupture::try_new(k0, a, n, rng).unwrap();
                mean_rupture_tension_over(ExactLinear::<_, DefaultQueue>::new(&s, &law, binned), 5.0, 30.0)
            }
            "tree" => {
                let tree = |_: &mut _| TreeRupture::new(k0, a, n);
                mean_rupture_tension_over(ExactLinear::<_, DefaultQueue>::new(&s, &law, tree), 5.0, 30.0)
            }
            _ => mean_rupture_tension_over(
                ExactLinear::<_, DefaultQueue>::new(&s, &law, |_| Scan::new(k0, a)),
                5.0,
                30.0,
            ),
        }
    };
    same_law("linear law at N = 3000, bins against scan", |s| run(s, "bins"), |s| run(s, "scan"));
    same_law("linear law at N = 3000, tree against scan", |s| run(s, "tree"), |s| run(s, "scan"));
}

/// The linear law's bins on the letter's scene against the worked example.
#[test]
fn linear_weak_bonds_bins_against_the_worked_example() {
    let run = |seed: u64, bins: bool| {
        let s = scene("linear", seed, &[]);
        let (k0, a, law, n) = (s.junctions.k0, a_of(&s), Linear::from_scene(&s), s.junctions.n);
        if bins {
            let binned = |rng: &mut _| BinnedRupture::try_new(k0, a, n, rng).unwrap();
            mean_rupture_tension(ExactLinear::<_, DefaultQueue>::new(&s, &law, binned))
        } else {
            mean_rupture_tension(ExactLinear::<_, DefaultQueue>::new(&s, &law, |_| Scan::new(k0, a)))
        }
    };
    same_law("linear law, bins against scan", |s| run(s, true), |s| run(s, false));
}

/// The worked example on the series stepper (tilted law, kinematic plate), against the tree.
#[test]
fn the_worked_example_runs_on_the_series_stepper() {
    let run = |seed: u64, tree: bool| {
        let s = scene("tilted", seed, &["plate.kinematic=true"]);
        let (k0, a, law, v) = (s.junctions.k0, a_of(&s), Tilted::from_scene(&s), s.plate.v);
        let bdx = s.junctions.beta_dx();
        if tree {
            let tree = |_: &mut _| Ok(TreeRupture::new(k0, a, 300));
            mean_rupture_tension(ExactSeries::new(&s, law, bdx, tree, DrivenPlate::new(v)).unwrap())
        } else {
            mean_rupture_tension(ExactSeries::new(&s, law, bdx, |_| Ok(Scan::new(k0, a)), DrivenPlate::new(v)).unwrap())
        }
    };
    same_law("tilted law, kinematic plate, scan against tree", |s| run(s, false), |s| run(s, true));
}

/// The tilted law's weak bonds on a dynamic plate: the bins (what a run uses from
/// `BINNED_FROM` junctions on) against the sum tree, on the same scene.
#[test]
fn tilted_weak_bonds_bins_against_the_tree() {
    let run = |seed: u64, bins: bool| {
        let s = scene("tilted", seed, &[]);
        let (k0, a, law, n) = (s.junctions.k0, a_of(&s), Tilted::from_scene(&s), s.junctions.n);
        let bdx = s.junctions.beta_dx();
        let rate = n as f64 * k0.max(s.junctions.kon0);
        let plate = || RosenbrockPlate::new(Plate::from_scene(&s), law.kappa * n as f64, 1e-10, 1e-12, rate).unwrap();
        if bins {
            let binned = |rng: &mut _| BinnedRupture::try_new(k0, a, n, rng);
            mean_rupture_tension(ExactSeries::new(&s, law, bdx, binned, plate()).unwrap())
        } else {
            let tree = |_: &mut _| TreeRupture::try_new(k0, a, n);
            mean_rupture_tension(ExactSeries::new(&s, law, bdx, tree, plate()).unwrap())
        }
    };
    same_law("tilted law, dynamic plate, bins against tree", |s| run(s, true), |s| run(s, false));
}

/// The tilted law's weak bonds from `PREFETCH_MIN_N` junctions on draw their formations'
/// picks ahead of use (so that the detached record is prefetched): against the picks drawn
/// from the generator at each formation, on the same scene (the letter's Fig. 1 scaled to
/// `N = PREFETCH_MIN_N`: `K = N/2`, `M = eta = N/4`, stationary start).
#[test]
fn tilted_weak_bonds_formations_drawn_ahead_against_drawn_at_use() {
    let n = PREFETCH_MIN_N;
    let sets = scaled(n);
    let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
    let run = |seed: u64, ahead: bool| {
        let s = scene("tilted", seed, &sets);
        let (k0, a, law) = (s.junctions.k0, a_of(&s), Tilted::from_scene(&s));
        let bdx = s.junctions.beta_dx();
        let rate = n as f64 * k0.max(s.junctions.kon0);
        let plate = RosenbrockPlate::new(Plate::from_scene(&s), law.kappa * n as f64, 1e-10, 1e-12, rate).unwrap();
        let e = ExactSeries::new(&s, law, bdx, |_: &mut _| TreeRupture::try_new(k0, a, n), plate).unwrap();
        mean_rupture_tension(if ahead { e } else { e.with_formations_drawn_at_use() })
    };
    same_law("tilted law, formations drawn ahead against at use", |s| run(s, true), |s| run(s, false));
}
