//! Cost per junction-step of the fixed-step engine.
//!
//! `cargo bench --bench fixed`. Scenes: the letter's Fig. 1 with `N` junctions, `kappa`
//! scaled to `30 / N` (the letter's total junction stiffness `N kappa = 30`, so the plate
//! dynamics are the same at every `N`), `dt = 0.1` (stable for every integrator), no
//! observers. Each iteration advances the same engine (through `runner::Simulation`) by a
//! fixed number of steps; every force law and bond kind (`testkit::law_bond_pairs`), on
//! one thread. The group `fixed/threads` runs each law with strong bonds at `N = 1e5` on 1
//! and 2 threads ([`Simulation::set_threads`]; the same results on each).

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use stickslip::runner::Simulation;
use stickslip_testkit as testkit;

const DT: f64 = 0.1;

fn junction_steps(c: &mut Criterion) {
    for (law, bond) in testkit::law_bond_pairs().map(|(l, b)| (l.name(), b.name())) {
        let mut group = c.benchmark_group(format!("fixed/{law}/{bond}"));
        group.sample_size(10);
        for n in [1_000usize, 100_000, 1_000_000] {
            let steps = (20_000_000 / n as u64).clamp(10, 20_000);
            group.measurement_time(Duration::from_secs(if n >= 1_000_000 { 4 } else { 3 }));
            group.throughput(Throughput::Elements(n as u64 * steps));
            let scene = scene(law, bond, n);
            group.bench_function(BenchmarkId::from_parameter(n), |b| {
                bench_steps(b, Simulation::new(&scene).unwrap(), steps);
            });
        }
        group.finish();
    }
}

/// The scene of `law` and `bond` at `n` junctions (module doc).
fn scene(law: &str, bond: &str, n: usize) -> stickslip::scene::Scene {
    testkit::fig1_with(&[
        &format!("junctions.n={n}"),
        &format!("junctions.force_law={law}"),
        &format!("junctions.bond={bond}"),
        &format!("junctions.kappa={}", 30.0 / n as f64),
        &format!("fixed.dt={DT}"),
        "run.t_end=1e9",
        "output.sample_dt=1e6",
    ])
}

/// Advances `sim` by `steps` steps per iteration, after a warm-up past the initial transient
/// (all junctions detached). Through the handle: one virtual call per advance.
fn bench_steps(b: &mut criterion::Bencher<'_>, mut sim: Simulation, steps: u64) {
    sim.advance(50.0).unwrap();
    b.iter(|| {
        let t = sim.time() + steps as f64 * DT;
        sim.advance(t).unwrap();
    });
}

fn threads(c: &mut Criterion) {
    let n = 100_000usize;
    let steps = 200u64;
    for law in testkit::LAWS.iter().map(|l| l.name()) {
        let mut group = c.benchmark_group(format!("fixed/threads/{law}"));
        group.sample_size(10).measurement_time(Duration::from_secs(3));
        group.throughput(Throughput::Elements(n as u64 * steps));
        let scene = scene(law, "strong", n);
        for threads in [1usize, 2] {
            group.bench_function(BenchmarkId::from_parameter(threads), |b| {
                let mut sim = Simulation::new(&scene).unwrap();
                sim.set_threads(threads);
                bench_steps(b, sim, steps);
            });
        }
        group.finish();
    }
}

criterion_group!(benches, junction_steps, threads);
criterion_main!(benches);
