//! A plain binary around the exact engine for profilers (`perf`, `valgrind --tool=callgrind`)
//! and whole-process timings, on the benchmark's scene (`testkit::scaled_linear`): warms up to
//! `t = 20`, then advances by `SPAN` time units and prints the events per second of that part.
//! Speed figures belong to `cargo bench --bench exact`; this is for looking inside.
//!
//! ```text
//! cargo build --profile perf --example profile_exact
//! target/perf/examples/profile_exact strong 1000000 100          # engine alone
//! target/perf/examples/profile_exact weak 1000000 50 --stats     # with the run's statistics
//! valgrind --tool=callgrind target/perf/examples/profile_exact strong 1000000 10
//! ```

use stickslip::engine::Engine;
use stickslip::engine::exact::{ArrayQueue, strong_linear, weak_linear};
use stickslip::observe::{Nothing, Observer};
use stickslip::runner::core_observers;
use stickslip_testkit::scaled_linear;

const USAGE: &str = "usage: profile_exact strong|weak N SPAN [--stats]";

/// Warm-up to `t = 20`, then `span` more: `(events, seconds)` of the second part.
fn time<E: Engine, O: Observer>(mut engine: E, obs: &mut O, span: f64) -> (u64, f64) {
    engine.advance(20.0, obs).expect("warm-up runs");
    let before = engine.counters().events.expect("the exact engine counts events");
    let start = std::time::Instant::now();
    engine.advance(20.0 + span, obs).expect("the run finishes");
    let seconds = start.elapsed().as_secs_f64();
    (engine.counters().events.expect("the exact engine counts events") - before, seconds)
}

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
    let stats = args.iter().any(|a| a == "--stats");
    let scene = scaled_linear(n, bond);
    let (events, seconds) = match (bond, stats) {
        ("strong", false) => time(strong_linear::<ArrayQueue>(&scene), &mut Nothing, span),
        ("strong", true) => time(strong_linear::<ArrayQueue>(&scene), &mut core_observers(&scene), span),
        (_, false) => time(weak_linear::<ArrayQueue>(&scene), &mut Nothing, span),
        (_, true) => time(weak_linear::<ArrayQueue>(&scene), &mut core_observers(&scene), span),
    };
    println!("{bond} N = {n}: {events} events in {seconds:.3} s = {:.3} M events/s", events as f64 / seconds / 1e6);
}
