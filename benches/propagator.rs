//! Cost of one inter-event step of the exact engine: `LinearPlate::new` + `trajectory` + `at`.
//!
//! `cargo bench --bench propagator`; medians are recorded in docs/propagator.md.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use stickslip::engine::exact::stepper::linear::propagator::LinearPlate;

/// (name, M, eta, k): the letter's Fig. 1 plate (underdamped), an overdamped stiff plate,
/// an exactly critical one, and the overdamped limit M = 0.
const PLATES: [(&str, f64, f64, f64); 4] = [
    ("underdamped", 75.0, 75.0, 165.0),
    ("overdamped", 1e-3, 75.0, 165.0),
    ("critical", 1.0, 2.0, 1.0),
    ("first_order", 0.0, 75.0, 165.0),
];

fn step(c: &mut Criterion) {
    for &(name, m, eta, k) in &PLATES {
        let rho = LinearPlate::new(m, eta, k).rho();
        // Short steps (Taylor path, rho tau = 0.05) and long steps (closed form, rho tau = 5).
        for (label, tau) in [("short", 0.05 / rho), ("long", 5.0 / rho)] {
            c.bench_function(&format!("new+trajectory+at/{name}/{label}"), |bn| {
                let mut y0 = 0.1;
                bn.iter(|| {
                    let p = LinearPlate::new(black_box(m), black_box(eta), black_box(k));
                    let t = p.trajectory(black_box(y0), black_box(0.3), black_box(2.0), black_box(0.5));
                    let (y, v) = t.at(black_box(tau));
                    y0 = 0.1 + 1e-3 * (y - y0);
                    v
                })
            });
        }
        let tau = 0.05 / rho;
        c.bench_function(&format!("new/{name}"), |bn| {
            bn.iter(|| LinearPlate::new(black_box(m), black_box(eta), black_box(k)))
        });
        for (label, tau) in [("short", 0.05 / rho), ("long", 5.0 / rho)] {
            c.bench_function(&format!("at/{name}/{label}"), |bn| {
                let t = LinearPlate::new(m, eta, k).trajectory(0.1, 0.3, 2.0, 0.5);
                bn.iter(|| t.at(black_box(tau)))
            });
        }
        c.bench_function(&format!("integrals/{name}/short"), |bn| {
            let t = LinearPlate::new(m, eta, k).trajectory(0.1, 0.3, 2.0, 0.5);
            bn.iter(|| t.integrals(black_box(tau), black_box(0.2)))
        });
        c.bench_function(&format!("integrals/{name}/long"), |bn| {
            let t = LinearPlate::new(m, eta, k).trajectory(0.1, 0.3, 2.0, 0.5);
            bn.iter(|| t.integrals(black_box(100.0 * tau), black_box(0.2)))
        });
        c.bench_function(&format!("bounds/{name}"), |bn| {
            let t = LinearPlate::new(m, eta, k).trajectory(0.1, 0.3, 2.0, 0.5);
            bn.iter(|| t.bounds(black_box(tau)))
        });
    }
}

criterion_group!(benches, step);
criterion_main!(benches);
