//! Cost of the tilted law's bond-force series (`engine::exact::stepper::series::SeriesSum`, src/engine/exact/stepper/series/sum/mod.rs):
//! add + remove of one junction, `force_and_stiffness`, `integral`, and a re-base, with
//! 1e5 anchors spread uniformly over 25 l0 (100 bins of width l0/4), default `rtol = 1e-10`
//! (`p = 17`); the direct O(N) sum over the same anchors for scale. Direct mode (the
//! engine's below `DIRECT_MAX` junctions): add + remove and a re-base with the first 1e3 of
//! those anchors (`series/direct/...`).
//!
//! `cargo bench --bench series`; medians are recorded in docs/performance.md.

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Duration;
use stickslip::engine::exact::stepper::series::SeriesSum;
use stickslip::physics::{ForceLaw, Tilted};

const N: usize = 100_000;

fn anchors(l0: f64) -> Vec<f64> {
    // A fixed low-discrepancy spread over [-25 l0, 0): the plate at 0 formed them while sliding.
    (0..N).map(|i| -25.0 * l0 * ((i as f64 * 0.618_033_988_749_895) % 1.0)).collect()
}

/// The engine's pattern: a junction forms at the plate (one bin in bins mode, the bin search
/// predicted) and one detaches by its handle.
fn add_remove_at_plate(g: &mut BenchmarkGroup<'_, WallTime>, s: &mut SeriesSum) {
    g.bench_function("add+remove/at-plate", |bn| {
        let mut i = 0usize;
        bn.iter(|| {
            i = (i + 1) & 63;
            let c = black_box(-0.001 * i as f64);
            let h = s.add(c);
            s.remove(c, h);
        })
    });
}

/// A re-base at `+-0.1` alternately.
fn rebase_back_and_forth(g: &mut BenchmarkGroup<'_, WallTime>, s: &mut SeriesSum, name: &str) {
    g.bench_function(name, |bn| {
        let mut y = 0.1;
        bn.iter(|| {
            y = -y;
            s.rebase(black_box(y))
        })
    });
}

fn series(c: &mut Criterion) {
    let law = Tilted { kappa: 0.1, l0: 1.0 };
    let cs = anchors(law.l0);
    let mut s = SeriesSum::new(law, 1e-10);
    for &a in &cs {
        s.add(a);
    }
    s.rebase(0.0);
    assert!((100..=101).contains(&s.bin_count()), "bins: {}", s.bin_count());
    let mut g = c.benchmark_group("series");
    g.measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));

    add_remove_at_plate(&mut g, &mut s);
    // Anchors in random bins (each add looks its bin up in the grid-index table).
    g.bench_function("add+remove/random-bin", |bn| {
        let mut i = 0usize;
        bn.iter(|| {
            i = (i + 7919) % N;
            let c = black_box(cs[i]);
            let h = s.add(c);
            s.remove(c, h);
        })
    });
    g.bench_function("force_and_stiffness", |bn| {
        let mut y = 0.01;
        bn.iter(|| {
            y = -y;
            s.force_and_stiffness(black_box(y))
        })
    });
    g.bench_function("integral", |bn| bn.iter(|| s.integral(black_box(-0.05), black_box(0.1))));
    rebase_back_and_forth(&mut g, &mut s, "rebase");
    g.bench_function("direct_sum_1e5", |bn| {
        bn.iter(|| {
            let y = black_box(0.01);
            cs.iter().map(|&a| law.force_x(y - a)).sum::<f64>()
        })
    });
    g.finish();

    let mut s = SeriesSum::direct(law, 1e-10);
    for &a in &cs[..1000] {
        s.add(a);
    }
    s.rebase(0.0);
    let mut g = c.benchmark_group("series/direct");
    g.measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    add_remove_at_plate(&mut g, &mut s);
    rebase_back_and_forth(&mut g, &mut s, "rebase/1e3");
    g.finish();
}

criterion_group!(benches, series);
criterion_main!(benches);
