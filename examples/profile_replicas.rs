//! Timing of whole replicas of a scene, as the work-precision study (`stickslip compare`)
//! runs them: `REPLICAS` runs of `SCENE` through `runner::run_scene_with` with seeds 1, 2,
//! .., no output files, each with its set-up, its summary and its regime verdict. Prints
//! the mean wall time per replica and the mean `friction_mean` (a check that two builds ran
//! the same thing). Extra arguments are scene overrides (`run.engine=exact`,
//! `fixed.dt=0.5`). Cost figures belong to the study itself; this is for profilers.
//!
//! ```text
//! cargo build --profile perf --example profile_replicas
//! target/perf/examples/profile_replicas scenarios/fig1.toml 400 run.engine=exact
//! valgrind --tool=cachegrind --cache-sim=no target/perf/examples/profile_replicas scenarios/fig1.toml 40 fixed.dt=0.5
//! ```

use stickslip::Scene;
use stickslip::runner::{RunOptions, run_scene_with};

const USAGE: &str = "usage: profile_replicas SCENE REPLICAS [section.key=value ...]";

fn usage() -> ! {
    eprintln!("{USAGE}");
    std::process::exit(2)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (path, reps) = match args.as_slice() {
        [p, r, ..] => (p.clone(), r.parse::<u64>().ok().filter(|&r| r > 0).unwrap_or_else(|| usage())),
        _ => usage(),
    };
    let base = match Scene::from_file(std::path::Path::new(&path), &args[2..]) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let scenes: Vec<Scene> = (1..=reps)
        .map(|seed| base.with_overrides(&[format!("run.seed={seed}")]).expect("a seed from 1 is valid"))
        .collect();
    let start = std::time::Instant::now();
    let mut friction = 0.0;
    for scene in &scenes {
        match run_scene_with(scene, None, &RunOptions::default()) {
            Ok(s) => friction += s.friction_mean,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(1);
            }
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "{reps} replicas of {path}: {:.4} ms per replica, mean friction_mean {:.6}",
        seconds / reps as f64 * 1e3,
        friction / reps as f64
    );
}
