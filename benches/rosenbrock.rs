//! Cost of the Rosenbrock (RODAS4) integrator on the engine's kind of plate: a 2-variable
//! plate `M X'' + eta X' + K (X - V t) + S(X) = 0`, `S(X) = kn X + c3 X^3`, with three
//! quadratures (`int X`, `int S`, `int X^2`): state dimension 5.
//!
//! - `event_step/{nonstiff,stiff}`: one step of length 1e-5 followed by `reset` (the N = 1e6
//!   case: events ~1e-5 apart); `dop853_event_step/nonstiff` is DOP853 on the same pattern.
//! - `unit_interval/{nonstiff,stiff}`: free adaptive steps over `[0, 1]` from a fresh
//!   integrator (rtol 1e-8, atol 1e-10).
//!
//! Non-stiff: `M = 1, eta = 2, K = 3, kn = 1, c3 = 4`. Stiff: `M = 1e-9, eta = 1, K = 1e3,
//! kn = 1e3, c3 = 1e4` (fast rate `eta/M = 1e9`).
//!
//! Run: `cargo bench --bench rosenbrock`; medians in `target/criterion/*/new/estimates.json`
//! (figures in docs/performance.md, "Stiff plate integrator").

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use stickslip::ode::{Dop853, Rosenbrock};

#[path = "../tests/suite/rosenbrock_support/mod.rs"]
mod support;
use support::{CubicPlate, Explicit};

const NONSTIFF: CubicPlate = CubicPlate { m: 1.0, eta: 2.0, k: 3.0, v: 0.5, kn: 1.0, c3: 4.0 };
const STIFF: CubicPlate = CubicPlate { m: 1e-9, eta: 1.0, k: 1e3, v: 0.5, kn: 1e3, c3: 1e4 };

fn event_steps(c: &mut Criterion) {
    for (name, plate) in [("nonstiff", NONSTIFF), ("stiff", STIFF)] {
        let mut ode = Rosenbrock::new(5, 1e-8, 1e-10).unwrap();
        ode.set_h_proposal(1e-2);
        let mut sys = plate;
        let (mut t, mut y) = (0.0, [0.2, 0.0, 0.0, 0.0, 0.0]);
        c.bench_function(&format!("rosenbrock/event_step/{name}"), |b| {
            b.iter(|| {
                let t_max = t + 1e-5;
                ode.step(&mut sys, &mut t, &mut y, t_max).unwrap();
                ode.reset();
                black_box(y[0])
            })
        });
    }
    let mut dop = Dop853::new(5, 1e-8, 1e-10).unwrap();
    dop.set_h_proposal(1e-2);
    let mut sys = Explicit(NONSTIFF);
    let (mut t, mut y) = (0.0, [0.2, 0.0, 0.0, 0.0, 0.0]);
    c.bench_function("rosenbrock/dop853_event_step/nonstiff", |b| {
        b.iter(|| {
            let t_max = t + 1e-5;
            dop.step(&mut sys, &mut t, &mut y, t_max).unwrap();
            dop.reset();
            black_box(y[0])
        })
    });
}

fn unit_interval(c: &mut Criterion) {
    for (name, plate) in [("nonstiff", NONSTIFF), ("stiff", STIFF)] {
        c.bench_function(&format!("rosenbrock/unit_interval/{name}"), |b| {
            b.iter(|| {
                let mut ode = Rosenbrock::new(5, 1e-8, 1e-10).unwrap();
                let mut sys = plate;
                let (mut t, mut y) = (0.0, [0.2, 0.0, 0.0, 0.0, 0.0]);
                while t < 1.0 {
                    ode.step(&mut sys, &mut t, &mut y, 1.0).unwrap();
                }
                black_box((y[0], ode.stats().accepted))
            })
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(50).measurement_time(Duration::from_secs(3));
    targets = event_steps, unit_interval
}
criterion_main!(benches);
