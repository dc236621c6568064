//! Cost per junction-step of the fixed-step engine.
//!
//! `cargo bench --bench fixed`. Scenes: the letter's Fig. 1 with `N` junctions, `kappa`
//! scaled to `30 / N` (the letter's total junction stiffness `N kappa = 30`, so the plate
//! dynamics are the same at every `N`), `dt = 0.1` (stable for every integrator), no
//! observers. Each iteration advances the same engine by a fixed number of steps.

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use stickslip::engine::fixed;
use stickslip::engine::{Engine, EngineVisitor};
use stickslip::observe::Nothing;
use stickslip::testkit;

const DT: f64 = 0.1;

struct Bench<'a, 'b> {
    bencher: &'a mut criterion::Bencher<'b>,
    steps: u64,
}

impl EngineVisitor for Bench<'_, '_> {
    type Output = ();
    fn visit<E: Engine>(self, mut engine: E) {
        let steps = self.steps;
        // Warm up past the initial transient (all junctions detached).
        engine.advance(50.0, &mut Nothing).unwrap();
        self.bencher.iter(|| {
            let t = engine.time() + steps as f64 * DT;
            engine.advance(t, &mut Nothing).unwrap();
        });
    }
}

fn junction_steps(c: &mut Criterion) {
    for (law, bond) in [("linear", "strong"), ("tilted", "strong"), ("linear", "weak"), ("tilted", "weak")] {
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
                fixed::dispatch(&scene, Bench { bencher: b, steps }).unwrap();
            });
        }
        group.finish();
    }
}

criterion_group!(benches, junction_steps);
criterion_main!(benches);
