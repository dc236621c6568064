//! Estimates of memory, work and outputs before a run, and the refusals they lead to.
//!
//! - the memory estimate (engine state from the structs' sizes, plus a measured baseline of
//!   a run at `N = 10`) is within 25 % of the peak resident set of the binary at
//!   `N = 1e5` and `1e6`, for the fixed engine and the exact engine's closed-form and series
//!   methods, strong and weak bonds (scenes in which every junction passes through both
//!   bags, so the reserved state is all touched); the whole estimate, with the constant
//!   baseline, within 25 % too;
//! - `run` refuses a scene too big for memory or an output too big for the disk in one line
//!   naming the field, exit code 2, no output directory; an allocation that fails anyway
//!   (address space limited under the process) ends in one line, exit code 1, no directory;
//! - `validate` prints the estimates; `sweep` and `compare` use fewer threads, or refuse;
//! - the expected number of events is right in expectation where it is exact (strong bonds
//!   on a kinematic plate): within 5 standard deviations (from the
//!   count's variance, at most twice its mean) of the count of a run.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use stickslip::Scene;
use stickslip::estimate::system::{MEMORY_ENV, REPORT_PEAK_ENV};
use stickslip::estimate::{BASELINE_BYTES, Estimate, available_memory};

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

fn scenario(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios").join(name)
}

fn sets(overrides: &[&str]) -> Vec<String> {
    overrides.iter().flat_map(|o| ["--set".to_string(), o.to_string()]).collect()
}

/// Runs the binary and returns its exit code, stderr and peak resident set in bytes, as the
/// binary reports it (`VmHWM` of its own process: a child's `ru_maxrss` would include the
/// resident set of this test process, which an `exec` carries into it).
fn run_measured(args: &[String]) -> (i32, String, u64) {
    let o = Command::new(BIN)
        .args(args)
        .env("STICKSLIP_PROGRESS", "never")
        .env(REPORT_PEAK_ENV, "1")
        .stdout(Stdio::null())
        .output()
        .expect("the binary runs");
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    let peak = err
        .lines()
        .find_map(|l| l.strip_prefix("peak memory ")?.split(' ').next()?.parse().ok())
        .unwrap_or_else(|| panic!("no peak memory reported: {err}"));
    (o.status.code().unwrap_or(-1), err, peak)
}

/// A scene in which every junction starts attached and ruptures within `t_end` with no
/// re-formation, so both bags (and a weak scene's sum tree) are written in full.
const ALL_RUPTURE: &[&str] = &[
    "run.engine=exact",
    "junctions.initial=attached",
    "junctions.kon0=0",
    "junctions.k0=100",
    "run.t_end=0.06",
    "run.t_warmup=0",
    "output.sample_dt=0.01",
];

fn variant(name: &str) -> Vec<&'static str> {
    let mut v: Vec<&'static str> = match name {
        "fixed" => return vec!["run.t_end=2"],
        _ => ALL_RUPTURE.to_vec(),
    };
    match name {
        "closed-form strong" => v.push("junctions.force_law=linear"),
        "closed-form weak" => v.extend(["junctions.force_law=linear", "junctions.bond=weak"]),
        "series strong" => {}
        "series weak" => v.push("junctions.bond=weak"),
        _ => unreachable!(),
    }
    v
}

#[test]
fn memory_estimates_match_the_measured_peak() {
    let dir = tempfile::tempdir().unwrap();
    let fig1 = scenario("fig1.toml");
    let cases: &[(&str, &[usize])] = &[
        ("fixed", &[100_000, 1_000_000]),
        ("closed-form strong", &[100_000, 1_000_000]),
        ("closed-form weak", &[100_000, 1_000_000]),
        ("series strong", &[100_000]),
        ("series weak", &[100_000]),
    ];
    for (name, ns) in cases {
        let measure = |n: usize| {
            let mut o = variant(name).into_iter().map(String::from).collect::<Vec<_>>();
            o.push(format!("junctions.n={n}"));
            let scene = Scene::from_file(&fig1, &o).unwrap();
            let out = dir.path().join(format!("{name}-{n}"));
            let mut args =
                vec!["run".to_string(), fig1.display().to_string(), "--out".into(), out.display().to_string()];
            args.extend(o.iter().flat_map(|s| ["--set".to_string(), s.clone()]));
            let (code, err, rss) = run_measured(&args);
            assert_eq!(code, 0, "{name} at N = {n}: {err}");
            (Estimate::of(&scene, false), rss)
        };
        let (_, baseline) = measure(10);
        assert!(baseline <= BASELINE_BYTES * 5 / 4, "{name}: a run at N = 10 peaks at {baseline} bytes");
        for &n in *ns {
            let (est, rss) = measure(n);
            let engine = baseline + est.engine_bytes();
            let whole = est.peak_bytes();
            for (what, e) in [("baseline + engine", engine), ("whole estimate", whole)] {
                let rel = (e as f64 - rss as f64) / rss as f64;
                assert!(rel.abs() <= 0.25, "{name} at N = {n}: {what} {e} against measured {rss} ({rel:+.3})");
            }
        }
    }
}

fn stickslip(args: &[String], env: &[(&str, String)]) -> (i32, String, String) {
    let o = Command::new(BIN).args(args).envs(env.iter().map(|(k, v)| (k, v))).output().expect("the binary runs");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

fn run_args(scene: &str, out: &Path, overrides: &[&str]) -> Vec<String> {
    let mut a = vec!["run".into(), scenario(scene).display().to_string(), "--out".into(), out.display().to_string()];
    a.extend(sets(overrides));
    a
}

#[test]
fn runs_too_big_are_refused_in_one_line_leaving_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("deep/out");
    let memory = [
        ("fig1.toml", "junctions.n=4000000000", "junctions.n = 4000000000"),
        ("fig1-exact.toml", "junctions.n=2000000000", "junctions.n = 2000000000"),
    ];
    for (scene, set, named) in memory {
        let (code, stdout, err) = stickslip(&run_args(scene, &out, &[set]), &[]);
        assert_eq!(code, 2, "{err}");
        assert!(stdout.is_empty());
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(named) && err.contains("of memory") && err.contains("available"), "{err}");
        assert!(!dir.path().join("deep").exists(), "a refused run leaves no directory");
    }
    // 1e6 junctions, events written over 1e8 time units: about 1e13 rows.
    let disk = ["junctions.n=1000000", "output.events=true", "run.t_end=1e8", "output.sample_dt=1e6"];
    let (code, _, err) = stickslip(&run_args("fig1-exact.toml", &out, &disk), &[]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: output.events: the outputs need an estimated") && err.contains("free at"), "{err}");
    assert!(!dir.path().join("deep").exists());
    // The cap from the environment counts as available memory.
    let env = [(MEMORY_ENV, (1u64 << 20).to_string())];
    let (code, _, err) = stickslip(&run_args("fig1.toml", &out, &[]), &env);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("junctions.n = 300") && err.contains(MEMORY_ENV), "{err}");
}

/// The address space of the child is limited below what the scene needs, while the memory
/// check (which reads `MemAvailable`) lets it start: the allocation fails inside the engine.
#[test]
fn a_failed_allocation_ends_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let n = 40_000_000usize; // the fixed engine: 360 MB; the exact engine: 1.6 GB
    let need =
        Estimate::of(&Scene::from_file(&scenario("fig1-exact.toml"), &[format!("junctions.n={n}")]).unwrap(), false);
    let free = available_memory().map_or(0, |a| a.bytes);
    assert!(
        free > need.peak_bytes(),
        "this test needs {} bytes of free memory, {free} are available",
        need.peak_bytes()
    );
    for scene in ["fig1.toml", "fig1-exact.toml"] {
        let out = dir.path().join("a/b");
        let mut cmd = Command::new(BIN);
        // A step well inside the plate's stability limit, and a generator whose period no
        // run reaches: no warning before the error.
        cmd.args(run_args(scene, &out, &[&format!("junctions.n={n}"), "fixed.dt=0.001", "fixed.rng=pcg"]));
        // SAFETY: setrlimit is async-signal-safe; nothing else runs between fork and exec.
        unsafe {
            use std::os::unix::process::CommandExt;
            cmd.pre_exec(|| {
                let lim = libc::rlimit { rlim_cur: 300 << 20, rlim_max: 300 << 20 };
                if libc::setrlimit(libc::RLIMIT_AS, &lim) == 0 { Ok(()) } else { Err(std::io::Error::last_os_error()) }
            });
        }
        let o = cmd.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{scene}: {err}");
        assert_eq!(err.lines().count(), 1, "{scene}: {err}");
        assert!(
            err.starts_with("error: out of memory: cannot allocate") && err.contains(&format!("junctions.n = {n}")),
            "{err}"
        );
        assert!(!dir.path().join("a").exists(), "{scene}: a failed run leaves no directory");
    }
}

#[test]
fn validate_prints_the_estimates() {
    let args = vec![
        "validate".to_string(),
        scenario("fig1-exact.toml").display().to_string(),
        "--set".into(),
        "junctions.n=1000000".into(),
    ];
    let (code, out, err) = stickslip(&args, &[]);
    assert_eq!(code, 0, "{err}");
    let est: Vec<&str> = out.lines().filter(|l| l.starts_with("# estimate:")).collect();
    assert_eq!(est.len(), 4, "{out}");
    assert!(
        est[0].contains("peak memory") && est[0].contains("44.0 B per junction") && est[0].contains("N = 1000000"),
        "{}",
        est[0]
    );
    assert!(est[1].contains("memory available"));
    assert!(est[2].contains("junction events expected"));
    assert!(est[3].contains("trace.csv") && est[3].contains("summary.json") && est[3].contains("free on the disk"));
}

#[test]
fn studies_use_fewer_threads_or_refuse() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scenario("fig2.toml");
    let n = 1_000_000usize;
    let est = Estimate::of(&Scene::from_file(&scene, &[format!("junctions.n={n}")]).unwrap(), false);
    let sweep = |avail: u64, out: &str| {
        let args: Vec<String> = [
            "sweep",
            scene.to_str().unwrap(),
            "--param",
            "plate.v",
            "--values",
            "0.1,1",
            "--threads",
            "4",
            "--set",
            &format!("junctions.n={n}"),
            "--set",
            "run.t_end=0.5",
            "--set",
            "run.t_warmup=0",
            "--out",
            dir.path().join(out).to_str().unwrap(),
        ]
        .map(String::from)
        .to_vec();
        stickslip(&args, &[(MEMORY_ENV, avail.to_string())])
    };
    // Room for two runs and a half: two threads.
    let (code, stdout, err) = sweep(BASELINE_BYTES + est.run_bytes() * 5 / 2, "two");
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("the sweep uses 2 worker threads instead of 4"), "{err}");
    assert!(stdout.contains("on 2 threads"), "{stdout}");
    // No room for one: refused, nothing written.
    let (code, _, err) = sweep(BASELINE_BYTES + est.run_bytes() / 2, "none");
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(&format!("junctions.n = {n}")), "{err}");
    assert!(!dir.path().join("none").exists());
    // compare counts its largest run the same way.
    let args: Vec<String> = [
        "compare",
        scene.to_str().unwrap(),
        "--set",
        &format!("junctions.n={n}"),
        "--set",
        "fixed.rng=pcg",
        "--dts",
        "0.5",
        "--replicas",
        "2",
        "--threads",
        "3",
        "--out",
        dir.path().join("cmp").to_str().unwrap(),
    ]
    .map(String::from)
    .to_vec();
    let (code, _, err) = stickslip(&args, &[(MEMORY_ENV, (BASELINE_BYTES + est.run_bytes() / 2).to_string())]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(&format!("junctions.n = {n}")) && err.lines().count() == 1, "{err}");
    assert!(!dir.path().join("cmp").exists());
}

/// Strong bonds on a kinematic plate are two-state chains with constant rates: the
/// expected count is exact, and the count's variance is at most twice its mean (for
/// alternating exponential durations of rates `a`, `b` the count of transitions has the
/// Fano factor `2 (a^2 + b^2) / (a + b)^2 <= 2`; junctions are independent).
#[test]
fn expected_events_are_right_where_the_rates_are_constant() {
    for initial in ["detached", "attached", "stationary"] {
        let o: Vec<String> = [
            "run.engine=exact",
            "plate.kinematic=true",
            "plate.v=0.7",
            "junctions.n=2000",
            "junctions.k0=0.3",
            "junctions.kon0=0.2",
            "run.t_end=20",
            "run.t_warmup=0",
            "run.seed=7",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain([format!("junctions.initial={initial}")])
        .collect();
        let scene = Scene::from_file(&scenario("fig1.toml"), &o).unwrap();
        let expected = Estimate::of(&scene, false).work.events;
        let got = stickslip::runner::run_scene(&scene, None).unwrap().counters.events.unwrap() as f64;
        let sd = (2.0 * expected).sqrt();
        assert!((got - expected).abs() <= 5.0 * sd, "{initial}: {got} events, expected {expected} +- {sd}");
    }
}
