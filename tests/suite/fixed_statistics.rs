//! Statistics of the fixed-step junction chain (run with `--release`).
//!
//! With `kappa = 0` the junctions exert no force, and with the plate below `V0` (`g = 1`)
//! every junction is an independent two-state Markov chain with per-step flip
//! probabilities `a` (formation) and `b` (rupture) set by the flip rule:
//! - linear: `a = kon0 dt`, `b = k0 dt`;
//! - exponential: `a = 1 - exp(-kon0 dt)`, `b = 1 - exp(-k0 dt)`;
//! - as-printed: `a = 1 - kon0 dt`, `b = 1 - k0 dt`.
//!
//! Its stationary attached probability is `pi = a / (a + b)` and the lag-`k`
//! autocorrelation of `q` is `rho^k`, `rho = 1 - a - b`. Tolerances come from these: the
//! variance of a time average of `T` consecutive states is
//! `pi (1 - pi) / T * [1 + 2 sum_{k=1}^{T-1} (1 - k/T) rho^k]`, divided by `N` for `N`
//! independent junctions. Every test uses a two-sided significance level `ALPHA` per test,
//! fixed seeds, and checks its own power: the same data must reject a nearby wrong rule.

use crate::common;

use statrs::distribution::{Binomial, ChiSquared, ContinuousCDF, Discrete, Normal};
use stickslip::Scene;
use stickslip::observe::{Observer, Recorder, Segment};
use stickslip::runner::{Observed, Simulation};
use stickslip_testkit::fixed_fig1 as scene;

/// Per-test false-alarm probability.
const ALPHA: f64 = 1e-5;

/// Two-sided normal critical value for `ALPHA` (about 4.42).
fn z_crit() -> f64 {
    Normal::new(0.0, 1.0).unwrap().inverse_cdf(1.0 - ALPHA / 2.0)
}

/// Variance of the mean of `t` consecutive states of one stationary two-state chain.
fn var_of_time_mean(pi: f64, rho: f64, t: u64) -> f64 {
    let tf = t as f64;
    let mut sum = 0.0;
    let mut r = 1.0;
    for k in 1..t {
        r *= rho;
        if r.abs() < 1e-300 {
            break;
        }
        sum += (1.0 - k as f64 / tf) * r;
    }
    pi * (1.0 - pi) / tf * (1.0 + 2.0 * sum)
}

/// Mean attached fraction over steps `warmup..warmup + steps` (each step reports the count
/// after its flips), and the largest plate speed seen.
struct ChainMean {
    warmup: u64,
    steps: u64,
}

struct Acc {
    from: f64,
    sum: u64,
    count: u64,
}

impl Observer for Acc {
    fn segment(&mut self, s: &Segment) {
        if s.t0 >= self.from {
            self.sum += s.attached;
            self.count += 1;
        }
    }
}

impl ChainMean {
    /// `(mean attached fraction over the steps after the warm-up, largest |Xd|)` of a run
    /// of `scene`, step by step.
    fn of(self, scene: &Scene) -> (f64, f64) {
        let mut e = Simulation::new(scene).unwrap();
        let dt = e.time_step().unwrap();
        let n = e.sample().n;
        let mut acc = Acc { from: self.warmup as f64 * dt - 0.5 * dt, sum: 0, count: 0 };
        let mut rec = Recorder::default();
        let mut vmax: f64 = 0.0;
        for k in 1..=self.warmup + self.steps {
            e.advance_observed(k as f64 * dt, Observed::Recorder(&mut rec)).unwrap();
            rec.segments.drain(..).for_each(|g| acc.segment(&g));
            rec.events.clear();
            vmax = vmax.max(e.sample().v.abs());
        }
        assert_eq!(acc.count, self.steps);
        (acc.sum as f64 / (acc.count * n) as f64, vmax)
    }
}

struct Case {
    name: &'static str,
    overrides: Vec<String>,
    /// Per-step formation and rupture probabilities of the rule under test.
    a: f64,
    b: f64,
    /// The stationary fraction a nearby wrong rule would give (power check).
    pi_wrong: f64,
}

fn run_case(c: &Case) {
    let (n, warmup, steps) = (2000u64, 100u64, 5000u64);
    let nn = format!("junctions.n={n}");
    let mut o: Vec<&str> = vec![&nn, "junctions.kappa=0", "fixed.dt=1", "junctions.initial=detached"];
    o.extend(c.overrides.iter().map(String::as_str));
    let s: Scene = scene(&o);
    let (mean, vmax) = ChainMean { warmup, steps }.of(&s);
    assert!(vmax <= s.junctions.v0(), "{}: the plate reached {vmax} > V0, so g < 1", c.name);
    let pi = c.a / (c.a + c.b);
    let rho = 1.0 - c.a - c.b;
    // The chain started detached: after `warmup` steps the bias is pi |rho|^warmup.
    assert!(pi * rho.abs().powi(warmup as i32) < 1e-12);
    let sd = (var_of_time_mean(pi, rho, steps) / n as f64).sqrt();
    let z = (mean - pi) / sd;
    let z_wrong = (mean - c.pi_wrong) / sd;
    eprintln!(
        "{}: mean {mean:.6}, pi {pi:.6}, sd {sd:.2e}, z {z:.2}, z against {:.4}: {z_wrong:.1}",
        c.name, c.pi_wrong
    );
    assert!(z.abs() < z_crit(), "{}: mean {mean} vs pi {pi}: z = {z}", c.name);
    assert!(z_wrong.abs() > z_crit(), "{}: no power against pi = {}: z = {z_wrong}", c.name, c.pi_wrong);
}

fn overrides(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

#[test]
fn linear_rule_stationary_fraction() {
    // a = 0.3, b = 0.2, pi = 0.6, rho = 0.5. The plate is driven (V = 0.05 < V0 = 0.5).
    // Wrong: the exponential rule's pi = (1 - e^-0.3) / (2 - e^-0.3 - e^-0.2) = 0.5886.
    let (a, b) = (0.3f64, 0.2f64);
    let (ae, be) = (-(-a).exp_m1(), -(-b).exp_m1());
    run_case(&Case {
        name: "linear",
        overrides: overrides(&["junctions.kon0=0.3", "junctions.k0=0.2", "plate.v=0.05", "run.seed=11"]),
        a,
        b,
        pi_wrong: ae / (ae + be),
    });
}

#[test]
fn exponential_rule_stationary_fraction() {
    // a = 1 - e^-0.5, b = 1 - e^-0.25: pi = 0.6401, rho = 0.385.
    // Wrong: the linear rule's (and the continuous process's) pi = 0.5/0.75 = 0.6667.
    let (a, b) = (-(-0.5f64).exp_m1(), -(-0.25f64).exp_m1());
    run_case(&Case {
        name: "exponential",
        overrides: overrides(&[
            "junctions.kon0=0.5",
            "junctions.k0=0.25",
            "plate.v=0",
            "fixed.flip=exponential",
            "fixed.rng=pcg",
            "run.seed=5",
        ]),
        a,
        b,
        pi_wrong: 0.5 / 0.75,
    });
}

#[test]
fn as_printed_rule_stationary_fraction() {
    // Flip when xi > k dt: a = 1 - 0.3 = 0.7, b = 1 - 0.2 = 0.8: pi = 0.4667, rho = -0.5
    // (the chain alternates). Wrong: the linear reading's pi = 0.6.
    run_case(&Case {
        name: "as-printed",
        overrides: overrides(&[
            "junctions.kon0=0.3",
            "junctions.k0=0.2",
            "plate.v=0",
            "fixed.flip=as-printed",
            "run.seed=3",
        ]),
        a: 0.7,
        b: 0.8,
        pi_wrong: 0.6,
    });
}

/// Attached counts at `samples` times spaced `spacing` steps apart, after `spacing` steps.
struct Counts {
    samples: usize,
    spacing: u64,
}

impl Counts {
    /// The attached count every `spacing` steps of a run of `scene`.
    fn of(self, scene: &Scene) -> Vec<u64> {
        let mut e = Simulation::new(scene).unwrap();
        let dt = e.time_step().unwrap();
        (1..=self.samples as u64)
            .map(|k| {
                e.advance((k * self.spacing) as f64 * dt).unwrap();
                e.sample().attached
            })
            .collect()
    }
}

/// Pearson chi-square of `counts` against Binomial(n, p), tails merged until every bin
/// expects at least 5; returns `(statistic, degrees of freedom)`.
fn chi_square(counts: &[u64], n: u64, p: f64) -> (f64, f64) {
    let m = counts.len() as f64;
    let dist = Binomial::new(p, n).unwrap();
    let mut observed = vec![0.0; n as usize + 1];
    for &c in counts {
        observed[c as usize] += 1.0;
    }
    let expected: Vec<f64> = (0..=n).map(|k| m * dist.pmf(k)).collect();
    let (stat, df) = common::chi_square(&observed, &expected);
    (stat, df as f64)
}

#[test]
fn attached_count_is_binomial_with_the_rules_stationary_fraction() {
    // Exponential rule, kon0 dt = 0.5, k0 dt = 0.25: pi = 0.6401, rho = 0.385; samples 40
    // steps apart are independent to rho^40 = 3e-17. The count is Binomial(20, pi).
    let (n, p_on, p_off) = (20u64, -(-0.5f64).exp_m1(), -(-0.25f64).exp_m1());
    let pi = p_on / (p_on + p_off);
    let s = scene(&[
        "junctions.n=20",
        "junctions.kappa=0",
        "junctions.kon0=0.5",
        "junctions.k0=0.25",
        "plate.v=0",
        "fixed.dt=1",
        "fixed.flip=exponential",
        "run.seed=2024",
    ]);
    let counts = Counts { samples: 5000, spacing: 40 }.of(&s);
    let (stat, df) = chi_square(&counts, n, pi);
    let crit = ChiSquared::new(df).unwrap().inverse_cdf(1.0 - ALPHA);
    eprintln!("chi2 = {stat:.1}, df {df}, critical {crit:.1}");
    assert!(stat < crit, "chi2 = {stat} >= {crit} (df {df})");
    // Power: the continuous-time fraction kon0/(kon0+k0) = 2/3 is rejected by the same data.
    let (stat, df) = chi_square(&counts, n, 0.5 / 0.75);
    let crit = ChiSquared::new(df).unwrap().inverse_cdf(1.0 - ALPHA);
    eprintln!("against 2/3: chi2 = {stat:.1}, df {df}, critical {crit:.1}");
    assert!(stat > crit, "no power: chi2 = {stat} < {crit}");
}

#[test]
fn stationary_initial_state_is_binomial() {
    // initial = "stationary": attached iff xi < kon0/(kon0+k0) = 0.25, N = 1e5 junctions.
    let n = 100_000u64;
    let s = scene(&[
        "junctions.n=100000",
        "junctions.initial=stationary",
        "junctions.kon0=0.1",
        "junctions.k0=0.3",
        "run.seed=77",
    ]);
    let count = Simulation::new(&s).unwrap().sample().attached as f64;
    let sd = (n as f64 * 0.25 * 0.75).sqrt();
    let z = (count - 0.25 * n as f64) / sd;
    eprintln!("stationary start: {count} attached of {n}, z = {z:.2}");
    assert!(z.abs() < z_crit(), "count {count}: z = {z}");
    // Power: the swapped probability k0/(kon0+k0) = 0.75 would be far off.
    assert!(((count - 0.75 * n as f64) / sd).abs() > z_crit());
}
