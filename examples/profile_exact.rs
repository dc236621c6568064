//! A plain binary around the exact engine for profilers (`perf`, `valgrind --tool=callgrind`)
//! and whole-process timings, on the benchmark's scene (`testkit::scaled_linear`): warms up to
//! `t = 20`, then advances by `SPAN` time units and prints the events per second of that part.
//! Speed figures belong to `cargo bench --bench exact`; this is for looking inside.
//!
//! ```text
//! cargo build --profile perf --example profile_exact
//! target/perf/examples/profile_exact strong 1000000 100          # engine alone
//! target/perf/examples/profile_exact weak 1000000 50 --stats     # with the run's statistics
//! target/perf/examples/profile_exact weak-tree 1000000 50        # weak bonds from a sum tree
//! /usr/bin/time -v target/perf/examples/profile_exact strong 100000000 1   # N = 1e8 (about 4 GB)
//! valgrind --tool=callgrind target/perf/examples/profile_exact strong 1000000 10
//! ```

use std::time::Instant;

use stickslip::Scene;
use stickslip::engine::Engine;
use stickslip::engine::exact::{ArrayQueue, strong_linear, weak_linear, weak_linear_tree};
use stickslip::observe::{Nothing, Observer};
use stickslip::runner::core_observers;
use stickslip_testkit::scaled_linear;

const USAGE: &str = "usage: profile_exact strong|weak|weak-tree N SPAN [--stats]";

/// Warm-up to `t = 20`, then `span` more: `(events, seconds)` of the second part. Prints
/// the warm-up's wall time.
fn time<E: Engine, O: Observer>(mut engine: E, obs: &mut O, span: f64) -> (u64, f64) {
    let warm = std::time::Instant::now();
    engine.advance(20.0, obs).expect("warm-up runs");
    eprintln!("warm-up to t = 20: {:.2} s", warm.elapsed().as_secs_f64());
    let before = engine.counters().events.expect("the exact engine counts events");
    let candidates_before = engine.counters().candidates.unwrap_or(0);
    let start = std::time::Instant::now();
    engine.advance(20.0 + span, obs).expect("the run finishes");
    let seconds = start.elapsed().as_secs_f64();
    let c = engine.counters();
    let (events, candidates) = (c.events.unwrap_or(0) - before, c.candidates.unwrap_or(0) - candidates_before);
    eprintln!("candidates per event: {:.3}", candidates as f64 / events.max(1) as f64);
    (engine.counters().events.expect("the exact engine counts events") - before, seconds)
}

/// Prints the set-up time (since `setup`), then [`time`]s `engine` with the run's observers
/// (`stats`) or none.
fn measure<E: Engine>(engine: E, scene: &Scene, stats: bool, setup: Instant, span: f64) -> (u64, f64) {
    eprintln!("set-up: {:.2} s", setup.elapsed().as_secs_f64());
    if stats { time(engine, &mut core_observers(scene), span) } else { time(engine, &mut Nothing, span) }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (bond, n, span) = match args.as_slice() {
        [b, n, s, ..] if ["strong", "weak", "weak-tree"].contains(&b.as_str()) => {
            match (n.parse::<usize>(), s.parse::<f64>()) {
                (Ok(n), Ok(s)) if n > 0 && s > 0.0 => (b.as_str(), n, s),
                _ => {
                    eprintln!("{USAGE}");
                    std::process::exit(2);
                }
            }
        }
        _ => {
            eprintln!("{USAGE}");
            std::process::exit(2);
        }
    };
    let stats = args.iter().any(|a| a == "--stats");
    let scene = scaled_linear(n, if bond == "strong" { "strong" } else { "weak" });
    // Set-up: the engine built (junction buffers and the initial state drawn).
    let setup = Instant::now();
    let (events, seconds) = match bond {
        "strong" => measure(strong_linear::<ArrayQueue>(&scene), &scene, stats, setup, span),
        "weak-tree" => measure(weak_linear_tree::<ArrayQueue>(&scene), &scene, stats, setup, span),
        _ => measure(weak_linear::<ArrayQueue>(&scene), &scene, stats, setup, span),
    };
    println!("{bond} N = {n}: {events} events in {seconds:.3} s = {:.3} M events/s", events as f64 / seconds / 1e6);
}
