//! Exact engine throughput: events per second at N = 1e3, 1e5, 1e6 for strong and weak
//! bonds (linear law), and the event-queue comparison (hand-written scan vs the
//! `priority-queue` crate). Run: `cargo bench --bench exact`.

use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use stickslip::engine::Engine;
use stickslip::engine::exact::{ArrayQueue, ChannelQueue, PqQueue, strong_linear, weak_linear};
use stickslip::observe::Nothing;
use stickslip::testkit::scaled_linear;

/// Simulated time per iteration that gives about 1e5 events (about 0.1 events per junction
/// per unit time in the Fig. 1 physics).
fn span(n: usize) -> f64 {
    1e6 / n as f64
}

fn bench_engine<E: Engine>(c: &mut Criterion, group: &str, n: usize, mut make: impl FnMut() -> E) {
    // Pilot: events per span at steady state, for the throughput figure.
    let mut pilot = make();
    pilot.advance(20.0, &mut Nothing).unwrap();
    let before = pilot.counters().events.unwrap();
    pilot.advance(20.0 + span(n), &mut Nothing).unwrap();
    let per_span = pilot.counters().events.unwrap() - before;

    let mut g = c.benchmark_group(group);
    g.sample_size(10).measurement_time(Duration::from_secs(8)).warm_up_time(Duration::from_secs(1));
    g.throughput(Throughput::Elements(per_span));
    g.bench_function(BenchmarkId::from_parameter(n), |b| {
        b.iter_custom(|iters| {
            let mut e = make();
            e.advance(20.0, &mut Nothing).unwrap();
            let mut t = 20.0;
            let start = Instant::now();
            for _ in 0..iters {
                t += span(n);
                e.advance(t, &mut Nothing).unwrap();
            }
            start.elapsed()
        })
    });
    g.finish();
}

fn sizes(c: &mut Criterion) {
    for n in [1_000, 100_000, 1_000_000] {
        let s = scaled_linear(n, "strong");
        bench_engine(c, "exact/strong-linear", n, || strong_linear::<ArrayQueue>(&s));
        let s = scaled_linear(n, "weak");
        bench_engine(c, "exact/weak-linear", n, || weak_linear::<ArrayQueue>(&s));
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

criterion_group!(benches, sizes, queues);
criterion_main!(benches);
