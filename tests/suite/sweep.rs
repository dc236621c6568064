//! `stickslip sweep`, the regime criterion on simulated traces, and `trace.svg`.
//!
//! - the sweep's tables are byte-identical with 1 and 2 threads, and every run has its own seed;
//! - a 2-D sweep (regime map) has both fields as leading columns, row-major grid points with
//!   the seeds of their index, rows that aggregate their own runs, and a heat map; summaries
//!   of runs made through the library API (travelling as JSON) give the command's tables, and
//!   summaries out of order are refused;
//! - bad `--values`, `--log-range`, `--range`, `--param`, `--replicas` (also more
//!   Park–Miller replicas than the generator's cycle holds), `--log-y` (also for maps) give
//!   one line on stderr, exit code 2, and no output directory;
//! - the regime criterion labels the fig2 scene smooth at V = 0.1 and stick-slip at V = 1
//!   (fixed seeds; its period, amplitude and cycles as `summary.json` reports them), and the
//!   velocity hysteresis alone (the first criterion, now a supporting sign) would have
//!   called the V = 0.1 trace stick-slip;
//! - `stickslip run` writes a well-formed `trace.svg` when `output.plot = true`, and none
//!   otherwise; `plot = true` with `trace = false` is refused.

use std::path::{Path, PathBuf};
use std::process::Command;

use stickslip::Scene;
use stickslip::observe::regime::{MIN_COHERENCE, Regime};
use stickslip_testkit::verdict_of as verdict;

use crate::common::svg::assert_well_formed_svg;

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

fn fig2() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/fig2.toml")
}

fn stickslip(args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(BIN).args(args).current_dir(dir).output().expect("the binary runs")
}

/// A short sweep of the fig2 scene with `threads` threads into `dir/out`.
fn short_sweep(dir: &Path, threads: &str) -> (String, String, serde_json::Value) {
    let scene = fig2();
    let out = dir.join("out");
    let o = stickslip(
        &[
            "sweep",
            scene.to_str().unwrap(),
            "--param",
            "plate.v",
            "--values",
            "0.1,1,8",
            "--replicas",
            "3",
            "--set",
            "run.t_end=300",
            "--set",
            "run.t_warmup=50",
            "--threads",
            threads,
            "--out",
            out.to_str().unwrap(),
        ],
        dir,
    );
    assert!(o.status.success(), "sweep failed: {}", String::from_utf8_lossy(&o.stderr));
    assert!(o.stderr.is_empty(), "no progress bar when stderr is not a terminal");
    let read = |n: &str| std::fs::read_to_string(out.join(n)).unwrap();
    let svg = read("sweep.svg");
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    let json: serde_json::Value = serde_json::from_str(&read("sweep.json")).unwrap();
    let names: Vec<String> =
        std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    assert!(names.iter().all(|n| !n.ends_with(".part")), "{names:?}");
    (read("sweep.csv"), read("runs.csv"), json)
}

#[test]
fn sweep_tables_do_not_depend_on_the_thread_count() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (csv1, runs1, json1) = short_sweep(a.path(), "1");
    let (csv2, runs2, json2) = short_sweep(b.path(), "2");
    assert_eq!(csv1, csv2);
    assert_eq!(runs1, runs2);
    assert_eq!(json1["threads"], 1);
    assert_eq!(json2["threads"], 2);
    assert_eq!(json1["seeds"], json2["seeds"]);
    let lines: Vec<&str> = csv1.lines().collect();
    assert_eq!(lines.len(), 4);
    assert!(lines[0].starts_with("plate.v,replicas,friction_mean,friction_mean_ci95,"));
    assert!(lines[1].starts_with("0.1,3,") && lines[2].starts_with("1,3,") && lines[3].starts_with("8,3,"));
    assert_eq!(runs1.lines().count(), 1 + 9);
}

#[test]
fn every_run_has_its_own_seed() {
    let d = tempfile::tempdir().unwrap();
    let (_, runs, json) = short_sweep(d.path(), "2");
    let seeds: Vec<u64> = json["seeds"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r.as_array().unwrap().clone())
        .map(|s| s.as_u64().unwrap())
        .collect();
    assert_eq!(seeds.len(), 9);
    let mut u = seeds.clone();
    u.sort_unstable();
    u.dedup();
    assert_eq!(u.len(), 9, "{seeds:?}");
    // runs.csv holds the same seeds in the same order (value-major).
    let from_csv: Vec<u64> = runs.lines().skip(1).map(|l| l.split(',').nth(2).unwrap().parse().unwrap()).collect();
    assert_eq!(from_csv, seeds);
    // None is the scene's own seed reused.
    assert!(!seeds.contains(&1));
}

/// Runs the binary in a fresh directory and checks the bad-input contract.
fn expect_bad_input(args: &[&str], mentions: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(fig2(), dir.path().join("fig2.toml")).unwrap();
    let mut all = vec!["sweep", "fig2.toml"];
    all.extend_from_slice(args);
    let o = stickslip(&all, dir.path());
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: one line expected, got {stderr:?}");
    assert!(stderr.starts_with("error: ") && !stderr.contains("panicked"), "{stderr}");
    for m in mentions {
        assert!(stderr.contains(m), "{args:?}: {stderr:?} does not mention {m:?}");
    }
    assert!(o.stdout.is_empty());
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left, vec![std::ffi::OsString::from("fig2.toml")], "{args:?}: something was written");
}

#[test]
fn bad_sweep_arguments_are_refused() {
    let v = ["--param", "plate.v"];
    let with =
        |extra: &[&'static str]| -> Vec<&'static str> { v.iter().copied().chain(extra.iter().copied()).collect() };
    expect_bad_input(&with(&["--values", "0.1,abc"]), &["--values", "abc"]);
    expect_bad_input(&with(&["--values", "0.1,,1"]), &["--values"]);
    expect_bad_input(&with(&["--values", ""]), &["--values"]);
    expect_bad_input(&with(&["--values", "1,inf"]), &["--values", "inf"]);
    expect_bad_input(&with(&["--values", "0.1,-2"]), &["plate.v", "-2", ">= 0"]);
    expect_bad_input(&with(&["--log-range", "0:1:5"]), &["--log-range", "0:1:5", "> 0"]);
    expect_bad_input(&with(&["--log-range", "1:0.1:5"]), &["--log-range", "less than"]);
    expect_bad_input(&with(&["--log-range", "-1:1:5"]), &["--log-range", "-1:1:5", "> 0"]);
    expect_bad_input(&with(&["--log-range", "0.1:1:1"]), &["--log-range", "COUNT"]);
    expect_bad_input(&with(&["--log-range", "0.1:1:0"]), &["--log-range", "COUNT"]);
    expect_bad_input(&with(&["--log-range", "0.1:x:3"]), &["--log-range", "HI"]);
    expect_bad_input(&with(&["--log-range", "0.1:1"]), &["--log-range"]);
    expect_bad_input(&with(&["--range", "a:1:3"]), &["--range", "LO"]);
    expect_bad_input(&with(&["--values", "1", "--replicas", "0"]), &["--replicas"]);
    expect_bad_input(&with(&["--values", "1", "--threads", "0"]), &["--threads"]);
    expect_bad_input(&with(&["--values", "-1,1", "--log-x"]), &["--log-x", "-1"]);
    expect_bad_input(&with(&["--values", "1", "--log-range", "1:2:3"]), &["--values"]);
    expect_bad_input(&with(&[]), &["--values"]);
    expect_bad_input(&["--param", "plate", "--values", "1"], &["--param", "plate", "SECTION.KEY"]);
    expect_bad_input(&["--param", "plate.vv", "--values", "1"], &["--param", "plate.vv", "fields"]);
    expect_bad_input(&["--param", "plates.v", "--values", "1"], &["--param", "plates"]);
    expect_bad_input(&["--param", "run.seed", "--values", "1,2"], &["run.seed"]);
    expect_bad_input(&["--param", "junctions.n", "--values", "10.5"], &["junctions.n", "10.5"]);
    expect_bad_input(&["--param", "junctions.temperature", "--values", "1,0"], &["junctions.temperature", "0"]);
    // The fixed engine's Park-Miller cycle holds 119 replicas of fig2's 300 junctions over
    // 60000 steps (18000300 draws each), not 120.
    expect_bad_input(
        &["--set", "run.engine=fixed", "--param", "plate.v", "--values", "1,2", "--replicas", "120"],
        &["--replicas 120: at plate.v = 1 ", "120 x 18000300 Park-Miller draws", "--set fixed.rng=pcg"],
    );
}

#[test]
fn bad_map_arguments_are_refused() {
    let two = |extra: &[&'static str]| -> Vec<&'static str> {
        ["--param", "plate.v", "--values", "0.5,1", "--param", "plate.k"]
            .iter()
            .copied()
            .chain(extra.iter().copied())
            .collect()
    };
    // The second field without values, with two lists for one field, three fields.
    expect_bad_input(&two(&[]), &["plate.k", "--values"]);
    expect_bad_input(&two(&["--values", "5", "--range", "1:2:3"]), &["--range"]);
    expect_bad_input(&two(&["--values", "5", "--param", "plate.eta", "--values", "1"]), &["--param", "at most 2"]);
    expect_bad_input(&two(&["--values", "5,x"]), &["--values", "x"]);
    // A value the scene refuses names both fields of its grid point.
    expect_bad_input(&two(&["--values", "5,-2"]), &["plate.v = 0.5", "plate.k = -2", ">= 0"]);
    expect_bad_input(
        &["--param", "plate.v", "--values", "1", "--param", "plate.v", "--values", "2"],
        &["plate.v", "twice"],
    );
    expect_bad_input(&["--param", "plate.v", "--values", "1", "--log-y"], &["--log-y"]);
    expect_bad_input(&two(&["--values", "-1,1", "--log-y"]), &["--log-y", "-1"]);
    expect_bad_input(&two(&["--values", "1", "--replicas", "0"]), &["--replicas"]);
}

/// A 3 x 2 map of the fig2 scene (plate.v x plate.k), 2 replicas, with `threads` threads
/// into `dir/map`: the three tables.
fn short_map(dir: &Path, threads: &str) -> (String, String, serde_json::Value) {
    let out = dir.join("map");
    let o = stickslip(
        &[
            "sweep",
            fig2().to_str().unwrap(),
            "--param",
            "plate.v",
            "--log-range",
            "0.1:10:3",
            "--param",
            "plate.k",
            "--values",
            "15,150",
            "--replicas",
            "2",
            "--set",
            "run.t_end=300",
            "--set",
            "run.t_warmup=50",
            "--threads",
            threads,
            "--out",
            out.to_str().unwrap(),
        ],
        dir,
    );
    assert!(o.status.success(), "map failed: {}", String::from_utf8_lossy(&o.stderr));
    let read = |n: &str| std::fs::read_to_string(out.join(n)).unwrap();
    let svg = read("sweep.svg");
    assert_well_formed_svg(&svg);
    assert!(svg.contains("regime map") && svg.contains("oscillation amplitude per junction"), "{svg}");
    (read("sweep.csv"), read("runs.csv"), serde_json::from_str(&read("sweep.json")).unwrap())
}

#[test]
fn a_map_has_both_fields_as_leading_columns_and_grid_point_seeds() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (csv1, runs1, json) = short_map(a.path(), "1");
    let (csv2, runs2, _) = short_map(b.path(), "2");
    assert_eq!((&csv1, &runs1), (&csv2, &runs2));
    let lines: Vec<&str> = csv1.lines().collect();
    assert_eq!(lines.len(), 1 + 6);
    assert!(lines[0].starts_with("plate.v,plate.k,replicas,friction_mean,"), "{}", lines[0]);
    assert!(
        lines[0]
            .ends_with(",oscillation_amplitude,oscillation_amplitude_ci95,oscillation_period,oscillation_period_ci95")
    );
    // Row-major: the first field varies slowest.
    let lead: Vec<(&str, &str)> = lines[1..]
        .iter()
        .map(|l| {
            let mut f = l.split(',');
            (f.next().unwrap(), f.next().unwrap())
        })
        .collect();
    assert_eq!(lead, [("0.1", "15"), ("0.1", "150"), ("1", "15"), ("1", "150"), ("10", "15"), ("10", "150")]);
    assert_eq!(runs1.lines().count(), 1 + 12);
    // Each row aggregates its own grid point's runs: the mean of runs.csv's friction_mean
    // over the rows with the same two leading values.
    for line in &lines[1..] {
        let f: Vec<&str> = line.split(',').collect();
        let mine: Vec<f64> = runs1
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect::<Vec<_>>())
            .filter(|r| r[0] == f[0] && r[1] == f[1])
            .map(|r| r[4].parse().unwrap())
            .collect();
        assert_eq!(mine.len(), 2);
        let mean = mine.iter().sum::<f64>() / 2.0;
        let row: f64 = f[3].parse().unwrap();
        assert!((row - mean).abs() <= 1e-12 * mean.abs(), "{line}: {row} against {mean}");
    }
    assert_eq!(json["param"], "plate.v");
    assert_eq!(json["param2"], "plate.k");
    assert_eq!(json["values2"], serde_json::json!(["15", "150"]));
    // Grid point g = i * 2 + j gets the seeds of value index g of a 1-D sweep.
    let expected = stickslip::studies::seeds::derive_all(1, 6, 2);
    let seeds: Vec<Vec<u64>> = serde_json::from_value(json["seeds"].clone()).unwrap();
    assert_eq!(seeds, expected);
    let from_runs: Vec<u64> = runs1.lines().skip(1).map(|l| l.split(',').nth(3).unwrap().parse().unwrap()).collect();
    assert_eq!(from_runs, expected.concat());
}

#[test]
fn summaries_run_elsewhere_give_the_same_tables_as_the_command() {
    use stickslip::studies::sweep::{OutcomeError, Sweep, SweepAxis, SweepSpec, ValueSpec, parse_values};
    // The command's tables.
    let dir = tempfile::tempdir().unwrap();
    let (csv, runs, _) = short_map(dir.path(), "2");
    // The same sweep through the library, each run's summary travelling as JSON (as from a
    // cluster), handed back in the order of `runs()`.
    let set = vec!["run.t_end=300".to_string(), "run.t_warmup=50".to_string()];
    let base = Scene::from_file(&fig2(), &set).unwrap();
    let axes = vec![
        SweepAxis {
            param: "plate.v".into(),
            values: parse_values(ValueSpec::LogRange("0.1:10:3")).unwrap(),
            log: true,
        },
        SweepAxis { param: "plate.k".into(), values: parse_values(ValueSpec::List("15,150")).unwrap(), log: false },
    ];
    let sweep = Sweep::prepare(base, SweepSpec { axes, replicas: 2, set }).unwrap();
    let travelled: Vec<String> = sweep
        .runs()
        .map(|run| serde_json::to_string(&stickslip::run_scene(run.scene, None).unwrap()).unwrap())
        .collect();
    let summaries: Vec<stickslip::output::Summary> =
        travelled.iter().map(|j| serde_json::from_str(j).unwrap()).collect();
    let outcome = sweep.outcome(summaries.clone()).unwrap();
    assert_eq!(outcome.sweep_csv(&sweep), csv);
    assert_eq!(outcome.runs_csv(&sweep), runs);
    // Out of order, or missing one: refused, not a wrong table.
    let mut swapped = summaries.clone();
    swapped.swap(0, 1);
    assert!(matches!(sweep.outcome(swapped), Err(OutcomeError::Order { position: 0, point: 0, replica: 0, .. })));
    assert!(matches!(sweep.outcome(summaries[1..].to_vec()), Err(OutcomeError::Count { expected: 12, got: 11 })));
}

fn fig2_at(v: &str) -> Scene {
    let o: Vec<String> = [
        format!("plate.v={v}"),
        "run.t_end=1000".into(),
        "run.t_warmup=200".into(),
        "output.trace=false".into(),
        "output.plot=false".into(),
    ]
    .to_vec();
    Scene::from_file(&fig2(), &o).unwrap()
}

#[test]
fn fig2_is_smooth_at_low_velocity_although_its_velocity_fluctuates_by_more_than_v() {
    // Below V0 = 0.5 the plate's velocity jitters by about +-2 V (event noise), so the
    // velocity hysteresis (a supporting sign only) sees many "slips"; the friction has no
    // coherent period, so the run is smooth.
    for seed in [1u64, 2, 3] {
        let mut s = fig2_at("0.1");
        s.run.seed = seed;
        let d = verdict(&s);
        assert!(d.oscillation.slips >= 20, "seed {seed}: {} slips", d.oscillation.slips);
        assert!(d.oscillation.oscillation_coherence < MIN_COHERENCE, "seed {seed}: {d:?}");
        assert_eq!(d.regime, Regime::Smooth, "seed {seed}");
    }
}

#[test]
fn fig2_is_stick_slip_at_intermediate_velocity_and_smooth_at_high_velocity() {
    for seed in [1u64, 2, 3] {
        let mut s = fig2_at("1");
        s.run.seed = seed;
        let d = verdict(&s);
        // About one cycle per 11 time units, the friction swinging by about +-0.2 per
        // junction around 0.65, the plate stuck a third of the time (a sawtooth).
        let o = &d.oscillation;
        assert_eq!(d.regime, Regime::StickSlip, "seed {seed}: {d:?}");
        assert!((10.0..12.5).contains(&o.oscillation_period.unwrap()), "seed {seed}: {o:?}");
        assert!((0.12..0.3).contains(&(o.oscillation_amplitude / 300.0)), "seed {seed}: {o:?}");
        assert!(o.stuck_fraction > 0.2, "seed {seed}: stuck {}", o.stuck_fraction);
        assert!(d.cycles >= 60, "seed {seed}: {} cycles", d.cycles);
        let summary = stickslip::run_scene(&s, None).unwrap();
        assert_eq!(summary.regime, Regime::StickSlip);
        assert_eq!(summary.stick_slip_cycles, d.cycles);
        assert_eq!(&summary.oscillation, o);

        let mut s = fig2_at("10");
        s.run.seed = seed;
        let d = verdict(&s);
        assert_eq!((d.oscillation.slips, d.regime), (0, Regime::Smooth), "seed {seed}");
    }
}

#[test]
fn trace_svg_is_written_when_asked_and_only_then() {
    let dir = tempfile::tempdir().unwrap();
    let scene = fig2();
    let scene = scene.to_str().unwrap();
    let short = ["--set", "run.t_end=100", "--set", "run.t_warmup=10"];
    let run = |out: &str, extra: &[&str]| {
        let mut a = vec!["run", scene, "--out", out];
        a.extend_from_slice(&short);
        a.extend_from_slice(extra);
        stickslip(&a, dir.path())
    };
    let o = run("plot", &[]); // fig2.toml sets output.plot = true
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let svg = std::fs::read_to_string(dir.path().join("plot/trace.svg")).unwrap();
    assert_well_formed_svg(&svg);
    assert!(svg.contains("friction per junction") && svg.contains("attached fraction"));
    assert!(!dir.path().join("plot/trace.svg.part").exists());
    // Same scene and seed: the same bytes.
    assert!(run("plot2", &[]).status.success());
    assert_eq!(svg, std::fs::read_to_string(dir.path().join("plot2/trace.svg")).unwrap());

    let o = run("noplot", &["--set", "output.plot=false"]);
    assert!(o.status.success());
    assert!(dir.path().join("noplot/trace.csv").exists());
    assert!(!dir.path().join("noplot/trace.svg").exists());

    let o = run("refused", &["--set", "output.trace=false"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("output.plot") && stderr.contains("output.trace"), "{stderr}");
    assert!(!dir.path().join("refused").exists());
}

#[test]
fn the_fig1_trace_plot_is_well_formed() {
    // The letter's own scene at its own step, with the fixed engine.
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/fig1.toml");
    let o = stickslip(&["run", scene.to_str().unwrap(), "--set", "output.plot=true", "--out", "f"], dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_well_formed_svg(&std::fs::read_to_string(dir.path().join("f/trace.svg")).unwrap());
}
