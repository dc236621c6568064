//! Exact engine throughput: events per second at N = 1e3, 1e5, 1e6 (and 1e7 for the linear
//! law) for strong and weak bonds (linear law and the letter's tilted law; the tilted law
//! also at N = 300, the letter's own scene, and 1e4), weak bonds' bins against a sum tree
//! (`exact/weak-linear-tree`), and the event-queue comparison (hand-written scan vs the
//! `priority-queue` crate). Run: `cargo bench --bench exact` (`-- linear` or `-- tilted` for
//! one law).

use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use stickslip::engine::Engine;
use stickslip::engine::exact::{ArrayQueue, ChannelQueue, PqQueue, strong_linear, weak_linear, weak_linear_tree};
use stickslip::observe::{Nothing, Observer};
use stickslip::runner::{Simulation, core_observers};
use stickslip_testkit::{scaled_linear, scaled_tilted};

/// Simulated time per iteration that gives about 1e5 events (about 0.1 events per junction
/// per unit time in the Fig. 1 physics).
fn span(n: usize) -> f64 {
    1e6 / n as f64
}

fn bench_engine<E: Engine>(c: &mut Criterion, group: &str, n: usize, make: impl FnMut() -> E) {
    bench_with(c, group, n, make, || Nothing);
}

/// Like `bench_engine`, with the observers `obs` makes fed along the way (e.g. the window
/// statistics and regime detector every run has).
fn bench_with<E: Engine, O: Observer>(
    c: &mut Criterion,
    group: &str,
    n: usize,
    mut make: impl FnMut() -> E,
    mut obs: impl FnMut() -> O,
) {
    // Pilot: events per span at steady state, for the throughput figure.
    let mut pilot = make();
    pilot.advance(20.0, &mut Nothing).unwrap();
    let before = pilot.counters().events.unwrap();
    pilot.advance(20.0 + span(n), &mut Nothing).unwrap();
    let per_span = pilot.counters().events.unwrap() - before;

    let mut g = c.benchmark_group(group);
    g.sample_size(10).measurement_time(Duration::from_secs(8)).warm_up_time(Duration::from_secs(1));
    g.throughput(Throughput::Elements(per_span));
    // One engine, warmed up once: every sample continues it in its steady state (at
    // N = 1e7 a new engine and warm-up per sample would cost minutes per row).
    let mut e = make();
    let mut o = obs();
    e.advance(20.0, &mut o).unwrap();
    let mut t = 20.0;
    g.bench_function(BenchmarkId::from_parameter(n), |b| {
        b.iter_custom(|iters| {
            let start = Instant::now();
            for _ in 0..iters {
                t += span(n);
                e.advance(t, &mut o).unwrap();
            }
            start.elapsed()
        })
    });
    g.finish();
}

/// Like `bench_engine` for the engine the scene selects, behind a [`Simulation`] handle (one
/// virtual call per iteration of about 1e5 events: negligible). The tilted law's engine is
/// chosen by `exact.tilted`, so the bench measures whatever a run of the scene would use.
fn bench_scene(c: &mut Criterion, group: &str, n: usize, scene: &stickslip::Scene) {
    let make = || Simulation::new(scene).unwrap();
    let mut pilot = make();
    pilot.advance(20.0).unwrap();
    let before = pilot.counters().events.unwrap();
    pilot.advance(20.0 + span(n)).unwrap();
    let per_span = pilot.counters().events.unwrap() - before;

    let mut g = c.benchmark_group(group);
    g.sample_size(10).measurement_time(Duration::from_secs(8)).warm_up_time(Duration::from_secs(1));
    g.throughput(Throughput::Elements(per_span));
    g.bench_function(BenchmarkId::from_parameter(n), |b| {
        b.iter_custom(|iters| {
            let mut e = make();
            e.advance(20.0).unwrap();
            let mut t = 20.0;
            let start = Instant::now();
            for _ in 0..iters {
                t += span(n);
                e.advance(t).unwrap();
            }
            start.elapsed()
        })
    });
    g.finish();
}

fn sizes(c: &mut Criterion) {
    for n in [1_000, 100_000, 1_000_000, 10_000_000] {
        let s = scaled_linear(n, "strong");
        bench_engine(c, "exact/strong-linear", n, || strong_linear::<ArrayQueue>(&s));
        let s = scaled_linear(n, "weak");
        bench_engine(c, "exact/weak-linear", n, || weak_linear::<ArrayQueue>(&s));
    }
}

/// Weak bonds' rupture candidates drawn from a sum tree of the junctions' weights, the
/// comparison for the bins of `exact/weak-linear` (the same process and scene).
fn weak_tree(c: &mut Criterion) {
    for n in [1_000, 100_000, 1_000_000, 10_000_000] {
        let s = scaled_linear(n, "weak");
        bench_engine(c, "exact/weak-linear-tree", n, || weak_linear_tree::<ArrayQueue>(&s));
    }
}

/// The letter's tilted law (scaled Fig. 1, `exact.tilted` at its default, `series`); N = 300
/// is the letter's Fig. 1 itself.
fn tilted(c: &mut Criterion) {
    for n in [300, 1_000, 10_000, 100_000, 1_000_000] {
        bench_scene(c, "exact/strong-tilted", n, &scaled_tilted(n, "strong"));
        bench_scene(c, "exact/weak-tilted", n, &scaled_tilted(n, "weak"));
    }
}

/// What a run pays: the same engines feeding the window statistics and regime detector.
fn with_statistics(c: &mut Criterion) {
    let n = 1_000_000;
    for bond in ["strong", "weak"] {
        let s = scaled_linear(n, bond);
        let obs = || core_observers(&s);
        if bond == "strong" {
            bench_with(c, "exact/strong-linear+stats", n, || strong_linear::<ArrayQueue>(&s), obs);
        } else {
            bench_with(c, "exact/weak-linear+stats", n, || weak_linear::<ArrayQueue>(&s), obs);
        }
    }
}

fn queues(c: &mut Criterion) {
    fn both<Q: ChannelQueue>(c: &mut Criterion, name: &str) {
        let n = 100_000;
        let s = scaled_linear(n, "strong");
        bench_engine(c, &format!("exact/queue-{name}/strong"), n, || strong_linear::<Q>(&s));
        let s = scaled_linear(n, "weak");
        bench_engine(c, &format!("exact/queue-{name}/weak"), n, || weak_linear::<Q>(&s));
    }
    both::<ArrayQueue>(c, "array");
    both::<PqQueue>(c, "priority-queue");
}

criterion_group!(benches, sizes, weak_tree, tilted, with_statistics, queues);
criterion_main!(benches);
