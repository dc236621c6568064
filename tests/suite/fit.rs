//! Calibration (`stickslip fit`, docs/calibration.md), on data the tests make from the
//! simulator at known parameters plus Gaussian noise of known size: a cheap scene (50
//! junctions on a kinematic plate, strong bonds, linear law, exact engine; about half a
//! millisecond a run), friction measured at six velocities.
//!
//! - the fit recovers two parameters within their 95 % profile intervals, and a parameter
//!   the scene does not use (the plate's mass, with a kinematic plate) is undetermined;
//! - across 20 seeds (noise and the fit's own seed both drawn afresh) the one-parameter
//!   interval covers the truth at its nominal 95 % rate: a binomial check, failing (0.03 %
//!   of the time for a correct method) when fewer than 15 cover; the larger check, two
//!   sided over 200 seeds, is `#[ignore]`d (command in docs/testing.md);
//! - the files do not depend on the number of threads;
//! - a fit killed (SIGKILL) and continued with `stickslip resume` writes the `fit.json` of
//!   an uninterrupted fit, byte for byte, also on another number of threads;
//! - every kind of bad input is one line naming the line or field, exit code 2, and no
//!   output directory.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rand_pcg::Pcg64;
use statrs::distribution::{Binomial, DiscreteCDF};
use stickslip::Scene;

use super::common::ALPHA;
use stickslip::fit::data::DataSet;
use stickslip::fit::free::parse_free;
use stickslip::fit::model::{Objective, PoolSimulator, Problem};
use stickslip::fit::solve::{FitResult, fit};

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

/// The tiny scene the Python tests share, `k0` and `kon0` the parameters fitted; these
/// tests run it with 50 junctions and longer runs ([`SIZE`]).
const TINY: &str = include_str!("../fixtures/fit-tiny.toml");
const SIZE: [&str; 3] = ["junctions.n=50", "run.t_end=300", "run.t_warmup=30"];

/// The truth and the measured velocities.
const K0: f64 = 0.5;
const KON0: f64 = 0.2;
const VELOCITIES: [f64; 6] = [0.1, 0.2, 0.5, 1.0, 2.0, 3.0];

fn scene(overrides: &[String]) -> Scene {
    let all: Vec<String> = SIZE.iter().map(|s| s.to_string()).chain(overrides.iter().cloned()).collect();
    Scene::from_toml_str(TINY, "tiny", "tiny", &all).unwrap()
}

/// The model's mean friction per junction at the truth at each velocity, over 32 replicas
/// (standard error below 4 % of the noise added below).
fn truth_curve() -> Vec<f64> {
    VELOCITIES
        .iter()
        .map(|v| {
            let s = scene(&[format!("plate.v={v}"), format!("junctions.k0={K0}"), format!("junctions.kon0={KON0}")]);
            (0..32u64)
                .map(|r| {
                    let mut s = s.clone();
                    s.run.seed = 1_000_000 + r;
                    stickslip::run_scene(&s, None).unwrap().friction_per_junction
                })
                .sum::<f64>()
                / 32.0
        })
        .collect()
}

/// The noise's standard deviation at a point of the curve: 20 % of it, about five times
/// the simulation's standard error with 4 replicas (the intervals hold when the simulation's
/// noise is small beside the data's: docs/calibration.md).
fn sigma_of(f: f64) -> f64 {
    0.2 * f
}

/// DATA.csv: the truth curve plus Gaussian noise of the stated sigma (seeded).
fn data_csv(truth: &[f64], seed: u64) -> String {
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut out = String::from("plate.v,friction,sigma\n");
    for (v, f) in VELOCITIES.iter().zip(truth) {
        let s = sigma_of(*f);
        let noisy = f + Normal::new(0.0, s).unwrap().sample(&mut rng);
        out.push_str(&format!("{v},{noisy},{s}\n"));
    }
    out
}

/// Fits `free` to `csv` with the scene's seed `seed`, 4 replicas, on 1 thread.
fn fit_with(csv: &str, free: &str, seed: u64, fixed: &[String]) -> (Problem, FitResult) {
    fit_on(csv, free, seed, fixed, 1)
}

/// [`fit_with`] on `threads` threads.
fn fit_on(csv: &str, free: &str, seed: u64, fixed: &[String], threads: usize) -> (Problem, FitResult) {
    let mut o = vec![format!("run.seed={seed}")];
    o.extend_from_slice(fixed);
    let base = scene(&o);
    let data = DataSet::parse(csv, "data.csv", &base, 1.0).unwrap();
    let free = parse_free(&[free.to_string()], &base, &data).unwrap();
    let problem = Problem::new(base, data, free, 4).unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let sim = PoolSimulator { pool: &pool, stop: None };
    let obj = Objective::new(&problem, &sim, Vec::new(), None, None, 100_000);
    let r = fit(&obj).unwrap();
    drop(obj);
    (problem, r)
}

fn covers(p: &Problem, r: &FitResult, j: usize, truth: f64) -> bool {
    let f = &p.free[j];
    let iv = &r.intervals[j];
    f.value(iv.low.y) <= truth && truth <= f.value(iv.high.y)
}

#[test]
fn two_parameters_are_recovered_within_their_intervals() {
    let truth = truth_curve();
    let (p, r) = fit_with(&data_csv(&truth, 11), "junctions.k0,junctions.kon0", 5, &[]);
    for (j, t) in [(0, K0), (1, KON0)] {
        let iv = &r.intervals[j];
        let (lo, hi) = (p.free[j].value(iv.low.y), p.free[j].value(iv.high.y));
        assert!(covers(&p, &r, j, t), "{}: truth {t} outside [{lo}, {hi}] (fit {})", p.free[j].field, r.best.values[j]);
        assert!(iv.determined(), "{}: [{lo}, {hi}]", p.free[j].field);
    }

    assert!(r.p_value.unwrap() > 1e-3, "chi2 {} with {} dof", r.chi2, r.dof);
    assert_eq!(r.dof, 4);
}

#[test]
fn the_thread_count_does_not_change_the_result() {
    // The evaluations of a batch run in parallel and the profiles' sides side by side; the
    // files are the same bytes on 1 and on 3 threads.
    let csv = data_csv(&truth_curve(), 14);
    let fixed = [format!("junctions.kon0={KON0}")];
    let files = |threads| {
        let (p, r) = fit_on(&csv, "junctions.k0,junctions.kappa=0.03:0.3", 7, &fixed, threads);
        (stickslip::fit::report::fit_json(&p, &r, "d.csv"), stickslip::fit::report::fit_csv(&p, &r))
    };
    let one = files(1);
    assert_eq!(one, files(3));
}

#[test]
fn a_parameter_without_effect_is_undetermined() {
    let truth = truth_curve();
    // The plate's mass does nothing with a kinematic plate: with common random numbers the
    // misfit is the same at every mass, so its profile is flat between the bounds.
    let fixed = [format!("junctions.k0={K0}"), format!("junctions.kon0={KON0}")];
    let (p, r) = fit_with(&data_csv(&truth, 12), "plate.mass=1:1000", 5, &fixed);
    let iv = &r.intervals[0];
    assert!(!iv.determined() && iv.flat(), "{iv:?}");
    assert_eq!((p.free[0].value(iv.low.y), p.free[0].value(iv.high.y)), (1.0, 1000.0));
    let flags = stickslip::fit::report::flags(&r, 0);
    assert!(flags.iter().any(|f| f.starts_with("flat profile")), "{flags:?}");
    let json: serde_json::Value = serde_json::from_str(&stickslip::fit::report::fit_json(&p, &r, "d.csv")).unwrap();
    assert_eq!(json["parameters"]["plate.mass"]["determined"], false);
}

/// Fits `k0` alone to `trials` fresh data sets (fresh noise and a fresh fit seed each) and
/// returns how many of its 95 % intervals cover the truth.
fn coverage(trials: u64) -> u64 {
    let truth = truth_curve();
    let fixed = [format!("junctions.kon0={KON0}")];
    (0..trials)
        .filter(|&t| {
            let (p, r) = fit_with(&data_csv(&truth, 100 + t), "junctions.k0", 1000 + t, &fixed);
            covers(&p, &r, 0, K0)
        })
        .count() as u64
}

#[test]
fn intervals_cover_the_truth_at_their_nominal_rate() {
    let n = 20;
    let k = coverage(n);
    // Refused when P(K <= k) < ALPHA under K ~ Binomial(20, 0.95): k <= 14.
    let b = Binomial::new(0.95, n).unwrap();
    assert!(b.cdf(14) < ALPHA && b.cdf(15) > ALPHA);
    println!("{k} of {n} intervals cover the truth");
    assert!(b.cdf(k) >= ALPHA, "{k} of {n} intervals cover the truth");
}

/// `cargo test --release --test suite fit::coverage_over_200_seeds -- --ignored`
#[test]
#[ignore]
fn coverage_over_200_seeds() {
    let n = 200;
    let k = coverage(n);
    let b = Binomial::new(0.95, n).unwrap();
    // Two-sided at ALPHA: neither too few (intervals too narrow) nor too many (too wide).
    let lo = (0..=n).find(|&x| b.cdf(x) >= ALPHA / 2.0).unwrap();
    let hi = (0..=n).find(|&x| b.sf(x) < ALPHA / 2.0).unwrap();
    println!("{k} of {n} intervals cover the truth");
    assert!((lo..=hi).contains(&k), "{k} of {n} intervals cover the truth; allowed {lo}..={hi}");
}

// ---------------------------------------------------------------------------------------
// The command line

fn files(dir: &Path) -> (String, String) {
    let scene = dir.join("tiny.toml");
    std::fs::write(&scene, toml::to_string(&self::scene(&[]).to_file()).unwrap()).unwrap();
    let data = dir.join("data.csv");
    std::fs::write(&data, data_csv(&truth_curve(), 13)).unwrap();
    (scene.to_str().unwrap().to_string(), data.to_str().unwrap().to_string())
}

fn stickslip(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("the binary runs")
}

#[test]
fn a_killed_fit_resumes_to_the_same_fit_json() {
    let d = tempfile::tempdir().unwrap();
    let (scene, data) = files(d.path());
    let whole = d.path().join("whole");
    let cut = d.path().join("cut");
    let args = |out: &Path, threads: &str| -> Vec<String> {
        [
            "fit",
            &scene,
            &data,
            "--free",
            "junctions.k0,junctions.kon0",
            "--replicas",
            "2",
            "--threads",
            threads,
            "--out",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain([out.to_str().unwrap().to_string()])
        .collect()
    };
    let o = Command::new(BIN).args(args(&whole, "2")).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lines = |dir: &Path| std::fs::read_to_string(dir.join("journal.jsonl")).map_or(0, |t| t.lines().count());
    let total = lines(&whole);
    // Killed after about a third of its evaluations.
    let mut child =
        Command::new(BIN).args(args(&cut, "1")).stdout(Stdio::null()).stderr(Stdio::null()).spawn().unwrap();
    let started = Instant::now();
    while lines(&cut) < total / 3 && started.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!cut.join("fit.json").exists(), "killed before it finished");
    let o = stickslip(&["resume", cut.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["fit.json", "fit.csv", "fit.toml", "fit.svg"] {
        assert_eq!(std::fs::read(whole.join(f)).unwrap(), std::fs::read(cut.join(f)).unwrap(), "{f}");
    }
    assert_eq!(lines(&cut), total);
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(whole.join("fit.json")).unwrap()).unwrap();
    assert_eq!(json["evaluations"].as_u64().unwrap() as usize, total - 1);
}

#[test]
fn bad_input_is_one_line_exit_2_and_nothing_written() {
    let d = tempfile::tempdir().unwrap();
    let (scene, _) = files(d.path());
    let cases: [(&str, &str, &str); 7] = [
        ("plate.v,f\n1,2\n", "junctions.k0", "no 'friction' column"),
        ("plate.vv,friction\n1,2\n", "junctions.k0", "column 'plate.vv'"),
        ("plate.v,friction\n1,2\n0.5,NaN\n", "junctions.k0", "line 3: friction = NaN"),
        ("plate.v,friction,sigma\n1,2,inf\n", "junctions.k0", "line 2: sigma = inf"),
        ("plate.v,friction\n1,2\n2,3\n", "junctions.k0=-1:1:lin", "junctions.k0 = -1"),
        ("plate.v,friction,sigma\n1,2,0.1\n", "junctions.k0,junctions.kon0", "1 point for 2 free parameters"),
        ("plate.v,friction\n1,2\n", "junctions.k0", "1 point for 1 free parameter"),
    ];
    for (k, (csv, free, mention)) in cases.iter().enumerate() {
        let data = d.path().join(format!("bad{k}.csv"));
        std::fs::write(&data, csv).unwrap();
        let out = d.path().join(format!("out{k}"));
        let o = stickslip(&["fit", &scene, data.to_str().unwrap(), "--free", free, "--out", out.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(mention) && err.lines().count() == 1, "{mention}: {err}");
        assert!(!out.exists(), "{mention}: {} was created", out.display());
    }
}
