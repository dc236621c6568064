//! What the `runner::Simulation` handle costs against the engine it erases: the same
//! engine advanced directly (type known: the test kit's `Concrete`) and through the handle (one
//! virtual call per advance). `cargo bench --bench simulation`; figures in
//! docs/performance.md.
//!
//! - `exact-strong-linear+stats`: the exact engine at `N = 1e6` feeding the core observers,
//!   about 1e5 events per advance (the workload of `benches/exact.rs`, `with_statistics`);
//! - `fixed-1000-one-step`: the fixed engine at `N = 1000`, one step per advance, no
//!   observers: the most calls per unit of work, so the per-call cost shows if it exists.

use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use stickslip::Scene;
use stickslip::runner::{Observed, Simulation, core_observers};
use stickslip_testkit::{Concrete, fig1_with, scaled_linear};

/// One workload: a scene, the time to warm up to, the span of one advance, advances per
/// iteration, and whether the core observers are fed.
#[derive(Clone, Copy)]
struct Work<'a> {
    scene: &'a Scene,
    warm: f64,
    span: f64,
    advances: u64,
    core: bool,
}

/// Times `iters` iterations of the workload on a fresh engine, advanced directly (the
/// kit's [`Concrete`]: the engine's type known, a local variable).
fn direct(w: Work, iters: u64) -> Duration {
    Concrete { scene: w.scene, warm: w.warm, span: w.span, advances: iters * w.advances, core: w.core, boxed: false }
        .run()
        .elapsed
}

/// The same through the handle.
fn through_handle(w: Work, iters: u64) -> Duration {
    let mut sim = Simulation::new(w.scene).unwrap();
    let mut core = core_observers(w.scene);
    sim.advance_observed(w.warm, Observed::Core(&mut core)).unwrap();
    let start = Instant::now();
    for k in 1..=iters * w.advances {
        let t = w.warm + k as f64 * w.span;
        if w.core {
            sim.advance_observed(t, Observed::Core(&mut core)).unwrap();
        } else {
            sim.advance(t).unwrap();
        }
    }
    start.elapsed()
}

fn bench(c: &mut Criterion, name: &str, w: Work, elements: u64) {
    let mut g = c.benchmark_group(format!("simulation/{name}"));
    g.sample_size(20).measurement_time(Duration::from_secs(8)).warm_up_time(Duration::from_secs(1));
    g.throughput(Throughput::Elements(elements));
    g.bench_function("direct", |b| b.iter_custom(|iters| direct(w, iters)));
    g.bench_function("handle", |b| b.iter_custom(|iters| through_handle(w, iters)));
    g.finish();
}

fn handle_against_direct(c: &mut Criterion) {
    let n = 1_000_000;
    let exact = scaled_linear(n, "strong");
    // About 0.1 events per junction per unit time: 1e5 events per advance.
    let span = 1e6 / n as f64 * 1.0;
    bench(c, "exact-strong-linear+stats", Work { scene: &exact, warm: 20.0, span, advances: 1, core: true }, 100_000);
    let fixed = fig1_with(&[
        "junctions.n=1000",
        "junctions.kappa=0.03",
        "fixed.dt=0.1",
        "junctions.force_law=linear",
        "run.t_end=1e9",
        "output.sample_dt=1e6",
    ]);
    let steps = 1000;
    bench(
        c,
        "fixed-1000-one-step",
        Work { scene: &fixed, warm: 50.0, span: 0.1, advances: steps, core: false },
        steps * 1000,
    );
}

criterion_group!(benches, handle_against_direct);
criterion_main!(benches);
