//! Cost per junction-step of the fixed-step engine.
//!
//! `cargo bench --bench fixed`. Scenes: the letter's Fig. 1 with `N` junctions, `kappa`
//! scaled to `30 / N` (the letter's total junction stiffness `N kappa = 30`, so the plate
//! dynamics are the same at every `N`), `dt = 0.1` (stable for every integrator), no
//! observers. Each iteration advances the same engine (through `runner::Simulation`) by a
//! fixed number of steps; every force law and bond kind (`testkit::law_bond_pairs`).

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
            let kappa = format!("junctions.kappa={}", 30.0 / n as f64);
            let scene = testkit::fig1_with(&[
                &format!("junctions.n={n}"),
                &format!("junctions.force_law={law}"),
                &format!("junctions.bond={bond}"),
                &kappa,
                &format!("fixed.dt={DT}"),
                "run.t_end=1e9",
                "output.sample_dt=1e6",
            ]);
            group.bench_function(BenchmarkId::from_parameter(n), |b| {
                // Through the handle: one virtual call per advance of `steps` steps.
                let mut sim = Simulation::new(&scene).unwrap();
                // Warm up past the initial transient (all junctions detached).
                sim.advance(50.0).unwrap();
                b.iter(|| {
                    let t = sim.time() + steps as f64 * DT;
                    sim.advance(t).unwrap();
                });
            });
        }
        group.finish();
    }
}

criterion_group!(benches, junction_steps);
criterion_main!(benches);
