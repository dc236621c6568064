//! A run or study holds its output directory while it works: a second run, sweep, compare or
//! resume into the same `--out` is refused at once (one line naming the directory and the
//! holder's process id, exit 2) and the first finishes as it would alone; a lock left by a
//! killed holder blocks nothing.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");
const LOCK: &str = ".stickslip.lock";

fn scenario(name: &str) -> String {
    format!("{}/scenarios/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The long run: about 1.2 M events of the letter's Fig. 1 scene in the exact engine, with
/// its trace and plot.
fn long_args(out: &Path) -> Vec<String> {
    let scene = scenario("fig1-exact.toml");
    ["run", &scene, "--set", "run.t_end=40000", "--out", out.to_str().unwrap()].map(String::from).to_vec()
}

fn spawn(args: &[String]) -> Child {
    Command::new(BIN).args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("the binary runs")
}

fn stickslip(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("the binary runs")
}

/// Waits until `child` holds `dir` (its lock file names it).
fn wait_for_hold(child: &mut Child, dir: &Path) {
    let started = Instant::now();
    let pid = format!("{}\n", child.id());
    while std::fs::read_to_string(dir.join(LOCK)).ok().as_deref() != Some(pid.as_str()) {
        assert!(child.try_wait().unwrap().is_none(), "the long run ended before it was seen holding {dir:?}");
        assert!(started.elapsed() < Duration::from_secs(60), "no lock file in {dir:?}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The files of `dir` with their bytes, `summary.json` without its wall-clock time.
fn contents(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let path = e.unwrap().path();
            let mut bytes = std::fs::read(&path).unwrap();
            if path.file_name().unwrap() == "summary.json" {
                let mut v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
                v.as_object_mut().unwrap().remove("wall_seconds");
                bytes = serde_json::to_vec(&v).unwrap();
            }
            (PathBuf::from(path.file_name().unwrap()), bytes)
        })
        .collect();
    files.sort();
    files
}

fn assert_refused(o: &Output, dir: &Path, holder: u32) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    let dir = dir.display().to_string();
    assert!(err.contains(&dir) && err.contains(&format!("process {holder} ")), "{err}");
    assert!(o.stdout.is_empty(), "{}", String::from_utf8_lossy(&o.stdout));
}

#[test]
fn a_second_run_study_or_resume_into_a_held_directory_is_refused_and_the_first_finishes_untouched() {
    let tmp = tempfile::tempdir().unwrap();
    let (raced, solo) = (tmp.path().join("raced"), tmp.path().join("solo"));
    let mut long = spawn(&long_args(&raced));
    wait_for_hold(&mut long, &raced);
    let dir = raced.to_str().unwrap();
    let (fig1, fig2) = (scenario("fig1.toml"), scenario("fig2.toml"));
    let refused = [
        stickslip(&["run", &fig1, "--out", dir]),
        stickslip(&["sweep", &fig2, "--param", "plate.v", "--values", "0.5,1", "--out", dir]),
        stickslip(&["compare", &fig1, "--dts", "0.5", "--replicas", "2", "--ref-replicas", "2", "--out", dir]),
        stickslip(&["resume", dir]),
    ];
    // All four were refused while the long run held the directory.
    assert!(long.try_wait().unwrap().is_none(), "the long run ended before the others were refused: lengthen it");
    for o in &refused {
        assert_refused(o, &raced, long.id());
    }
    let first = long.wait_with_output().unwrap();
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    assert!(stickslip(&long_args(&solo).iter().map(String::as_str).collect::<Vec<_>>()).status.success());
    let names = |c: &[(PathBuf, Vec<u8>)]| c.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    let (a, b) = (contents(&raced), contents(&solo));
    assert_eq!(names(&a), ["summary.json", "trace.csv", "trace.svg"].map(PathBuf::from), "no lock file is left");
    assert!(a == b, "the raced run's files differ from a run alone");
}

#[test]
fn a_lock_left_by_a_killed_holder_blocks_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("d");
    let mut long = spawn(&long_args(&dir));
    wait_for_hold(&mut long, &dir);
    long.kill().unwrap();
    long.wait().unwrap();
    assert!(dir.join(LOCK).exists(), "the killed run's lock file stays behind");
    let fig1 = scenario("fig1.toml");
    let o = stickslip(&["run", &fig1, "--out", dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!dir.join(LOCK).exists());
    assert!(dir.join("summary.json").is_file());
}
