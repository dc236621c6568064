//! `stickslip compare` end to end on a tiny scene: the three files with finite numbers, the
//! same CSV (timing columns aside) with 1 and 2 threads, a diverging step reported rather
//! than fatal, and bad arguments refused with one line and nothing written.
//! Run with `cargo test --release --test suite compare::` (a few seconds).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

/// 20 weak junctions (so the rupture force is compared too), linear law, the letter's plate.
/// At dt = 4 the plate step grows by ~34 per step (every junction attached), so 75 steps
/// take it past the engine's divergence threshold of 1e100.
pub(super) const TINY: &str = r#"
[junctions]
n = 20
bond = "weak"
force_law = "linear"
initial = "stationary"
[plate]
mass = 75.0
eta = 75.0
k = 150.0
v = 0.5
[run]
engine = "exact"
t_end = 300.0
t_warmup = 50.0
seed = 3
[fixed]
dt = 0.5
[output]
sample_dt = 1.0
"#;

fn run_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN).args(args).current_dir(dir).output().expect("the binary runs")
}

fn tiny_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), TINY).unwrap();
    dir
}

const ARGS: [&str; 7] = ["compare", "tiny.toml", "--dts", "0.5,0.25,4", "--replicas", "4", "--ref-replicas"];

/// Runs the tiny study with `threads` threads into `out`; returns the CSV text.
fn study(dir: &Path, out: &str, threads: &str) -> String {
    let mut args = ARGS.to_vec();
    args.extend_from_slice(&["8", "--out", out, "--threads", threads]);
    let o = run_in(dir, &args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "compare failed: {stderr}");
    std::fs::read_to_string(dir.join(out).join("compare.csv")).unwrap()
}

/// The CSV without its timing columns (`wall_seconds`, `cpu_seconds`).
fn without_timing(csv: &str) -> Vec<Vec<String>> {
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..header.len()).filter(|&i| !header[i].ends_with("_seconds")).collect();
    assert_eq!(keep.len() + 2, header.len(), "expected two timing columns in {header:?}");
    csv.lines()
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            keep.iter().map(|&i| cells[i].to_string()).collect()
        })
        .collect()
}

/// Without `--threads` the replicas run one at a time, and `compare.md` says how many ran at
/// a time either way (a cost may depend on it; the estimates do not).
#[test]
fn compare_md_states_how_many_replicas_ran_at_a_time() {
    let dir = tiny_dir();
    let mut args = ARGS.to_vec();
    args.extend_from_slice(&["8", "--out", "default"]);
    let o = run_in(dir.path(), &args);
    assert!(o.status.success(), "compare failed: {}", String::from_utf8_lossy(&o.stderr));
    let md = std::fs::read_to_string(dir.path().join("default/compare.md")).unwrap();
    assert!(md.contains("replicas run one at a time"), "{md}");
    study(dir.path(), "two", "2");
    let md = std::fs::read_to_string(dir.path().join("two/compare.md")).unwrap();
    assert!(md.contains("replicas run 2 at a time"), "{md}");
    let csv = |d: &str| std::fs::read_to_string(dir.path().join(d).join("compare.csv")).unwrap();
    assert_eq!(without_timing(&csv("default")), without_timing(&csv("two")));
}

#[test]
fn tiny_study_writes_three_files_reports_divergence_and_ignores_the_thread_count() {
    let dir = tiny_dir();
    let one = study(dir.path(), "one", "1");
    let two = study(dir.path(), "two", "2");
    assert_eq!(without_timing(&one), without_timing(&two), "the CSV depends on the thread count");

    let rows: Vec<Vec<String>> = one.lines().map(|l| l.split(',').map(str::to_string).collect()).collect();
    let header = &rows[0];
    let col = |name: &str| header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"));
    for o in ["friction_mean", "friction_std", "attached_fraction_mean", "rupture_force_mean"] {
        for c in ["estimate", "se", "error", "ci_low", "ci_high", "floor"] {
            col(&format!("{o}_{c}"));
        }
    }
    // Reference, 3 exact points (1, 2, 4 replicas), 3 fixed points.
    assert_eq!(rows.len(), 1 + 1 + 3 + 3, "{one}");
    let engines: Vec<&str> = rows[1..].iter().map(|r| r[col("engine")].as_str()).collect();
    assert_eq!(engines, ["reference", "exact", "exact", "exact", "fixed", "fixed", "fixed"]);
    let n = header.len();
    for r in &rows[1..] {
        assert_eq!(r.len(), n, "ragged row {r:?}");
        let status = r[col("status")].as_str();
        for (h, v) in header.iter().zip(r) {
            if !v.is_empty() && !["engine", "status"].contains(&h.as_str()) {
                let x: f64 = v.parse().unwrap_or_else(|_| panic!("{h} = {v:?} is not a number"));
                assert!(x.is_finite(), "{h} = {v}");
            }
        }
        if status == "ok" {
            for o in ["friction_mean", "rupture_force_mean"] {
                let est = &r[col(&format!("{o}_estimate"))];
                assert!(!est.is_empty(), "{o} missing in {r:?}");
            }
            if r[col("engine")] != "reference" {
                let (lo, hi) = (&r[col("friction_mean_ci_low")], &r[col("friction_mean_ci_high")]);
                assert!(lo.parse::<f64>().unwrap() < hi.parse::<f64>().unwrap());
            }
        }
    }
    // dt = 4 diverges in every replica: reported, with no estimate.
    let last = &rows[rows.len() - 1];
    assert_eq!(last[col("dt")], "4.0");
    assert_eq!(last[col("status")], "diverged", "{last:?}");
    assert_eq!(last[col("diverged_replicas")], "4");
    assert!(last[col("friction_mean_estimate")].is_empty());
    assert!(last[col("plate_growth")].parse::<f64>().unwrap() > 1.0);
    // The stable steps are not flagged.
    for r in &rows[5..7] {
        assert_eq!(r[col("status")], "ok", "{r:?}");
    }

    let out = dir.path().join("one");
    let md = std::fs::read_to_string(out.join("compare.md")).unwrap();
    assert!(md.contains("## Reading"), "{md}");
    assert!(md.contains("diverged in 4 of 4 replicas"), "{md}");
    assert!(!md.contains("NaN"), "{md}");
    let svg = std::fs::read_to_string(out.join("compare.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"), "not an SVG");
    assert!(svg.contains("diverged"), "the figure does not mention the diverged step");
    assert!(!svg.contains("NaN"));
    // Written atomically: no temporary file is left.
    let names: Vec<String> =
        std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert!(names.iter().all(|n| !n.ends_with(".part")), "{names:?}");
}

/// Every file and directory under `root`, relative to it, sorted.
fn tree(root: &Path) -> Vec<PathBuf> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            out.push(p.strip_prefix(root).unwrap().to_path_buf());
            if p.is_dir() {
                walk(root, &p, out);
            }
        }
    }
    let mut out = Vec::new();
    walk(root, root, &mut out);
    out.sort();
    out
}

/// Exit 2, one line on stderr naming `mentions`, nothing on stdout, nothing written.
fn expect_bad(extra: &[&str], mentions: &[&str]) {
    let dir = tiny_dir();
    let before = tree(dir.path());
    let mut args = vec!["compare", "tiny.toml"];
    args.extend_from_slice(extra);
    let o = run_in(dir.path(), &args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: not one line: {stderr:?}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    for m in mentions {
        assert!(stderr.contains(m), "{args:?}: {stderr:?} does not mention {m:?}");
    }
    assert!(o.stdout.is_empty(), "{args:?}: {}", String::from_utf8_lossy(&o.stdout));
    assert_eq!(tree(dir.path()), before, "{args:?}: something was written");
}

#[test]
fn bad_dts_lists_are_refused() {
    for (dts, what) in [
        ("", "empty"),
        (" ", "empty"),
        ("-0.5", "-0.5"),
        ("0.5,-1", "-1"),
        ("NaN", "NaN"),
        ("0.5,nan", "nan"),
        ("inf", "inf"),
        ("abc", "abc"),
        ("0.5,x", "x"),
        ("0", "0"),
        ("0.5,0.0", "0.0"),
        ("0.5,,0.25", "empty"),
    ] {
        expect_bad(&["--dts", dts], &["--dts", what]);
        // Also as --dts=VALUE.
        expect_bad(&[&format!("--dts={dts}")], &["--dts"]);
    }
}

#[test]
fn other_bad_arguments_are_refused() {
    expect_bad(&["--replicas", "1"], &["--replicas", "1"]);
    expect_bad(&["--replicas", "x"], &["--replicas"]);
    expect_bad(&["--ref-replicas", "0"], &["--ref-replicas", "0"]);
    // More replicas than a plan holds (each job keeps its scene).
    expect_bad(&["--replicas", "100000000"], &["--replicas", "100000000", "10000"]);
    expect_bad(&["--ref-replicas", "100000000000"], &["--ref-replicas", "100000000000", "40000"]);
    // A step too long or too short for the run, shown short.
    expect_bad(&["--dts", "1e300"], &["--dts: 1e300: run.t_end"]);
    expect_bad(&["--threads", "0"], &["--threads", "0"]);
    expect_bad(&["--exact-rtol", "0"], &["--exact-rtol", "exact.rtol", "0"]);
    expect_bad(&["--exact-rtol", "0.5"], &["--exact-rtol", "exact.rtol", "0.5"]);
    expect_bad(&["--exact-rtol", "x"], &["--exact-rtol"]);
    expect_bad(&["--set", "plate.k=-1"], &["plate.k", "-1"]);
    // Park-Miller blocks that do not fit in the generator's period.
    expect_bad(&["--dts", "1e-6", "--replicas", "2"], &["--replicas", "Park-Miller"]);
    // An output path that is a file.
    let dir = tiny_dir();
    std::fs::write(dir.path().join("file"), b"").unwrap();
    let o = run_in(dir.path(), &["compare", "tiny.toml", "--out", "file/sub", "--replicas", "2"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("output directory"));
}
