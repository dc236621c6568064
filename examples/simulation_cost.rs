//! Instruction counts of the `runner::Simulation` handle against the engine it erases: the
//! same work done directly on the engine as a local variable (`direct`) or behind a pointer
//! (`direct-boxed`), or through the handle (`handle`), for a count under callgrind (figures
//! and commands in docs/performance.md, "The Simulation handle"):
//!
//! ```sh
//! cargo build --profile perf --example simulation_cost
//! for w in fixed exact; do for h in direct direct-boxed handle; do
//!   valgrind --tool=callgrind --callgrind-out-file=/dev/null target/perf/examples/simulation_cost $w $h
//! done; done
//! ```
//!
//! `fixed`: the fixed engine at `N = 1000`, 20 000 advances of one step each, no observers
//! (the most calls per unit of work). `exact`: the exact engine at `N = 1e5` (strong bonds,
//! linear law) feeding the core observers, 200 advances of about 1e4 events each.

use stickslip::Scene;
use stickslip::runner::{Observed, Simulation, core_observers};
use stickslip_testkit::{Concrete, fig1_with, scaled_linear};

/// The work: advances of `span` from `t = 0`, with or without the core observers.
#[derive(Clone, Copy)]
struct Work<'a> {
    scene: &'a Scene,
    span: f64,
    advances: u32,
    core: bool,
}

/// Advances the engine directly (the test kit's [`Concrete`]), as a local variable or
/// (`boxed`) behind a pointer the optimiser cannot see through, as behind a handle.
fn direct(w: Work, boxed: bool) -> f64 {
    Concrete { scene: w.scene, warm: 0.0, span: w.span, advances: w.advances.into(), core: w.core, boxed }
        .run()
        .friction
}

fn handle(w: Work) -> f64 {
    let mut sim = Simulation::new(w.scene).unwrap();
    let mut core = core_observers(w.scene);
    for k in 1..=w.advances {
        let t = k as f64 * w.span;
        if w.core {
            sim.advance_observed(t, Observed::Core(&mut core)).unwrap();
        } else {
            sim.advance(t).unwrap();
        }
    }
    sim.sample().friction
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: simulation_cost (fixed|exact) (direct|direct-boxed|handle)";
    let (Some(which), Some(how)) = (args.first(), args.get(1)) else {
        eprintln!("{usage}");
        std::process::exit(2);
    };
    let scene = match which.as_str() {
        "fixed" => fig1_with(&["junctions.n=1000", "junctions.kappa=0.03", "fixed.dt=0.1", "run.t_end=1e9"]),
        "exact" => scaled_linear(100_000, "strong"),
        _ => {
            eprintln!("{usage}");
            std::process::exit(2);
        }
    };
    let work = match which.as_str() {
        "fixed" => Work { scene: &scene, span: 0.1, advances: 20_000, core: false },
        _ => Work { scene: &scene, span: 1.0, advances: 200, core: true },
    };
    let friction = match how.as_str() {
        "direct" => direct(work, false),
        "direct-boxed" => direct(work, true),
        "handle" => handle(work),
        _ => {
            eprintln!("{usage}");
            std::process::exit(2);
        }
    };
    // The same work gives the same state: print it so that both can be compared.
    println!("{which} {how}: friction at the end {friction}");
}
