//! The exact engine beside a peer, in one criterion run: rebop (the fastest Rust Gillespie
//! library we know) on the junctions aggregated as a two-state system, and the linear law's
//! exact engine on the same junction kinetics with its plate.
//!
//! The peer's system is `N` switches aggregated as two populations, `A` (attached) and `B`
//! (detached), with the reactions `A -> B` at rate `k_off A` and `B -> A` at rate `k_on B`
//! (`k_off = k0`, `k_on = kon0` of the scene): the same jump process as the engine's
//! attached count with strong bonds and `g = 1`, without any continuous state (no plate, no
//! extensions, no statistics). It is as cheap as an exact SSA can be: one exponential, one
//! uniform and two integer updates per event.
//!
//! Rows per `N` (1e3, 1e6, 1e7), all in events per second (criterion's throughput):
//! `peer/rebop-two-state/N`, `peer/strong-linear/N` and `peer/weak-linear/N`
//! (`testkit::scaled_linear`, the scene of `benches/exact.rs`, one engine per row warmed up
//! to `t = 20`, then `1e6 / N` time units per iteration, about 1e5 events), and
//! `peer/strong-linear-run/N`: the same engine as a run drives it, through the runner's loop
//! (`runner::drive` along the scene's output grid, a sample every time unit) feeding the
//! run's own observers (window statistics from `t = 20`, regime detector): what `stickslip
//! run` does between its set-up and its files. After each `N` the bench prints the
//! median events per second of each row over its samples, and the engine's ratio to the
//! peer. It then measures each engine's ratio in *paired rounds*: a fresh engine and a fresh
//! rebop system warmed up to `t = 20`, then [`ROUNDS`] rounds each timing one span of rebop
//! and one of the engine back to back, so that the host's slow and fast spells (other
//! tenants) fall on both sides of each ratio; it prints the median of the rounds' ratios
//! with their quartiles, and the rounds' median rates.
//!
//! ```text
//! cargo bench -p stickslip-peer --bench peer                 # N = 1e3, 1e6, 1e7
//! PEER_N=1e6 cargo bench -p stickslip-peer --bench peer      # N = 1e6 only
//! ```
//!
//! It lives in the workspace member `peer/` (not a default member), so rebop is built only
//! for this command, never by the root's `cargo build` or `cargo test`.

use std::cell::RefCell;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use stickslip::engine::Engine;
use stickslip::engine::exact::{ArrayQueue, strong_linear, weak_linear};
use stickslip::observe::Nothing;
use stickslip::runner::{OutputGrid, core_observers, drive};
use stickslip::scene::{BondKind, ForceLawKind};
use stickslip_testkit::{scaled_linear, scaled_with};

rebop::define_system! {
    k_off k_on;
    TwoState { A, B }
    rupture   : A => B @ k_off
    formation : B => A @ k_on
}

// The same system with a counter of reactions, for the pilot run that counts the events of
// one iteration (the timed system has no counter).
rebop::define_system! {
    k_off k_on;
    Counted { A, B, E }
    rupture   : A => B + E @ k_off
    formation : B => A + E @ k_on
}

/// Simulated time per iteration: about 1e5 events (0.1 events per junction per time unit).
fn span(n: usize) -> f64 {
    1e6 / n as f64
}

/// Warm-up end (the engine's steady state; the two-state system starts stationary).
const WARM: f64 = 20.0;

thread_local! {
    /// Events per second of every timed call, per row.
    static RATES: RefCell<Vec<(String, f64)>> = const { RefCell::new(Vec::new()) };
}

fn record(row: &str, events: f64, elapsed: Duration) {
    RATES.with(|r| r.borrow_mut().push((row.to_string(), events / elapsed.as_secs_f64())));
}

fn median_rate(row: &str) -> f64 {
    let mut v: Vec<f64> = RATES.with(|r| r.borrow().iter().filter(|(k, _)| k == row).map(|&(_, x)| x).collect());
    v.sort_by(f64::total_cmp);
    if v.is_empty() { f64::NAN } else { v[v.len() / 2] }
}

/// The two-state system at stationarity: `A = N kon/(k0 + kon)`.
fn two_state(n: usize, k0: f64, kon: f64, seed: u64) -> TwoState {
    let mut s = TwoState::with_parameters(k0, kon);
    s.seed(seed);
    s.A = (n as f64 * kon / (k0 + kon)).round() as isize;
    s.B = n as isize - s.A;
    s
}

/// The events of one span after the warm-up, counted by a pilot of the two-state system
/// with a counter (the timed system has none).
fn events_per_span(n: usize, k0: f64, kon: f64, seed: u64) -> u64 {
    let mut pilot = Counted::with_parameters(k0, kon);
    pilot.seed(seed);
    pilot.A = (n as f64 * kon / (k0 + kon)).round() as isize;
    pilot.B = n as isize - pilot.A;
    pilot.advance_until(WARM);
    let before = pilot.E;
    pilot.advance_until(WARM + span(n));
    (pilot.E - before) as u64
}

fn rebop_row(c: &mut Criterion, n: usize, k0: f64, kon: f64) {
    let per_span = events_per_span(n, k0, kon, 1);

    let row = format!("rebop-two-state/{n}");
    let mut g = c.benchmark_group("peer");
    g.sample_size(10).measurement_time(Duration::from_secs(6)).warm_up_time(Duration::from_secs(1));
    g.throughput(Throughput::Elements(per_span));
    // One system (and below, one engine) per row, warmed up once: the samples continue it.
    let mut s = two_state(n, k0, kon, 2);
    s.advance_until(WARM);
    let mut t = WARM;
    g.bench_function(BenchmarkId::new("rebop-two-state", n), |b| {
        b.iter_custom(|iters| {
            let start = Instant::now();
            for _ in 0..iters {
                t += span(n);
                s.advance_until(t);
            }
            let elapsed = start.elapsed();
            std::hint::black_box(s.A);
            record(&row, (iters * per_span) as f64, elapsed);
            elapsed
        })
    });
    g.finish();
}

/// The events of one span after the warm-up, counted on a pilot engine.
fn engine_events_per_span<E: Engine>(mut pilot: E, n: usize) -> u64 {
    pilot.advance(WARM, &mut Nothing).unwrap();
    let before = pilot.counters().events.unwrap();
    pilot.advance(WARM + span(n), &mut Nothing).unwrap();
    pilot.counters().events.unwrap() - before
}

/// A row of `per_span` events per iteration: `advance(t)` continues one warmed-up engine to
/// `t` and returns its event count so far (`events` after the warm-up).
fn timed_row(
    c: &mut Criterion,
    name: &str,
    n: usize,
    per_span: u64,
    mut events: u64,
    mut advance: impl FnMut(f64) -> u64,
) {
    let row = format!("{name}/{n}");
    let mut g = c.benchmark_group("peer");
    g.sample_size(10).measurement_time(Duration::from_secs(6)).warm_up_time(Duration::from_secs(1));
    g.throughput(Throughput::Elements(per_span));
    let mut t = WARM;
    g.bench_function(BenchmarkId::new(name, n), |b| {
        b.iter_custom(|iters| {
            let before = events;
            let start = Instant::now();
            for _ in 0..iters {
                t += span(n);
                events = advance(t);
            }
            let elapsed = start.elapsed();
            record(&row, (events - before) as f64, elapsed);
            elapsed
        })
    });
    g.finish();
}

fn engine_row<E: Engine>(c: &mut Criterion, name: &str, n: usize, make: impl Fn() -> E) {
    let per_span = engine_events_per_span(make(), n);
    let mut e = make();
    e.advance(WARM, &mut Nothing).unwrap();
    let events = e.counters().events.unwrap();
    timed_row(c, name, n, per_span, events, |t| {
        e.advance(t, &mut Nothing).unwrap();
        e.counters().events.unwrap()
    });
}

/// The strong-bond engine as a run drives it: the runner's loop ([`drive`]) along the output
/// grid up to each iteration's end, feeding the run's core observers (window from `WARM`).
fn run_row(c: &mut Criterion, n: usize) {
    let scene = scaled_with(n, ForceLawKind::Linear, BondKind::Strong, &["run.t_warmup=20", "run.t_end=1e9"]);
    let per_span = engine_events_per_span(strong_linear::<ArrayQueue>(&scene), n);
    let grid = OutputGrid::new(&scene, None);
    let mut obs = core_observers(&scene);
    let mut e = strong_linear::<ArrayQueue>(&scene);
    drive(&mut e, &OutputGrid { t_end: WARM, ..grid }, &mut obs).unwrap();
    let events = e.counters().events.unwrap();
    timed_row(c, "strong-linear-run", n, per_span, events, |t| {
        drive(&mut e, &OutputGrid { t_end: t, ..grid }, &mut obs).unwrap();
        std::hint::black_box(obs.0.friction_mean());
        e.counters().events.unwrap()
    });
}

/// Rounds of the paired measurement ([`paired`]).
const ROUNDS: usize = 31;

/// `(lower quartile, median, upper quartile)` of `v` (sorted in place).
fn quartiles(v: &mut [f64]) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    (at(0.25), at(0.5), at(0.75))
}

/// The ratio of an engine to rebop in [`ROUNDS`] paired rounds: in each, one span of
/// rebop's two-state system (its events counted by a pilot, [`events_per_span`]) and one
/// span of the engine, timed back to back. Each engine is paired with its own rebop system
/// and with nothing else in between: rebop's state is a few bytes, so the engine's working
/// set stays in the cache from one round to the next, as it does in a long run (another
/// engine's span in between would evict it, and every round would start cold).
fn paired<E: Engine>(n: usize, k0: f64, kon: f64, name: &str, mut e: E) {
    let per_span = events_per_span(n, k0, kon, 3) as f64;
    let mut peer = two_state(n, k0, kon, 4);
    peer.advance_until(WARM);
    e.advance(WARM, &mut Nothing).unwrap();
    let mut t = WARM;
    let (mut ratios, mut peer_rates, mut rates) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..ROUNDS {
        t += span(n);
        let start = Instant::now();
        peer.advance_until(t);
        let peer_rate = per_span / start.elapsed().as_secs_f64();
        std::hint::black_box(peer.A);
        let before = e.counters().events.unwrap();
        let start = Instant::now();
        e.advance(t, &mut Nothing).unwrap();
        let rate = (e.counters().events.unwrap() - before) as f64 / start.elapsed().as_secs_f64();
        ratios.push(rate / peer_rate);
        peer_rates.push(peer_rate);
        rates.push(rate);
    }
    let (lo, mid, hi) = quartiles(&mut ratios);
    let (peer_mid, mid_rate) = (quartiles(&mut peer_rates).1, quartiles(&mut rates).1);
    println!(
        "peer N = {n}: {name} paired over {ROUNDS} rounds: {mid:.3}x rebop (quartiles {lo:.3}, {hi:.3}); \
         medians {:.2} M events/s against rebop's {:.1}",
        mid_rate / 1e6,
        peer_mid / 1e6
    );
}

/// The sizes: `PEER_N` (a comma-separated list, e.g. `PEER_N=1000000`), else 1e3, 1e6, 1e7.
fn sizes() -> Vec<usize> {
    match std::env::var("PEER_N") {
        Ok(s) => s.split(',').map(|x| x.trim().parse::<f64>().expect("PEER_N: numbers") as usize).collect(),
        Err(_) => vec![1_000, 1_000_000, 10_000_000],
    }
}

fn peer(c: &mut Criterion) {
    for n in sizes() {
        let strong = scaled_linear(n, "strong");
        let weak = scaled_linear(n, "weak");
        let (k0, kon) = (strong.junctions.k0, strong.junctions.kon0);
        rebop_row(c, n, k0, kon);
        engine_row(c, "strong-linear", n, || strong_linear::<ArrayQueue>(&strong));
        engine_row(c, "weak-linear", n, || weak_linear::<ArrayQueue>(&weak));
        run_row(c, n);
        let peer = median_rate(&format!("rebop-two-state/{n}"));
        if peer.is_nan() {
            continue; // filtered out by criterion's own filter
        }
        println!("\npeer N = {n}: rebop two-state {:.1} M events/s (median of its samples)", peer / 1e6);
        for name in ["strong-linear", "weak-linear", "strong-linear-run"] {
            let own = median_rate(&format!("{name}/{n}"));
            if !own.is_nan() {
                println!("peer N = {n}: {name} {:.2} M events/s, {:.3}x rebop", own / 1e6, own / peer);
            }
        }
        paired(n, k0, kon, "strong-linear", strong_linear::<ArrayQueue>(&strong));
        paired(n, k0, kon, "weak-linear", weak_linear::<ArrayQueue>(&weak));
        println!();
    }
}

criterion_group!(benches, peer);
criterion_main!(benches);
