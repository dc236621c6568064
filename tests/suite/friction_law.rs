//! `stickslip friction-law`: a friction law for continuum codes from a V-T map.
//!
//! - the Abaqus `*FRICTION` data lines and the Ansys `TBFIELD`/`TBDATA` blocks, read back
//!   into numbers, are the steady rows of `law.csv` (the same doubles, the same order), and
//!   the unit conversions hold (`V l0 / t0` m/s, `T T_ref` K, `mu = F kB T_ref / l0 / L`,
//!   with `F` the mean over replicas of `runs.csv`'s `friction_mean`);
//! - a point in stick-slip has no `mu` in `law.csv`, is in neither export (but named in
//!   their comments and in `law.json`);
//! - `--from` a finished sweep's directory writes the bytes the command writes when it runs
//!   the same map itself;
//! - the fitted form recovers known coefficients from exact synthetic data, and on data with
//!   Gaussian noise of known standard deviation its 95 % intervals cover the truth 95 % of the
//!   time and its chi-square averages its degrees of freedom;
//! - a law that cannot be written (a file's name taken by a directory) replaces none of the
//!   old law's files and leaves no `.part`;
//! - bad input (a missing scale, a bad scale, a sweep not over V and T, an unfinished sweep,
//!   an empty directory, fields not V and T when it runs the map) is one line on stderr naming
//!   the option or the directory, exit code 2, and nothing written.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use stickslip::observe::regime::Regime;
use stickslip::studies::law::{BOLTZMANN, FrictionLaw, LawInput, PointRuns, RunRecord, ScaleArgs, fit};

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

fn stickslip(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("the binary runs")
}

const SCALES: [&str; 8] = ["--l0", "2e-9", "--t0", "3e-6", "--t-ref", "300", "--normal-load", "1e-9"];
const L0: f64 = 2e-9;
const T0: f64 = 3e-6;
const T_REF: f64 = 300.0;
const LOAD: f64 = 1e-9;
/// Weak bonds (temperature matters), short runs: sliding at V = 0.1 and 10, stick-slip at
/// V = 1 and T = 2.
const SET: [&str; 6] = ["--set", "run.t_end=300", "--set", "run.t_warmup=100", "--set", "junctions.bond=weak"];
const AXES: [&str; 8] =
    ["--param", "plate.v", "--values", "0.1,1,10", "--param", "junctions.temperature", "--values", "0.5,2"];

/// The map run by `friction-law` into `out`.
fn run_law(out: &Path) -> Output {
    let o = out.display().to_string();
    let mut args = vec!["friction-law", fig2_static()];
    args.extend(SET);
    args.extend(AXES);
    args.extend(["--replicas", "2", "--out", &o]);
    args.extend(SCALES);
    stickslip(&args)
}

/// The fig2 scene's path.
fn fig2_static() -> &'static str {
    concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/fig2.toml")
}

fn table(path: &Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(str::to_string).collect();
    lines.map(|l| header.iter().cloned().zip(l.split(',').map(str::to_string)).collect()).collect()
}

fn num(s: &str) -> f64 {
    s.trim().parse().unwrap_or_else(|_| panic!("'{s}' is not a number"))
}

/// `(mu, slip rate, temperature)` of every Abaqus `*FRICTION` data line.
fn abaqus_rows(text: &str) -> Vec<[f64; 3]> {
    let mut rows = Vec::new();
    let mut inside = false;
    for line in text.lines().filter(|l| !l.starts_with("**")) {
        if line.starts_with('*') {
            inside = line.trim().eq_ignore_ascii_case("*FRICTION");
            continue;
        }
        assert!(inside, "a data line outside *FRICTION: {line}");
        assert!(line.len() <= 256, "an Abaqus input line is at most 256 characters");
        let f: Vec<f64> = line.split(',').map(num).collect();
        assert_eq!(f.len(), 4, "mu, slip rate, contact pressure, temperature: {line}");
        assert_eq!(f[2], 0.0, "no pressure dependence");
        rows.push([f[0], f[1], f[3]]);
    }
    rows
}

/// `(mu, slip rate, temperature)` of every Ansys `TBDATA` with the fields in force.
fn ansys_rows(text: &str) -> Vec<[f64; 3]> {
    let (mut temp, mut slrv, mut rows) = (None, None, Vec::new());
    let mut seen_tb = false;
    for line in text.lines().filter(|l| !l.starts_with('!')) {
        let f: Vec<&str> = line.split(',').collect();
        match f[0] {
            "TB" => {
                assert_eq!(f, ["TB", "FRIC", "1", "", "", "ISO"]);
                seen_tb = true;
            }
            "TBFIELD" if f[1] == "TEMP" => {
                temp = Some(num(f[2]));
                slrv = None;
            }
            "TBFIELD" if f[1] == "SLRV" => slrv = Some(num(f[2])),
            "TBDATA" => {
                assert!(seen_tb && f[1] == "1");
                rows.push([num(f[2]), slrv.take().expect("SLRV before TBDATA"), temp.expect("TEMP before TBDATA")]);
            }
            other => panic!("unexpected command {other}"),
        }
    }
    rows
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

#[test]
fn exports_read_back_match_the_table_and_leave_out_stick_slip() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("law");
    let o = run_law(&out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = table(&out.join("law.csv"));
    let runs = table(&out.join("runs.csv"));
    assert_eq!(rows.len(), 6);
    let force_unit = BOLTZMANN * T_REF / L0;
    let mut expected = Vec::new();
    for r in &rows {
        let (v, t) = (num(&r["plate.v"]), num(&r["junctions.temperature"]));
        // Units.
        assert!(close(num(&r["slip_rate_m_s"]), v * L0 / T0, 1e-15));
        assert!(close(num(&r["temperature_k"]), t * T_REF, 1e-15));
        // The total friction is the mean of the replicas' friction_mean, in newtons.
        let f: Vec<f64> = runs
            .iter()
            .filter(|x| num(&x["plate.v"]) == v && num(&x["junctions.temperature"]) == t)
            .map(|x| num(&x["friction_mean"]))
            .collect();
        assert_eq!(f.len(), 2);
        let mean = (f[0] + f[1]) / 2.0;
        assert!(close(num(&r["friction_n"]), mean * force_unit, 1e-14));
        // Per junction: N = 300 junctions.
        assert!(close(num(&r["friction_per_junction"]) * 300.0, mean, 1e-13));
        // The interval: t_{0.975, 1} |f0 - f1| / 2.
        let half = 12.706204736174698 * (f[0] - f[1]).abs() / 2.0;
        assert!(close(num(&r["friction_n_ci95"]), half * force_unit, 1e-9));
        let steady = r["steady"] == "true";
        let replica_regimes: Vec<&str> = runs
            .iter()
            .filter(|x| num(&x["plate.v"]) == v && num(&x["junctions.temperature"]) == t)
            .map(|x| x["regime"].as_str())
            .collect();
        assert_eq!(steady, replica_regimes.iter().all(|g| *g == "smooth"));
        if steady {
            assert!(close(num(&r["mu"]), mean * force_unit / LOAD, 1e-14));
            assert!(close(num(&r["mu_ci95"]), half * force_unit / LOAD, 1e-9));
            expected.push([num(&r["mu"]), num(&r["slip_rate_m_s"]), num(&r["temperature_k"])]);
        } else {
            assert!(r["mu"].is_empty() && r["mu_ci95"].is_empty(), "a point in stick-slip has no mu");
        }
    }
    let left_out = rows.len() - expected.len();
    assert!(left_out >= 1 && !expected.is_empty(), "the map has steady and stick-slip points");
    let abaqus = std::fs::read_to_string(out.join("abaqus.inp")).unwrap();
    let ansys = std::fs::read_to_string(out.join("ansys.mac")).unwrap();
    // The same doubles in the same order (T ascending, then V): exactly.
    assert_eq!(abaqus_rows(&abaqus), expected);
    assert_eq!(ansys_rows(&ansys), expected);
    for text in [&abaqus, &ansys] {
        assert_eq!(text.matches("left out: V = ").count(), left_out);
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("law.json")).unwrap()).unwrap();
    assert_eq!(json["left_out"].as_array().unwrap().len(), left_out);
    assert_eq!(json["fit"]["residuals"].as_array().unwrap().len(), expected.len());
    assert_eq!(json["units"]["force_unit_n"].as_f64().unwrap(), force_unit);
}

#[test]
fn from_a_finished_sweep_gives_the_files_of_a_map_run_here() {
    let dir = tempfile::tempdir().unwrap();
    let (here, swept, law) = (dir.path().join("here"), dir.path().join("swept"), dir.path().join("law"));
    assert!(run_law(&here).status.success());
    let s = swept.display().to_string();
    let mut args = vec!["sweep", fig2_static()];
    args.extend(SET);
    args.extend(AXES);
    args.extend(["--replicas", "2", "--out", &s]);
    assert!(stickslip(&args).status.success());
    let l = law.display().to_string();
    let mut args = vec!["friction-law", "--from", &s, "--out", &l];
    args.extend(SCALES);
    let o = stickslip(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["law.csv", "abaqus.inp", "ansys.mac", "law.json"] {
        assert_eq!(std::fs::read(here.join(f)).unwrap(), std::fs::read(law.join(f)).unwrap(), "{f}");
    }
}

/// A map of exact `mu(V, T)` as two replicas `mu +- d`, in the model's force units.
fn synthetic(mu: impl Fn(f64, f64) -> f64, d: f64) -> (LawInput, stickslip::studies::law::Scales) {
    let scales =
        ScaleArgs { l0: Some(1e-9), t0: Some(1e-6), t_ref: Some(300.0), normal_load: Some(2.0), force_unit: Some(0.5) }
            .resolve()
            .unwrap();
    let mut points = Vec::new();
    for v in [0.05, 0.2, 0.7, 2.0, 6.0, 20.0] {
        for t in [0.4, 0.8, 1.5, 3.0] {
            // mu = F * 0.5 / 2: F = 4 mu.
            let f = 4.0 * mu(v, t);
            let run = |x: f64| RunRecord { friction_mean: x, friction_per_junction: x / 100.0, regime: Regime::Smooth };
            points.push(PointRuns { v, t, runs: vec![run(f - 4.0 * d), run(f + 4.0 * d)] });
        }
    }
    (LawInput { scene: "synthetic".into(), replicas: 2, points }, scales)
}

#[test]
fn the_fit_recovers_known_coefficients_from_exact_data() {
    // mu = 0.3 - 0.02 x + 0.05 y + 0.004 x^2 - 0.003 x y + 0.01 y^2 + 0.001 V, x = ln V, y = 1/T - 1.
    let truth = [0.3, -0.02, 0.05, 0.004, -0.003, 0.01, 0.001];
    let mu = |v: f64, t: f64| {
        let (x, y) = (v.ln(), 1.0 / t - 1.0);
        truth[0] + truth[1] * x + truth[2] * y + truth[3] * x * x + truth[4] * x * y + truth[5] * y * y + truth[6] * v
    };
    let (input, scales) = synthetic(mu, 1e-3);
    let law = FrictionLaw::new(&input, scales, 2).unwrap();
    let f = law.fit.as_ref().unwrap();
    assert_eq!(f.terms.iter().map(|t| t.name()).collect::<Vec<_>>(), ["1", "x", "y", "x^2", "x*y", "y^2", "V/V0"]);
    for (c, t) in f.coefficients.iter().zip(truth) {
        assert!((c - t).abs() < 1e-12, "{c} against {t}");
    }
    assert!(f.weighted && f.dof == 24 - 7 && f.chi_square.unwrap() < 1e-15);
    // Degree 1 of a degree-1 law: also exact, with the degree-1 terms only.
    let lin = |v: f64, t: f64| 0.2 + 0.01 * v.ln() - 0.04 * (1.0 / t - 1.0);
    let (input, scales) = synthetic(lin, 1e-3);
    let f = FrictionLaw::new(&input, scales, 1).unwrap().fit.unwrap();
    assert_eq!(f.terms.len(), 4);
    for (c, t) in f.coefficients.iter().zip([0.2, 0.01, -0.04, 0.0]) {
        assert!((c - t).abs() < 1e-12, "{c} against {t}");
    }
}

#[test]
fn the_fit_intervals_cover_the_truth_on_noisy_data() {
    // 24 points, sigma 0.01, 7 terms: chi^2 on 17 degrees of freedom. 2000 data sets.
    let truth = [0.3, -0.02, 0.05, 0.004, -0.003, 0.01, 0.001];
    let mut rng = rand_pcg::Pcg64::seed_from_u64(20261127);
    let sigma = 0.01;
    let sets = 2000;
    let (mut covered, mut chi2_sum) = ([0usize; 7], 0.0);
    for _ in 0..sets {
        let mut pts = Vec::new();
        for v in [0.05f64, 0.2, 0.7, 2.0, 6.0, 20.0] {
            for t in [0.4f64, 0.8, 1.5, 3.0] {
                let (x, y) = (v.ln(), 1.0 / t - 1.0);
                let z = truth[0]
                    + truth[1] * x
                    + truth[2] * y
                    + truth[3] * x * x
                    + truth[4] * x * y
                    + truth[5] * y * y
                    + truth[6] * v;
                let e: f64 = StandardNormal.sample(&mut rng);
                pts.push(fit::FitPoint { x, y, z: z + sigma * e, sigma: Some(sigma) });
            }
        }
        let f = fit::fit(&pts, 2).unwrap();
        assert_eq!(f.dof, 17);
        chi2_sum += f.chi_square.unwrap();
        for k in 0..7 {
            let se = f.standard_errors[k].unwrap();
            covered[k] += usize::from((f.coefficients[k] - truth[k]).abs() <= 1.959963984540054 * se);
        }
    }
    // Coverage: binomial(2000, 0.95), standard deviation 0.0049; 4 of them.
    for (k, c) in covered.iter().enumerate() {
        let p = *c as f64 / sets as f64;
        assert!((p - 0.95).abs() < 4.0 * (0.95f64 * 0.05 / sets as f64).sqrt(), "term {k}: coverage {p}");
    }
    // The mean chi-square: 17 with standard deviation sqrt(2 * 17 / 2000); 4 of them.
    let mean = chi2_sum / sets as f64;
    assert!((mean - 17.0).abs() < 4.0 * (34.0f64 / sets as f64).sqrt(), "mean chi-square {mean}");
}

fn assert_refused(o: &Output, mention: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(err.starts_with("error: ") && err.contains(mention), "'{mention}' in {err}");
}

fn law_files_in(dir: &Path) -> Vec<PathBuf> {
    ["law.csv", "abaqus.inp", "ansys.mac", "law.json"].iter().map(|f| dir.join(f)).filter(|p| p.exists()).collect()
}

/// A finished 2-D sweep of two short runs in `out`.
fn vt_sweep(out: &Path) -> PathBuf {
    let o = out.display().to_string();
    let mut args = vec!["sweep", fig2_static()];
    args.extend(SET);
    args.extend(["--param", "plate.v", "--values", "0.1,10", "--param", "junctions.temperature", "--values", "1"]);
    args.extend(["--out", &o]);
    assert!(stickslip(&args).status.success());
    out.to_path_buf()
}

#[test]
fn a_law_that_cannot_be_written_leaves_the_old_one_whole() {
    let dir = tempfile::tempdir().unwrap();
    let vt = vt_sweep(&dir.path().join("vt"));
    let vt_s = vt.display().to_string();
    let mut args = vec!["friction-law", "--from", &vt_s];
    args.extend(SCALES);
    assert!(stickslip(&args).status.success());
    let old: Vec<Vec<u8>> =
        ["law.csv", "ansys.mac", "law.json"].iter().map(|f| std::fs::read(vt.join(f)).unwrap()).collect();
    // abaqus.inp replaced by a directory, and a law of other scales asked for.
    std::fs::remove_file(vt.join("abaqus.inp")).unwrap();
    std::fs::create_dir(vt.join("abaqus.inp")).unwrap();
    let i = args.iter().position(|a| *a == "--l0").unwrap();
    args[i + 1] = "5e-9";
    let o = stickslip(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.lines().count() == 1 && err.contains("abaqus.inp"), "{err}");
    for (f, bytes) in ["law.csv", "ansys.mac", "law.json"].iter().zip(&old) {
        assert_eq!(&std::fs::read(vt.join(f)).unwrap(), bytes, "{f} unchanged");
    }
    let parts: Vec<_> = std::fs::read_dir(&vt)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".part"))
        .collect();
    assert!(parts.is_empty(), "left behind: {parts:?}");
}

#[test]
fn bad_input_is_one_line_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    // A finished 2-D sweep to read from, and a 1-D one.
    let vt = vt_sweep(&dir.path().join("vt"));
    let vt_s = vt.display().to_string();
    let v1 = dir.path().join("v1");
    let v1_s = v1.display().to_string();
    let mut args = vec!["sweep", fig2_static()];
    args.extend(SET);
    args.extend(["--param", "plate.v", "--values", "0.1,10", "--out", &v1_s]);
    assert!(stickslip(&args).status.success());

    // A missing scale, for each one, when running a map: no output directory.
    for (k, option) in ["--l0", "--t0", "--t-ref", "--normal-load"].iter().enumerate() {
        let out = dir.path().join(format!("missing{k}"));
        let o_s = out.display().to_string();
        let mut scales: Vec<&str> = SCALES.to_vec();
        scales.drain(2 * k..2 * k + 2);
        let mut args = vec!["friction-law", fig2_static()];
        args.extend(AXES);
        args.extend(["--out", &o_s]);
        args.extend(scales);
        let o = stickslip(&args);
        assert_refused(&o, &format!("{option}: missing"));
        assert!(!out.exists(), "nothing written for a missing {option}");
        // And reading a sweep: nothing added to it.
        let mut scales: Vec<&str> = SCALES.to_vec();
        scales.drain(2 * k..2 * k + 2);
        let mut args = vec!["friction-law", "--from", &vt_s];
        args.extend(scales);
        assert_refused(&stickslip(&args), &format!("{option}: missing"));
        assert!(law_files_in(&vt).is_empty());
    }
    // A scale that is not a positive number.
    for bad in ["0", "-1", "nan", "inf"] {
        let mut args = vec!["friction-law", "--from", &vt_s];
        args.extend(SCALES);
        let i = args.iter().position(|a| *a == "--t0").unwrap();
        args[i + 1] = bad;
        assert_refused(&stickslip(&args), "--t0");
        assert!(law_files_in(&vt).is_empty());
    }
    // Not a V-T sweep.
    let mut args = vec!["friction-law", "--from", &v1_s];
    args.extend(SCALES);
    assert_refused(&stickslip(&args), "plate.v and junctions.temperature");
    assert!(law_files_in(&v1).is_empty());
    // Fields other than V and T when running the map: refused before anything runs.
    let out = dir.path().join("vk");
    let o_s = out.display().to_string();
    let mut args = vec!["friction-law", fig2_static(), "--param", "plate.v", "--values", "1", "--param", "plate.k"];
    args.extend(["--values", "5,15", "--out", &o_s]);
    args.extend(SCALES);
    assert_refused(&stickslip(&args), "plate.v x plate.k");
    assert!(!out.exists());
    // A grid point that the scales cannot carry: a slip rate that underflows
    // (1e-310 l0 / t0 is subnormal) and a temperature whose 1/T squared overflows; refused
    // before anything runs.
    for (v, t, mention) in [
        ("1e-310,1", "1", "plate.v = 1e-310: the law's slip rate V l0 / t0 would be 6.66"),
        ("1", "1e-200,1", "junctions.temperature = 1e-200: the friction law is fitted in 1/T"),
    ] {
        let mut args = vec!["friction-law", fig2_static(), "--param", "plate.v", "--values", v];
        args.extend(["--param", "junctions.temperature", "--values", t, "--out", &o_s]);
        args.extend(SCALES);
        assert_refused(&stickslip(&args), mention);
        assert!(!out.exists());
    }
    // An unfinished sweep: the journal of the 2-D sweep cut to its header and one run, its
    // tables gone (as a sweep killed after one run leaves it).
    let cut = dir.path().join("cut");
    std::fs::create_dir(&cut).unwrap();
    let journal = std::fs::read_to_string(vt.join("journal.jsonl")).unwrap();
    let two: String = journal.lines().take(2).map(|l| format!("{l}\n")).collect();
    std::fs::write(cut.join("journal.jsonl"), two).unwrap();
    let c_s = cut.display().to_string();
    let mut args = vec!["friction-law", "--from", &c_s];
    args.extend(SCALES);
    assert_refused(&stickslip(&args), "has not finished (1 of 2 runs");
    assert_eq!(std::fs::read_dir(&cut).unwrap().count(), 1, "only the journal");
    // A directory without a sweep, and none at all.
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let e_s = empty.display().to_string();
    let mut args = vec!["friction-law", "--from", &e_s];
    args.extend(SCALES);
    assert_refused(&stickslip(&args), "holds no sweep");
    let none = dir.path().join("none").display().to_string();
    let mut args = vec!["friction-law", "--from", &none];
    args.extend(SCALES);
    assert_refused(&stickslip(&args), "not a directory");
    // And the finished sweep makes a law.
    let mut args = vec!["friction-law", "--from", &vt_s];
    args.extend(SCALES);
    let o = stickslip(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(law_files_in(&vt).len(), 4);
}
