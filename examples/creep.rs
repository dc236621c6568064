//! Low-velocity creep with weak bonds (`scenarios/creep.toml`): what the exact engine costs
//! against the fixed-step engine over the same simulated time, and the friction's growth
//! with the logarithm of the driving velocity, against the thermally activated (Bell)
//! theory of `stickslip_testkit::creep`.
//!
//! ```sh
//! cargo run --profile perf --example creep              # everything (about a minute of CPU)
//! cargo run --profile perf --example creep -- --replicas 8 --threads 2
//! ```
//!
//! Prints Markdown tables on stdout. Seeds: replica `r` of velocity point `k` uses
//! `stickslip::studies::seeds::pcg_seed(run.seed, Exact, k, r)`, so the tables do not depend
//! on the number of threads (the timing columns aside).

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;
use stickslip::output::Summary;
use stickslip::studies::compare::thread_cpu_seconds;
use stickslip::studies::format::sig;
use stickslip::studies::seeds::{Role, pcg_seed};
use stickslip::studies::stats::mean_ci95 as mean_ci;
use stickslip::{Scene, run_scene};
use stickslip_testkit::creep::theory;

struct Args {
    replicas: usize,
    threads: usize,
    skip_fixed: bool,
}

fn args() -> Args {
    let mut a = Args { replicas: 8, threads: 0, skip_fixed: false };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut num = |name: &str| -> usize {
            let v = it.next().unwrap_or_else(|| die(&format!("{name}: a value is required")));
            v.parse().unwrap_or_else(|_| die(&format!("{name} = {v:?}: must be a whole number")))
        };
        match k.as_str() {
            "--replicas" => a.replicas = num("--replicas"),
            "--threads" => a.threads = num("--threads"),
            "--skip-fixed" => a.skip_fixed = true,
            other => die(&format!("unknown argument {other:?} (allowed: --replicas N, --threads N, --skip-fixed)")),
        }
    }
    if a.replicas < 2 {
        die(&format!("--replicas = {}: must be at least 2", a.replicas));
    }
    a
}

fn die(m: &str) -> ! {
    eprintln!("error: {m}");
    std::process::exit(2)
}

/// Runs a scene; returns its summary, wall and CPU seconds.
fn timed(scene: &Scene) -> (Summary, f64, f64) {
    let c0 = thread_cpu_seconds();
    let t0 = Instant::now();
    let s = run_scene(scene, None).unwrap_or_else(|e| die(&format!("{}: {e}", scene.name)));
    (s, t0.elapsed().as_secs_f64(), thread_cpu_seconds() - c0)
}

fn with(scene: &Scene, o: &[String]) -> Scene {
    scene.with_overrides(o).unwrap_or_else(|e| die(&e.to_string()))
}

fn main() {
    let a = args();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(a.threads).build().expect("thread pool");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/creep.toml");
    let base = Scene::from_file(&path, &[]).unwrap_or_else(|e| die(&e.to_string()));
    let quiet = with(&base, &["output.trace=false".into()]);
    let n = base.junctions.n as f64;

    // (a) Cost against simulated time.
    println!("## Cost: exact engine against simulated time (V = {})\n", base.plate.v);
    println!("| t_end | events | wall s | cpu s | cpu ns per event |");
    println!("| --- | --- | --- | --- | --- |");
    for t_end in [1e9, 1e10, 1e11] {
        let s = with(&quiet, &[format!("run.t_end={t_end:e}"), format!("run.t_warmup={:e}", 0.2 * t_end)]);
        let (sum, wall, cpu) = timed(&s);
        let ev = sum.counters.events.unwrap_or(0);
        println!("| {t_end:e} | {ev} | {} | {} | {} |", sig(wall, 3), sig(cpu, 3), sig(cpu * 1e9 / ev as f64, 3));
    }
    if !a.skip_fixed {
        println!("\n## Cost: fixed-step engine, dt = {} (measured, then extrapolated)\n", base.fixed.dt);
        println!(
            "| t_end | steps | wall s | cpu s | cpu ns per junction-step | cpu s extrapolated to t_end = {:e} |",
            base.run.t_end
        );
        println!("| --- | --- | --- | --- | --- | --- |");
        for t_end in [1e5, 1e6] {
            let s = with(
                &quiet,
                &["run.engine=fixed".into(), format!("run.t_end={t_end:e}"), format!("run.t_warmup={:e}", 0.2 * t_end)],
            );
            let (sum, wall, cpu) = timed(&s);
            let steps = sum.counters.steps.unwrap_or(0) as f64;
            println!(
                "| {t_end:e} | {steps} | {} | {} | {} | {} |",
                sig(wall, 3),
                sig(cpu, 3),
                sig(cpu * 1e9 / (steps * n), 3),
                sig(cpu * base.run.t_end / t_end, 3)
            );
        }
    }

    // (b) Velocity sweep: t_end = 2000 / (kappa V), about 150 to 500 junction lifetimes.
    let vs: Vec<f64> = (0..9).map(|k| 10f64.powf(-7.0 + 0.5 * k as f64)).collect();
    println!("\n## Velocity sweep, exact engine, {} replicas per velocity\n", a.replicas);
    println!(
        "| V | t_end | events per replica | cpu s per replica | rupture force | Bell theory | friction per junction | theory |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut fit = Vec::new();
    for (k, &v) in vs.iter().enumerate() {
        let t_end = 2000.0 / (base.junctions.kappa * v);
        let s = with(
            &quiet,
            &[format!("plate.v={v:e}"), format!("run.t_end={t_end:e}"), format!("run.t_warmup={:e}", 0.2 * t_end)],
        );
        let th = theory(&s);
        let runs: Vec<(Summary, f64, f64)> = pool.install(|| {
            (0..a.replicas)
                .into_par_iter()
                .map(|r| {
                    let mut s = s.clone();
                    s.run.seed = pcg_seed(base.run.seed, Role::Exact, k as u64, r as u64);
                    timed(&s)
                })
                .collect()
        });
        let rf: Vec<f64> = runs.iter().map(|r| r.0.rupture_force_mean.unwrap_or(f64::NAN)).collect();
        let fr: Vec<f64> = runs.iter().map(|r| r.0.friction_per_junction).collect();
        let events = runs.iter().map(|r| r.0.counters.events.unwrap_or(0) as f64).sum::<f64>() / runs.len() as f64;
        let cpu = runs.iter().map(|r| r.2).sum::<f64>() / runs.len() as f64;
        let (rfm, rfh) = mean_ci(&rf);
        let (frm, frh) = mean_ci(&fr);
        println!(
            "| {} | {} | {} | {} | {} +- {} | {} | {} +- {} | {} |",
            sig(v, 2),
            sig(t_end, 2),
            sig(events, 3),
            sig(cpu, 2),
            sig(rfm, 5),
            sig(rfh, 2),
            sig(th.rupture_force, 5),
            sig(frm, 5),
            sig(frh, 2),
            sig(th.friction_per_junction, 5)
        );
        fit.push((v.ln(), rfm, rfh, frm, frh, th.rupture_force, th.friction_per_junction));
    }
    // Weighted least-squares slopes against ln V, with 95 % intervals from the points' intervals.
    let slope = |pts: &[(f64, f64, f64)]| -> (f64, f64) {
        let w: Vec<f64> = pts.iter().map(|p| 1.0 / (p.2 * p.2)).collect();
        let sw: f64 = w.iter().sum();
        let xm = pts.iter().zip(&w).map(|(p, w)| w * p.0).sum::<f64>() / sw;
        let ym = pts.iter().zip(&w).map(|(p, w)| w * p.1).sum::<f64>() / sw;
        let sxx: f64 = pts.iter().zip(&w).map(|(p, w)| w * (p.0 - xm).powi(2)).sum();
        let sxy: f64 = pts.iter().zip(&w).map(|(p, w)| w * (p.0 - xm) * (p.1 - ym)).sum();
        // The points' half-widths are 95 % ones: the slope's is 1/sqrt(sxx) on that scale.
        (sxy / sxx, 1.0 / sxx.sqrt())
    };
    let (s_rf, h_rf) = slope(&fit.iter().map(|p| (p.0, p.1, p.2)).collect::<Vec<_>>());
    let (s_fr, h_fr) = slope(&fit.iter().map(|p| (p.0, p.3, p.4)).collect::<Vec<_>>());
    // The theory's slopes by the same fit (same points and weights).
    let (t_rf, _) = slope(&fit.iter().map(|p| (p.0, p.5, p.2)).collect::<Vec<_>>());
    let (t_fr, _) = slope(&fit.iter().map(|p| (p.0, p.6, p.4)).collect::<Vec<_>>());
    println!(
        "\nSlopes against ln V (weighted least squares, 95 % intervals; the theory's values fitted the same way): \
         rupture force {} +- {} (theory {}; f_b = {}), friction per junction {} +- {} (theory {}; f_b / 2 = {}).",
        sig(s_rf, 4),
        sig(h_rf, 2),
        sig(t_rf, 4),
        sig(1.0 / base.junctions.beta_dx(), 3),
        sig(s_fr, 4),
        sig(h_fr, 2),
        sig(t_fr, 4),
        sig(0.5 / base.junctions.beta_dx(), 3)
    );
}
