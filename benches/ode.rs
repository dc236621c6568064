//! Cost per step of the DOP853 integrator (`src/ode/`).
//!
//! - `osc2`: 2-dimensional harmonic oscillator, free adaptive steps.
//! - `junctions/n`: the plate ODE of the `tilted` law with `n` attached junctions,
//!   state `[X, X', int X dt, int F_b dt]`,
//!   `M X'' = -eta X' - k (X - V t) - sum_i kappa x_i (1 - l0 / sqrt(x_i^2 + l0^2))`,
//!   `x_i = X - c_i` (Fig. 1 parameters; the junction force is the library's
//!   `physics::Tilted`); one RHS evaluation costs `n` square roots.
//!   `free`: free adaptive steps; `cut`: the engine's pattern, a step to `t + 0.03` followed
//!   by `reset` (one step + one restart evaluation per iteration); `rhs`: one evaluation.
//!
//! Run: `cargo bench --bench ode`; medians in `target/criterion/*/new/estimates.json`
//! (figures in docs/ode.md).

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use stickslip::ode::{Dop853, OdeSystem};
use stickslip::physics::{ForceLaw, Tilted};

struct Osc;
impl OdeSystem for Osc {
    fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = y[1];
        d[1] = -y[0];
    }
}

struct Junctions {
    c: Vec<f64>,
    law: Tilted,
    m: f64,
    eta: f64,
    k: f64,
    v: f64,
}

impl Junctions {
    fn new(n: usize) -> Self {
        // Deterministic anchors spread over [-2, 2] around the plate.
        let mut s = 0x2545F4914F6CDD1Du64;
        let c = (0..n)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                -2.0 + 4.0 * (s >> 11) as f64 / (1u64 << 53) as f64
            })
            .collect();
        Self { c, law: Tilted { kappa: 0.1, l0: 1.0 }, m: 75.0, eta: 75.0, k: 150.0, v: 0.5 }
    }
}

impl OdeSystem for Junctions {
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        let x = y[0];
        let fb: f64 = self.c.iter().map(|&c| self.law.force_x(x - c)).sum();
        d[0] = y[1];
        d[1] = (-self.eta * y[1] - self.k * (x - self.v * t) - fb) / self.m;
        d[2] = x;
        d[3] = fb;
    }
}

fn bench_osc(c: &mut Criterion) {
    let mut ode = Dop853::new(2, 1e-10, 1e-12).unwrap();
    let (mut t, mut y) = (0.0, [1.0, 0.0]);
    c.bench_function("osc2/free", |b| {
        b.iter(|| {
            ode.step(&mut Osc, &mut t, &mut y, f64::MAX).unwrap();
            black_box(&y);
        })
    });
}

fn bench_junctions(c: &mut Criterion) {
    for n in [300usize, 3000] {
        let mut sys = Junctions::new(n);
        let y0 = [0.0, 0.0, 0.0, 0.0];
        let mut out = [0.0; 4];
        c.bench_function(&format!("junctions/{n}/rhs"), |b| {
            b.iter(|| {
                sys.rhs(black_box(1.0), black_box(&y0), &mut out);
                black_box(&out);
            })
        });
        let mut ode = Dop853::new(4, 1e-10, 1e-12).unwrap();
        let (mut t, mut y) = (0.0, y0);
        c.bench_function(&format!("junctions/{n}/free"), |b| {
            b.iter(|| {
                if t > 200.0 {
                    (t, y) = (0.0, y0);
                    ode.reset();
                }
                ode.step(&mut sys, &mut t, &mut y, f64::MAX).unwrap();
                black_box(&y);
            })
        });
        let mut ode = Dop853::new(4, 1e-10, 1e-12).unwrap();
        let (mut t, mut y) = (0.0, y0);
        c.bench_function(&format!("junctions/{n}/cut"), |b| {
            b.iter(|| {
                if t > 200.0 {
                    (t, y) = (0.0, y0);
                }
                let t_max = t + 0.03;
                while t < t_max {
                    ode.step(&mut sys, &mut t, &mut y, t_max).unwrap();
                }
                ode.reset();
                black_box(&y);
            })
        });
        let st = ode.stats();
        eprintln!(
            "junctions/{n}/cut: {:.3} accepted steps and {:.2} RHS evaluations per 0.03 interval ({st:?})",
            st.accepted as f64 / st.restarts as f64,
            st.rhs_evals as f64 / st.restarts as f64
        );
    }
}

fn config() -> Criterion {
    Criterion::default().sample_size(50).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(3))
}

criterion_group! { name = benches; config = config(); targets = bench_osc, bench_junctions }
criterion_main!(benches);
