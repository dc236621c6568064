//! Timing of the tilted law's exact engine (the engine the scene selects: `exact.tilted =
//! "series"` by default) on the scaled Fig. 1 scene (`testkit::scaled_tilted`, `testkit::scaled_with`): warms up to
//! `t = 20`, then advances by `SPAN` time units and prints the events per second of that part.
//! Extra arguments are scene overrides (`plate.k=1e9`). Speed figures belong to
//! `cargo bench --bench exact -- tilted`; this is for profilers and quick looks.
//!
//! ```text
//! cargo build --profile perf --example profile_tilted
//! target/perf/examples/profile_tilted strong 1000000 10
//! target/perf/examples/profile_tilted weak 1000 100 plate.k=1e9 plate.mass=1e-6 plate.eta=100
//! ```

use stickslip::runner::Simulation;
use stickslip::scene::ForceLawKind;
use stickslip_testkit::{bond_named, scaled_with};

const USAGE: &str = "usage: profile_tilted strong|weak N SPAN [section.key=value ...]";

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (bond, n, span) = match args.as_slice() {
        [b, n, s, ..] if b == "strong" || b == "weak" => match (n.parse::<usize>(), s.parse::<f64>()) {
            (Ok(n), Ok(s)) if n > 0 && s > 0.0 => (b.as_str(), n, s),
            _ => {
                eprintln!("{USAGE}");
                std::process::exit(2);
            }
        },
        _ => {
            eprintln!("{USAGE}");
            std::process::exit(2);
        }
    };
    let overrides: Vec<&str> = args[3..].iter().map(String::as_str).collect();
    let scene = scaled_with(n, ForceLawKind::Tilted, bond_named(bond).expect("strong or weak"), &overrides);
    let mut sim = Simulation::new(&scene).expect("the scene runs");
    sim.advance(20.0).expect("warm-up runs");
    let c0 = sim.counters();
    let start = std::time::Instant::now();
    sim.advance(20.0 + span).expect("the run finishes");
    let seconds = start.elapsed().as_secs_f64();
    let c1 = sim.counters();
    let events = c1.events.unwrap_or(0) - c0.events.unwrap_or(0);
    let steps = c1.ode_steps.unwrap_or(0) - c0.ode_steps.unwrap_or(0);
    println!(
        "{bond} N = {n}: {events} events in {seconds:.3} s = {:.3} M events/s; {steps} plate steps, {} series re-basings, series error {:.1e}",
        events as f64 / seconds / 1e6,
        c1.series_rebases.unwrap_or(0) - c0.series_rebases.unwrap_or(0),
        c1.series_error.unwrap_or(0.0)
    );
}
