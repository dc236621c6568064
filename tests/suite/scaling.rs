//! `stickslip bench`: a tiny scaling study writes a well-formed `bench.csv` (one line per size
//! and engine, figures consistent with each other and with the estimate) and `bench.svg`;
//! bad options are refused in one line, exit 2, with nothing written.

use std::path::Path;
use std::process::{Command, Output};

use stickslip::Scene;
use stickslip::estimate::Estimate;
use stickslip::estimate::system::MEMORY_ENV;
use stickslip::scene::EngineKind;
use stickslip::studies::scaling;

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

fn scenario(name: &str) -> String {
    format!("{}/scenarios/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn bench(args: &[&str], env: &[(&str, String)]) -> Output {
    let scene = scenario("fig1-exact.toml");
    let mut all = vec!["bench", scene.as_str()];
    all.extend_from_slice(args);
    Command::new(BIN).args(&all).envs(env.iter().map(|(k, v)| (k, v))).output().expect("the binary runs")
}

#[test]
fn a_tiny_bench_writes_a_well_formed_csv_and_svg() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("b");
    let o = bench(
        &["--n-min", "100", "--n-max", "300", "--per-decade", "1", "--work", "20000", "--out", out.to_str().unwrap()],
        &[],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut names: Vec<String> =
        std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    assert_eq!(names, ["bench.csv", "bench.svg"]);

    let csv = std::fs::read_to_string(out.join("bench.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some(scaling::CSV_HEADER));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let base = Scene::from_file(Path::new(&scenario("fig1-exact.toml")), &[]).unwrap();
    let expected = [(100, "exact"), (100, "fixed"), (300, "exact"), (300, "fixed")];
    assert_eq!(rows.len(), expected.len(), "{csv}");
    for (row, &(n, engine)) in rows.iter().zip(&expected) {
        assert_eq!(row.len(), 10, "{row:?}");
        assert_eq!((row[0], row[1].parse::<usize>().unwrap()), (engine, n));
        let num = |i: usize| row[i].parse::<f64>().unwrap_or_else(|_| panic!("column {i} of {row:?}"));
        let (t_end, work, run_seconds, ns, setup) = (num(2), num(4), num(5), num(6), num(7));
        assert!(t_end > 0.0 && work >= 1.0 && run_seconds > 0.0 && setup >= 0.0, "{row:?}");
        assert!((ns - run_seconds * 1e9 / work).abs() <= 1e-9 * ns, "{row:?}");
        // The run's scene, as the study builds it: its estimate and, for the fixed engine,
        // its steps.
        let kind = if engine == "exact" { EngineKind::Exact } else { EngineKind::Fixed };
        let scene = scaling::scene_at(&base, n, kind, Some(t_end)).unwrap();
        assert_eq!(scene.run.t_end, t_end);
        let est = Estimate::of(&scene, false);
        assert_eq!(num(8), est.engine_bytes() as f64 / n as f64, "{row:?}");
        match kind {
            EngineKind::Fixed => {
                assert_eq!(row[3], "junction-step");
                assert_eq!(work as u64, n as u64 * scene.fixed.steps_for(t_end), "{row:?}");
            }
            EngineKind::Exact => assert_eq!(row[3], "event"),
        }
        // Measured memory: a number, or empty where the peak cannot be reset.
        assert!(row[9].is_empty() || num(9) >= 0.0, "{row:?}");
    }

    let svg = std::fs::read_to_string(out.join("bench.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"), "{}", &svg[..100.min(svg.len())]);
    for text in [
        "ns per unit of work",
        "set-up time",
        "memory per junction",
        "exact, ns per event",
        "fixed, ns per junction-step",
    ] {
        assert!(svg.contains(text), "bench.svg lacks {text:?}");
    }
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(stdout.lines().count(), 6, "{stdout}");
}

#[test]
fn bad_bench_options_are_refused_in_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("never");
    let out_s = out.to_str().unwrap().to_string();
    // (arguments, what the error line mentions, environment)
    type Case<'a> = (&'a [&'a str], &'a str, Vec<(&'a str, String)>);
    let cases: [Case; 11] = [
        (&["--n-min", "0"], "--n-min = 0", vec![]),
        (
            &["--n-max", "1000000000000000"],
            "--n-max = 1000000000000000: must be from --n-min (1000) to 4294967295",
            vec![],
        ),
        (&["--work", "1e300"], "--work = 1e300: must be a number of events or junction-steps from 1 to 1e15", vec![]),
        (&["--n-min", "1000", "--n-max", "999"], "--n-max = 999", vec![]),
        (&["--work", "nan"], "--work = NaN", vec![]),
        (&["--work", "0"], "--work = 0", vec![]),
        (&["--t-end", "-1"], "--t-end = -1", vec![]),
        (&["--per-decade", "0"], "--per-decade", vec![]),
        (&["--n-max", "many"], "--n-max", vec![]),
        (&["--n-max", "100000000"], "--n-max = 100000000", vec![(MEMORY_ENV, (1u64 << 30).to_string())]),
        (&[], "--n-min = 1000", vec![(MEMORY_ENV, (1u64 << 20).to_string())]),
    ];
    for (args, mentions, env) in cases {
        let mut all = args.to_vec();
        all.extend(["--out", out_s.as_str()]);
        let o = bench(&all, &env);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(mentions), "{args:?}: {err} does not mention {mentions}");
        assert!(o.stdout.is_empty() && !out.exists(), "{args:?}");
    }
}
