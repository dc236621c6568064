//! Long runs (docs/runs.md): a run killed with SIGKILL after it wrote a checkpoint and
//! continued with `stickslip resume` gives the same `trace.csv` and `events.csv`, byte for
//! byte, and the same `summary.json` apart from `wall_seconds`, as an uninterrupted run
//! with the same seed; for the fixed engine and the exact engine (linear law with strong
//! and weak bonds, tilted law), and for kinematic plates and a thermally activated scene. Also: the progress display changes nothing, a finished run
//! is not resumed, and bad `resume` inputs and bad `--checkpoint-every` values are refused
//! with one line and exit code 2, with nothing changed on disk, as is a `resume` when less
//! memory is available than the run needs. A new run first removes every file an earlier
//! run left in its directory, and nothing else: one that fails, is killed before its first
//! checkpoint or writes fewer files leaves none of the earlier run's.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use stickslip::estimate::system::MEMORY_ENV;
use stickslip_testkit::FIG1;

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");
/// Checkpoint interval of the killed runs (seconds of wall time).
const EVERY: &str = "0.05";

/// A scene for the kill-and-resume test: the letter's Fig. 1 with overrides, and the
/// first `t_end` to try (doubled while the run ends before it can be killed).
struct Case {
    name: &'static str,
    /// Overrides shared by several cases, applied before `sets`.
    base: &'static [&'static str],
    sets: &'static [&'static str],
    t_end: f64,
}

/// The letter's Fig. 1 scaled to `N = 1e5` (`K = N/2`, `M = eta = N/4`, stationary start),
/// where weak bonds draw their rupture candidates from bins (`BINNED_FROM`).
const SCALED_1E5: &[&str] = &[
    "junctions.bond=weak",
    "junctions.n=100000",
    "plate.k=50000",
    "plate.mass=25000",
    "plate.eta=25000",
    "junctions.initial=stationary",
    "run.t_warmup=1",
];

const FIXED: Case = Case {
    name: "fixed (tilted law, weak bonds, Park-Miller)",
    base: &[],
    sets: &["junctions.bond=weak", "fixed.dt=0.2", "output.events=false"],
    t_end: 20000.0,
};
const LINEAR_STRONG: Case = Case {
    name: "exact, linear law, strong bonds, events.csv",
    base: &[],
    sets: &["run.engine=exact", "junctions.force_law=linear", "output.events=true", "run.t_warmup=100"],
    t_end: 4000.0,
};
const LINEAR_WEAK: Case = Case {
    name: "exact, linear law, weak bonds",
    base: &[],
    sets: &["run.engine=exact", "junctions.force_law=linear", "junctions.bond=weak", "run.t_warmup=100"],
    t_end: 20000.0,
};
/// Weak bonds with the linear law at `N = 1e5`, whose rupture candidates come from bins
/// (`BINNED_FROM`): the bins, their tickets drawn ahead and running sums go through the
/// checkpoint.
const LINEAR_WEAK_BINS: Case = Case {
    name: "exact, linear law, weak bonds, N = 1e5 (bins)",
    base: SCALED_1E5,
    sets: &["run.engine=exact", "junctions.force_law=linear"],
    t_end: 20.0,
};
const TILTED: Case = Case {
    name: "exact, tilted law, weak bonds, events.csv",
    base: &[],
    sets: &["run.engine=exact", "junctions.bond=weak", "output.events=true", "run.t_warmup=10"],
    t_end: 300.0,
};
/// Weak bonds with the tilted law at `N = 1e5`: rupture candidates from bins (`BINNED_FROM`)
/// and formations' picks drawn ahead (`PREFETCH_MIN_N`), both through the checkpoint.
const TILTED_WEAK_LARGE: Case = Case {
    name: "exact, tilted law, weak bonds, N = 1e5 (bins, formations drawn ahead)",
    base: SCALED_1E5,
    sets: &["run.engine=exact"],
    t_end: 20.0,
};
const TILTED_KINEMATIC: Case = Case {
    name: "exact, tilted law (series), kinematic plate, weak bonds, events.csv",
    base: &[],
    sets: &["run.engine=exact", "junctions.bond=weak", "plate.kinematic=true", "output.events=true", "run.t_warmup=10"],
    t_end: 2000.0,
};

const KINEMATIC_EXACT: Case = Case {
    name: "exact, linear law, weak bonds, kinematic plate, events.csv",
    base: &[],
    sets: &[
        "run.engine=exact",
        "junctions.force_law=linear",
        "junctions.bond=weak",
        "plate.kinematic=true",
        "output.events=true",
        "run.t_warmup=100",
    ],
    t_end: 20000.0,
};
const KINEMATIC_FIXED: Case = Case {
    name: "fixed (tilted law, weak bonds), kinematic plate",
    base: &[],
    sets: &["junctions.bond=weak", "plate.kinematic=true", "fixed.dt=0.2", "output.events=false"],
    t_end: 20000.0,
};
/// Temperature as an input (docs/model.md, "Temperature"): the checkpoint's scene holds
/// the values in force and the reference values, and the resumed run goes on with them.
const THERMAL: Case = Case {
    name: "exact, linear law, weak bonds, thermally activated at T = 1.4",
    base: &[],
    sets: &[
        "run.engine=exact",
        "junctions.force_law=linear",
        "junctions.bond=weak",
        "junctions.temperature=1.4",
        "junctions.e_off=2",
        "junctions.e_on=1",
        "junctions.kappa_slope=-0.1",
        "plate.k_slope=0.2",
        "plate.eta_slope=-0.1",
        "run.t_warmup=100",
    ],
    t_end: 20000.0,
};

fn scene_args(dir: &Path, case: &Case, t_end: f64) -> Vec<String> {
    let scene = dir.join("scene.toml");
    if !scene.exists() {
        std::fs::write(&scene, FIG1).unwrap();
    }
    let mut a = vec![scene.to_str().unwrap().to_string()];
    for s in case.base.iter().chain(case.sets).map(|s| s.to_string()).chain([format!("run.t_end={t_end}")]) {
        a.push("--set".into());
        a.push(s);
    }
    a
}

fn run(args: &[String], envs: &[(&str, &str)]) -> Output {
    let mut c = Command::new(BIN);
    c.args(args).env_remove("STICKSLIP_PROGRESS");
    for (k, v) in envs {
        c.env(k, v);
    }
    let out = c.output().expect("the binary runs");
    assert!(out.status.success(), "{args:?} failed: {:?}\n{}", out.status, String::from_utf8_lossy(&out.stderr));
    out
}

fn strings(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

/// Starts `args` and kills it (SIGKILL) once `dir/checkpoint.bin` exists and the run has
/// gone on a little past it. Returns false if the run ended (or finished its work) before
/// it could be killed.
fn kill_after_checkpoint(args: &[String], dir: &Path) -> bool {
    let ckpt = dir.join("checkpoint.bin");
    let before = std::fs::metadata(&ckpt).and_then(|m| m.modified()).ok();
    let mut child = Command::new(BIN)
        .args(args)
        .env_remove("STICKSLIP_PROGRESS")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "{args:?}: {status:?}");
            return false;
        }
        let now = std::fs::metadata(&ckpt).and_then(|m| m.modified()).ok();
        if now.is_some() && now != before {
            break;
        }
        assert!(Instant::now() < deadline, "{args:?}: no checkpoint after 120 s");
        std::thread::sleep(Duration::from_millis(2));
    }
    // Let the run write past the checkpoint, so that the resume has something to cut.
    std::thread::sleep(Duration::from_millis(30));
    child.kill().unwrap(); // SIGKILL
    let status = child.wait().unwrap();
    // The kill may land after the run has finished its work (summary written, checkpoint
    // removed) but before the process exited, or while it renames its finished outputs
    // into place: neither is the mid-run kill this test is about (resuming after a kill
    // among the renames is `reopen_takes_back_a_file_already_renamed_into_place`).
    let finalising = ["summary.json", "trace.csv", "events.csv"].iter().any(|f| dir.join(f).exists());
    if status.success() || !ckpt.exists() || finalising {
        return false;
    }
    true
}

/// Appends a line cut short, as a kill inside a write system call could leave.
fn tear(dir: &Path) {
    for name in ["trace.csv.part", "events.csv.part"] {
        let p = dir.join(name);
        if p.exists() {
            let mut b = std::fs::read(&p).unwrap();
            b.extend_from_slice(b"12.5,0.25,1");
            std::fs::write(&p, b).unwrap();
        }
    }
}

fn summary_without_wall_time(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let wall = v.as_object_mut().unwrap().remove("wall_seconds").expect("wall_seconds");
    assert!(wall.as_f64().unwrap() > 0.0);
    v
}

/// The files in `dir`, but for the lock file a killed run leaves (not an output; a resume
/// that is refused takes it, and removes it when it gives the directory up).
fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|f| f != stickslip::output::lock::FILE)
        .collect();
    v.sort();
    v
}

/// Same outputs in `a` and `b`: CSV files byte for byte, summaries but for the wall time.
fn assert_same_outputs(name: &str, a: &Path, b: &Path) {
    for f in ["trace.csv", "events.csv"] {
        let (pa, pb) = (a.join(f), b.join(f));
        assert_eq!(pa.exists(), pb.exists(), "{name}: {f}");
        if pa.exists() {
            let (x, y) = (std::fs::read(&pa).unwrap(), std::fs::read(&pb).unwrap());
            assert!(x.len() > 1000, "{name}: {f} is too short to test anything");
            let first = x.iter().zip(&y).position(|(p, q)| p != q);
            assert!(
                x == y,
                "{name}: {f} differs (lengths {} and {}, first difference at byte {first:?})",
                x.len(),
                y.len()
            );
        }
    }
    assert_eq!(summary_without_wall_time(a), summary_without_wall_time(b), "{name}: summary.json");
}

/// `resume` with less memory available than the run needs (the cap from the environment)
/// is refused in one line naming `junctions.n` and the cap, exit code 2, and every file in
/// `dir` is left as it was, byte for byte.
fn refused_without_memory(name: &str, dir: &Path) {
    let snapshot = |d: &Path| -> Vec<(String, Vec<u8>)> {
        files(d).into_iter().map(|f| (f.clone(), std::fs::read(d.join(&f)).unwrap())).collect()
    };
    let before = snapshot(dir);
    let o = Command::new(BIN)
        .args(["resume", dir.to_str().unwrap()])
        .env_remove("STICKSLIP_PROGRESS")
        .env(MEMORY_ENV, (1u64 << 20).to_string())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{name}: {err}");
    assert!(o.stdout.is_empty(), "{name}");
    assert_eq!(err.lines().count(), 1, "{name}: {err}");
    assert!(err.contains("junctions.n = ") && err.contains("of memory") && err.contains(MEMORY_ENV), "{name}: {err}");
    assert!(snapshot(dir) == before, "{name}: a refused resume changed the directory");
}

/// Runs `case` uninterrupted, and killed `kills` times and resumed; compares.
fn kill_and_resume(case: &Case, kills: usize) {
    let tmp = tempfile::tempdir().unwrap();
    let mut t_end = case.t_end;
    for attempt in 0.. {
        assert!(attempt < 6, "{}: the run always ended before it could be killed", case.name);
        let dir = tmp.path().join(format!("killed-{attempt}"));
        let mut args = strings(&["run"]);
        args.extend(scene_args(tmp.path(), case, t_end));
        args.extend(strings(&["--out", dir.to_str().unwrap(), "--checkpoint-every", EVERY]));
        if !kill_after_checkpoint(&args, &dir) {
            t_end *= 2.0;
            continue;
        }
        let names = files(&dir);
        assert!(names.contains(&"checkpoint.bin".to_string()), "{}: {names:?}", case.name);
        assert!(!names.iter().any(|n| n == "summary.json" || n == "trace.csv"), "{}: {names:?}", case.name);
        assert!(names.contains(&"trace.csv.part".to_string()), "{}: {names:?}", case.name);
        tear(&dir);
        let resume = strings(&["resume", dir.to_str().unwrap()]);
        let mut killed = 1;
        while killed < kills {
            // Kill the resumed run too, once it has written a checkpoint of its own.
            if !kill_after_checkpoint(&resume, &dir) {
                break;
            }
            tear(&dir);
            killed += 1;
        }
        if dir.join("checkpoint.bin").exists() {
            refused_without_memory(case.name, &dir);
            let out = run(&resume, &[]);
            let stdout = String::from_utf8_lossy(&out.stdout);
            assert!(stdout.starts_with("resumed from the checkpoint at t = "), "{stdout}");
        } else if !dir.join("trace.svg").exists() {
            // The last kill landed after the results were in place, before the plot.
            let out = run(&resume, &[]);
            let stdout = String::from_utf8_lossy(&out.stdout);
            assert!(stdout.contains("is drawn now"), "{stdout}");
        }
        // trace.svg: drawn by default with trace.csv.
        let mut expected = vec!["summary.json", "trace.csv", "trace.svg"];
        if case.sets.contains(&"output.events=true") {
            expected.insert(0, "events.csv");
        }
        assert_eq!(files(&dir), expected, "{}: what a finished run leaves", case.name);
        let reference = tmp.path().join("reference");
        let mut args = strings(&["run"]);
        args.extend(scene_args(tmp.path(), case, t_end));
        args.extend(strings(&["--out", reference.to_str().unwrap()]));
        run(&args, &[]);
        assert_same_outputs(case.name, &reference, &dir);
        // Resuming the finished run does nothing and says so.
        let out = run(&strings(&["resume", dir.to_str().unwrap()]), &[]);
        assert!(String::from_utf8_lossy(&out.stdout).contains("is finished"));
        assert_same_outputs(case.name, &reference, &dir);
        return;
    }
}

#[test]
fn killed_and_resumed_fixed_engine() {
    kill_and_resume(&FIXED, 1);
}

#[test]
fn killed_and_resumed_exact_linear_strong() {
    kill_and_resume(&LINEAR_STRONG, 1);
}

/// A run killed after its results were in place but before its plot was drawn: `resume`
/// draws the plot (the bytes an uninterrupted run draws) and says so; then there is nothing
/// left to do.
#[test]
fn resume_draws_a_plot_left_undrawn() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    let mut args = strings(&["run"]);
    args.extend(scene_args(tmp.path(), &LINEAR_WEAK, 200.0));
    args.extend(strings(&["--out", dir.to_str().unwrap()]));
    run(&args, &[]);
    let svg = std::fs::read(dir.join("trace.svg")).unwrap();
    std::fs::remove_file(dir.join("trace.svg")).unwrap();
    let resume = strings(&["resume", dir.to_str().unwrap()]);
    let out = run(&resume, &[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("its trace.svg was missing and is drawn now"), "{stdout}");
    assert!(std::fs::read(dir.join("trace.svg")).unwrap() == svg, "the plot differs from the run's own");
    let out = run(&resume, &[]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("nothing to resume"));
}

#[test]
fn killed_twice_and_resumed_exact_linear_weak() {
    kill_and_resume(&LINEAR_WEAK, 2);
}

#[test]
fn killed_and_resumed_exact_linear_weak_in_bins() {
    const { assert!(stickslip::engine::exact::BINNED_FROM <= 100_000) };
    kill_and_resume(&LINEAR_WEAK_BINS, 1);
}

#[test]
fn killed_and_resumed_kinematic_plates() {
    kill_and_resume(&KINEMATIC_EXACT, 1);
    kill_and_resume(&KINEMATIC_FIXED, 1);
}

#[test]
fn killed_and_resumed_thermal() {
    kill_and_resume(&THERMAL, 1);
}

#[test]
fn killed_and_resumed_exact_tilted() {
    kill_and_resume(&TILTED, 1);
}

#[test]
fn killed_and_resumed_exact_tilted_weak_in_bins() {
    const { assert!(stickslip::engine::exact::BINNED_FROM <= 100_000) };
    const { assert!(stickslip::engine::exact::stepper::series::PREFETCH_MIN_N <= 100_000) };
    kill_and_resume(&TILTED_WEAK_LARGE, 1);
}

#[test]
fn killed_and_resumed_exact_tilted_kinematic() {
    kill_and_resume(&TILTED_KINEMATIC, 1);
}

#[test]
fn progress_changes_nothing() {
    // The progress thread runs (STICKSLIP_PROGRESS=always) on a run long enough to draw.
    let tmp = tempfile::tempdir().unwrap();
    let case = LINEAR_WEAK;
    let mut outs = Vec::new();
    for (i, env) in ["always", "never"].into_iter().enumerate() {
        let dir = tmp.path().join(format!("p{i}"));
        let mut args = strings(&["run"]);
        args.extend(scene_args(tmp.path(), &case, 4000.0));
        args.extend(strings(&["--out", dir.to_str().unwrap(), "--set", "output.sample_dt=0.5"]));
        let out = run(&args, &[("STICKSLIP_PROGRESS", env)]);
        // stderr is a pipe here: indicatif draws nothing even when the thread runs.
        assert!(out.stderr.is_empty(), "{env}: {:?}", String::from_utf8_lossy(&out.stderr));
        outs.push(dir);
    }
    assert_same_outputs("progress", &outs[0], &outs[1]);
}

/// Runs `args` with stderr on a pseudo-terminal (80 x 24); returns what the terminal
/// received and the exit status.
fn run_on_terminal(args: &[String]) -> (String, std::process::ExitStatus) {
    use std::io::Read;
    use std::os::fd::FromRawFd;
    let (mut master, mut slave) = (-1, -1);
    let size = libc::winsize { ws_row: 24, ws_col: 80, ws_xpixel: 0, ws_ypixel: 0 };
    // SAFETY: openpty writes two fds into the given integers; the null pointers are allowed.
    let rc = unsafe { libc::openpty(&mut master, &mut slave, std::ptr::null_mut(), std::ptr::null(), &size) };
    assert_eq!(rc, 0, "openpty: {}", std::io::Error::last_os_error());
    // SAFETY: both fds were just opened and are owned by nothing else.
    let (mut master, slave) = unsafe { (std::fs::File::from_raw_fd(master), std::fs::File::from_raw_fd(slave)) };
    let mut child = Command::new(BIN)
        .args(args)
        .env_remove("STICKSLIP_PROGRESS")
        .stdout(Stdio::null())
        .stderr(Stdio::from(slave))
        .spawn()
        .unwrap();
    // The child holds the only slave fd now: reading ends (EIO) when it exits.
    let reader = std::thread::spawn(move || {
        let mut got = Vec::new();
        let mut buf = [0u8; 4096];
        while let Ok(n) = master.read(&mut buf) {
            if n == 0 {
                break;
            }
            got.extend_from_slice(&buf[..n]);
        }
        got
    });
    let status = child.wait().unwrap();
    let got = reader.join().unwrap();
    (String::from_utf8_lossy(&got).into_owned(), status)
}

fn wall_seconds(dir: &Path) -> f64 {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["wall_seconds"].as_f64().unwrap()
}

#[test]
fn progress_on_a_terminal_and_quiet_otherwise() {
    // A run that lasts well past the 1.5 s after which progress appears (t_end doubled
    // until it does, on a fast machine).
    let tmp = tempfile::tempdir().unwrap();
    let mut t_end = 60000.0;
    for attempt in 0.. {
        assert!(attempt < 5, "the runs never lasted 2.5 s");
        let (tty, pipe) = (tmp.path().join(format!("tty{attempt}")), tmp.path().join(format!("pipe{attempt}")));
        let with_out = |dir: &Path| {
            let mut a = strings(&["run"]);
            a.extend(scene_args(tmp.path(), &LINEAR_WEAK, t_end));
            a.extend(strings(&["--out", dir.to_str().unwrap(), "--set", "output.sample_dt=10"]));
            a
        };
        let (seen, status) = run_on_terminal(&with_out(&tty));
        assert!(status.success(), "{status:?}: {seen}");
        if wall_seconds(&tty) < 2.5 {
            t_end *= 2.0;
            continue;
        }
        assert!(seen.contains("events/s") && seen.contains("t = ") && seen.contains("ETA"), "{seen:?}");
        assert!(!seen.contains("NaN") && !seen.contains("inf"), "{seen:?}");
        // The same run with stderr a pipe prints nothing on stderr.
        let out = run(&with_out(&pipe), &[]);
        assert!(wall_seconds(&pipe) > 1.5 + 0.2, "too short to show progress: the test tests nothing");
        assert!(out.stderr.is_empty(), "{:?}", String::from_utf8_lossy(&out.stderr));
        assert_same_outputs("terminal", &tty, &pipe);
        return;
    }
}

// ---- bad input ---------------------------------------------------------------------------

/// Every file under `dir` with its contents, but for the lock file a killed run leaves.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut v: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().file_name() != stickslip::output::lock::FILE)
        .map(|e| {
            let p = e.unwrap().path();
            let b = if p.is_file() { std::fs::read(&p).unwrap() } else { Vec::new() };
            (p, b)
        })
        .collect();
    v.sort();
    v
}

/// Runs the binary and checks the bad-input contract; returns the stderr line.
fn expect_bad_input(args: &[String], watch: &Path, mentions: &[&str]) -> String {
    let before = snapshot(watch);
    let out = Command::new(BIN).args(args).env_remove("STICKSLIP_PROGRESS").output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    assert_eq!(out.status.code(), Some(2), "{args:?}: {:?} {stderr}", out.status);
    assert_eq!(stderr.lines().count(), 1, "{args:?}: one line expected, got {stderr:?}");
    assert!(stderr.starts_with("error: ") && stderr.ends_with('\n'), "{stderr:?}");
    for m in mentions {
        assert!(stderr.contains(m), "{args:?}: {stderr:?} does not mention {m:?}");
    }
    assert!(out.stdout.is_empty(), "{args:?}: stdout {:?}", String::from_utf8_lossy(&out.stdout));
    assert!(snapshot(watch) == before, "{args:?}: files changed");
    stderr
}

/// A run of `LINEAR_STRONG` killed after a checkpoint, in `tmp/name`.
fn killed_run(tmp: &Path, name: &str) -> PathBuf {
    let dir = tmp.join(name);
    let mut t_end = 2000.0;
    loop {
        let _ = std::fs::remove_dir_all(&dir);
        let mut args = strings(&["run"]);
        args.extend(scene_args(tmp, &LINEAR_STRONG, t_end));
        args.extend(strings(&["--out", dir.to_str().unwrap(), "--checkpoint-every", "0.02"]));
        if kill_after_checkpoint(&args, &dir) {
            return dir;
        }
        t_end *= 2.0;
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
    }
}

#[test]
fn bad_resume_inputs() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let resume = |d: &Path| strings(&["resume", d.to_str().unwrap()]);

    // No such directory; a directory with no checkpoint; a regular file.
    expect_bad_input(&resume(&t.join("missing")), t, &["missing", "not a directory"]);
    let empty = t.join("empty");
    std::fs::create_dir(&empty).unwrap();
    expect_bad_input(&resume(&empty), &empty, &["no checkpoint.bin"]);
    std::fs::write(t.join("file"), b"x").unwrap();
    expect_bad_input(&resume(&t.join("file")), t, &["not a directory"]);

    let good = killed_run(t, "good");
    let ckpt = std::fs::read(good.join("checkpoint.bin")).unwrap();
    let variant = |name: &str, edit: &dyn Fn(&Path)| {
        let d = t.join(name);
        copy_dir(&good, &d);
        edit(&d);
        d
    };

    // Damaged: a flipped byte, cut short, not a checkpoint at all, empty.
    for (name, bytes, mentions) in [
        (
            "flipped",
            {
                let mut b = ckpt.clone();
                let n = b.len();
                b[n / 2] ^= 1;
                b
            },
            &["damaged"][..],
        ),
        ("cut", ckpt[..ckpt.len() - 100].to_vec(), &["damaged"][..]),
        ("json", b"{\"t\": 1}".to_vec(), &["not a stickslip checkpoint"][..]),
        ("zero", Vec::new(), &["not a stickslip checkpoint"][..]),
        (
            "version",
            {
                let mut b = ckpt.clone();
                b[21] = 99;
                b
            },
            &["format 99"][..],
        ),
    ] {
        let d = variant(name, &|d| std::fs::write(d.join("checkpoint.bin"), &bytes).unwrap());
        expect_bad_input(&resume(&d), &d, &[&["checkpoint.bin"][..], mentions].concat());
    }

    // Partial outputs that do not match the checkpoint: missing, cut short, overwritten.
    let d = variant("no-trace", &|d| std::fs::remove_file(d.join("trace.csv.part")).unwrap());
    expect_bad_input(&resume(&d), &d, &["cannot resume", "trace.csv.part is missing"]);
    let d = variant("short-events", &|d| {
        std::fs::OpenOptions::new().write(true).open(d.join("events.csv.part")).unwrap().set_len(10).unwrap()
    });
    expect_bad_input(&resume(&d), &d, &["cannot resume", "events.csv.part holds 10 bytes"]);
    let d = variant("other-trace", &|d| {
        let p = d.join("trace.csv.part");
        let b: Vec<u8> = std::fs::read(&p).unwrap().iter().map(|&c| if c == b'1' { b'2' } else { c }).collect();
        std::fs::write(p, b).unwrap();
    });
    expect_bad_input(&resume(&d), &d, &["cannot resume", "trace.csv.part does not hold"]);

    // The untouched copy still resumes.
    let out = run(&resume(&good), &[]);
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("resumed from the checkpoint"));
}

#[test]
fn bad_checkpoint_every() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let out = t.join("out");
    for bad in ["0", "-1", "-0.5", "NaN", "inf", "abc", ""] {
        let mut args = strings(&["run"]);
        args.extend(scene_args(t, &FIXED, 10.0));
        args.extend(strings(&["--out", out.to_str().unwrap(), "--checkpoint-every", bad]));
        expect_bad_input(&args, t, &["--checkpoint-every"]);
        assert!(!out.exists());
        let args = strings(&["resume", t.to_str().unwrap(), "--checkpoint-every", bad]);
        expect_bad_input(&args, t, &["--checkpoint-every"]);
    }
}

#[test]
fn a_new_run_removes_a_stale_checkpoint() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = killed_run(tmp.path(), "d");
    assert!(dir.join("checkpoint.bin").exists());
    let mut args = strings(&["run"]);
    args.extend(scene_args(tmp.path(), &FIXED, 50.0));
    args.extend(strings(&["--out", dir.to_str().unwrap()]));
    run(&args, &[]);
    assert!(!dir.join("checkpoint.bin").exists());
    let out = run(&strings(&["resume", dir.to_str().unwrap()]), &[]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("is finished"));
}

/// `run` of the letter's Fig. 1 (fixed engine) with `sets` into `out`, scene file in `tmp`.
fn fig1_run(tmp: &Path, out: &Path, sets: &[&str]) -> Vec<String> {
    let scene = tmp.join("scene.toml");
    std::fs::write(&scene, FIG1).unwrap();
    let mut a = strings(&["run", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    for s in sets {
        a.extend(strings(&["--set", s]));
    }
    a
}

/// A finished run with every output file (trace, plot, events) in `tmp/name`, beside a file
/// and a directory of the user's, which no run may remove.
fn finished_run_with_every_file(tmp: &Path, name: &str) -> PathBuf {
    let dir = tmp.join(name);
    std::fs::create_dir_all(dir.join("mine")).unwrap();
    std::fs::write(dir.join("notes.txt"), b"kept").unwrap();
    run(&fig1_run(tmp, &dir, &["fixed.dt=0.1", "output.events=true", "output.plot=true"]), &[]);
    for f in ["summary.json", "trace.csv", "trace.svg", "events.csv"] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    dir
}

/// The user's own file and directory are still in `dir`.
fn assert_user_files_kept(dir: &Path) {
    assert_eq!(std::fs::read(dir.join("notes.txt")).unwrap(), b"kept");
    assert!(dir.join("mine").is_dir());
}

#[test]
fn a_new_run_that_fails_leaves_no_output_of_an_earlier_run() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = finished_run_with_every_file(tmp.path(), "d");
    // dt = 1.5 is beyond the plate step's stability limit: the plate diverges.
    let args = fig1_run(tmp.path(), &dir, &["fixed.dt=1.5", "run.t_end=3000", "output.plot=true"]);
    let out = Command::new(BIN).args(&args).env_remove("STICKSLIP_PROGRESS").output().unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("diverged"));
    assert_eq!(files(&dir), ["mine", "notes.txt"]);
    assert_user_files_kept(&dir);
}

#[test]
fn a_new_run_with_fewer_files_leaves_none_of_an_earlier_runs_others() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = finished_run_with_every_file(tmp.path(), "d");
    let old = std::fs::read(dir.join("summary.json")).unwrap();
    run(&fig1_run(tmp.path(), &dir, &["fixed.dt=0.5", "run.t_end=20", "output.trace=false"]), &[]);
    assert_eq!(files(&dir), ["mine", "notes.txt", "summary.json"]);
    assert_ne!(std::fs::read(dir.join("summary.json")).unwrap(), old);
    assert_user_files_kept(&dir);
}

#[test]
fn a_new_run_killed_before_its_first_checkpoint_leaves_nothing_to_resume() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = finished_run_with_every_file(tmp.path(), "d");
    let mut args = fig1_run(tmp.path(), &dir, &["fixed.dt=0.1", "run.t_end=1e7", "output.sample_dt=1000"]);
    args.extend(strings(&["--checkpoint-every", "3600"]));
    let mut child = Command::new(BIN)
        .args(&args)
        .env_remove("STICKSLIP_PROGRESS")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // The finished run left no `.part` file: this one is the new run's, begun.
    let deadline = Instant::now() + Duration::from_secs(60);
    while !dir.join("trace.csv.part").exists() {
        assert!(child.try_wait().unwrap().is_none(), "the run ended before it could be killed");
        assert!(Instant::now() < deadline, "no trace.csv.part after 60 s");
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    assert_eq!(files(&dir), ["mine", "notes.txt", "trace.csv.part"]);
    assert_user_files_kept(&dir);
    let resume = strings(&["resume", dir.to_str().unwrap()]);
    expect_bad_input(&resume, &dir, &["no checkpoint.bin"]);
}
