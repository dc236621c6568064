//! Bad input to the `stickslip` binary: bad scene files, bad `--set` overrides, bad
//! arguments, unreadable scenes and unwritable output directories.
//!
//! Every case must exit with code 2, print exactly one line on stderr naming the field (or
//! the file position, or the argument) and the offending value, print nothing on stdout,
//! never panic, and leave no output directory or file behind. These tests need no engine:
//! bad input is refused before any engine is built.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

/// A valid scene for the fixed engine (the letter's Fig. 1, shortened).
const GOOD: &str = r#"
[junctions]
n = 30
bond = "strong"
[plate]
mass = 75.0
eta = 75.0
[run]
engine = "fixed"
t_end = 10.0
seed = 1
[fixed]
dt = 1.0
rng = "park-miller"
"#;

/// Every file and directory under `root`, relative to it, sorted.
fn tree(root: &Path) -> Vec<PathBuf> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            out.push(p.strip_prefix(root).unwrap().to_path_buf());
            if p.is_dir() && !p.is_symlink() {
                walk(root, &p, out);
            }
        }
    }
    let mut out = Vec::new();
    walk(root, root, &mut out);
    out.sort();
    out
}

/// Runs the binary in `dir` and checks the bad-input contract; returns the stderr line.
fn expect_bad_input_in(dir: &Path, args: &[&str], mentions: &[&str]) -> String {
    let before = tree(dir);
    let out: Output = Command::new(BIN).args(args).current_dir(dir).output().expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    assert_eq!(out.status.code(), Some(2), "{args:?}: exit status {:?}, stderr {stderr:?}", out.status);
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{args:?}: stderr must be exactly one line, got {stderr:?}");
    assert!(stderr.ends_with('\n'), "{args:?}: stderr line is not terminated: {stderr:?}");
    let line = lines[0];
    assert!(line.starts_with("error: "), "{args:?}: {line:?}");
    for m in mentions {
        assert!(line.contains(m), "{args:?}: the message {line:?} does not mention {m:?}");
    }
    assert!(stdout.is_empty(), "{args:?}: nothing may be printed on stdout, got {stdout:?}");
    assert_eq!(tree(dir), before, "{args:?}: files or directories were created or removed");
    line.to_string()
}

/// Writes `text` as `scene.toml` in a fresh directory and checks both `run` (whose default
/// output directory `out/scene/` would be created in that directory) and `validate`.
pub(crate) fn expect_bad_scene(text: &str, mentions: &[&str]) -> String {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), text).unwrap();
    let line = expect_bad_input_in(dir.path(), &["run", "scene.toml"], mentions);
    let line2 = expect_bad_input_in(dir.path(), &["validate", "scene.toml"], mentions);
    assert_eq!(line, line2, "run and validate report the same error");
    // With an explicit output directory too.
    let out = dir.path().join("results");
    expect_bad_input_in(dir.path(), &["run", "scene.toml", "--out", out.to_str().unwrap()], mentions);
    assert!(!out.exists());
    line
}

/// `GOOD` with one line appended to the section `section` (TOML allows a section once, so
/// the line is inserted right after the header).
fn good_with(section: &str, line: &str) -> String {
    let header = format!("[{section}]\n");
    if GOOD.contains(&header) {
        GOOD.replacen(&header, &format!("{header}{line}\n"), 1)
    } else {
        format!("{GOOD}{header}{line}\n")
    }
}

/// Runs with the valid scene and extra arguments, in a fresh directory.
fn expect_bad_args(extra: &[&str], mentions: &[&str]) -> String {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), GOOD).unwrap();
    let mut args = vec!["run", "scene.toml"];
    args.extend_from_slice(extra);
    expect_bad_input_in(dir.path(), &args, mentions)
}

#[test]
fn the_good_scene_is_valid() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), GOOD).unwrap();
    let out = Command::new(BIN).args(["validate", "scene.toml"]).current_dir(dir.path()).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.stderr.is_empty());
}

// ---- scene files -------------------------------------------------------------------------

#[test]
fn toml_syntax_error_names_the_file_position() {
    let line = expect_bad_scene("[junctions]\nn = [\n", &["scene.toml:2:", "TOML syntax error"]);
    assert!(line.contains("scene.toml:2:"), "{line}");
    expect_bad_scene("[plate\nk = 1\n", &["scene.toml:1:", "TOML syntax error"]);
    expect_bad_scene("[plate]\nk = 1\nk = 2\n", &["scene.toml:3:", "TOML syntax error"]);
    expect_bad_scene("[junctions]\nbond = strong\n", &["scene.toml:2:", "TOML syntax error"]);
}

#[test]
fn unknown_key() {
    expect_bad_scene(&good_with("junctions", "kapa = 0.1"), &["junctions.kapa", "unknown field"]);
    expect_bad_scene(&good_with("output", "svg = true"), &["output.svg", "unknown field"]);
}

#[test]
fn unknown_section() {
    expect_bad_scene(&format!("{GOOD}\n[junction]\nn = 3\n"), &["junction", "unknown field"]);
    expect_bad_scene("[plate.extra]\nk = 1\n", &["plate.extra", "unknown field"]);
}

#[test]
fn wrong_type() {
    expect_bad_scene(&good_with("plate", "k = \"stiff\""), &["plate.k", "stiff"]);
    expect_bad_scene("[junctions]\nn = 2.5\n", &["junctions.n", "2.5"]);
    expect_bad_scene("[output]\ntrace = 1\n", &["output.trace", "1"]);
    expect_bad_scene("plate = 5\n", &["plate", "5"]);
}

#[test]
fn negative_values() {
    expect_bad_scene(&good_with("plate", "k = -150.0"), &["plate.k", "-150"]);
    expect_bad_scene("[junctions]\nkappa = -0.1\n", &["junctions.kappa", "-0.1"]);
    expect_bad_scene("[run]\nt_end = -1.0\n", &["run.t_end", "-1"]);
    expect_bad_scene("[junctions]\nn = -3\n", &["junctions.n", "-3"]);
    expect_bad_scene("[run]\nseed = -1\n", &["run.seed", "-1"]);
}

#[test]
fn nan_and_infinity() {
    expect_bad_scene("[junctions]\nkappa = nan\n", &["junctions.kappa", "NaN"]);
    expect_bad_scene("[plate]\nv = inf\n", &["plate.v", "inf"]);
    expect_bad_scene("[plate]\neta = -inf\n", &["plate.eta", "-inf"]);
    expect_bad_scene("[fixed]\ndt = nan\n", &["fixed.dt", "NaN"]);
    expect_bad_scene("[exact]\nrtol = nan\n", &["exact.rtol", "NaN"]);
}

#[test]
fn zero_junctions() {
    expect_bad_scene(&good_with("junctions", "").replace("n = 30", "n = 0"), &["junctions.n", "0"]);
}

#[test]
fn park_miller_seed_out_of_range_with_the_fixed_engine() {
    expect_bad_scene(&GOOD.replace("seed = 1", "seed = 0"), &["run.seed = 0", "Park-Miller"]);
    expect_bad_scene(&GOOD.replace("seed = 1", "seed = 2147483647"), &["run.seed = 2147483647", "Park-Miller"]);
}

#[test]
fn warmup_not_before_the_end() {
    expect_bad_scene(&good_with("run", "t_warmup = 10.0"), &["run.t_warmup", "10", "run.t_end"]);
    expect_bad_scene(&good_with("run", "t_warmup = 50.0"), &["run.t_warmup", "50"]);
}

/// A fixed-step run steps up to `t_end - 1e-9 dt`: a shorter run, or a window that starts
/// after that, holds no step (its averages would be 0 / 0, a NaN), and is refused; just
/// inside the bounds the run takes its step.
#[test]
fn fixed_step_window_without_a_step() {
    let short = |t: &str| GOOD.replace("t_end = 10.0", &format!("t_end = {t}"));
    expect_bad_scene(&short("1e-300"), &["run.t_end = 1e-300", "fixed.dt", "no step"]);
    expect_bad_scene(&short("1e-9"), &["run.t_end = 0.000000001", "fixed.dt"]);
    let late = good_with("run", "t_warmup = 9.9999999995");
    expect_bad_scene(&late, &["run.t_warmup = 9.9999999995", "9.999999999", "no step"]);
    for text in [short("2e-9"), good_with("run", "t_warmup = 9.9999999985")] {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("scene.toml"), text).unwrap();
        let out = Command::new(BIN).args(["run", "scene.toml", "--out", "o"]).current_dir(dir.path()).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let summary = std::fs::read_to_string(dir.path().join("o/summary.json")).unwrap();
        assert!(summary.contains("\"friction_std\": 0"), "{summary}");
    }
}

/// Totals over the junctions must be numbers: the plate's stiffness with every junction
/// attached (`K + kappa N` overflowed into a panic of the closed-form plate), and the
/// expected junction events (a run of `inf` events never ends).
#[test]
fn totals_over_the_junctions_are_finite() {
    let exact = GOOD.replace("engine = \"fixed\"", "engine = \"exact\"");
    let kappa = good_with("junctions", "kappa = 1e308").replace("engine = \"fixed\"", "engine = \"exact\"");
    expect_bad_scene(&kappa, &["junctions.kappa = 1e308", "plate.k + junctions.kappa N", "N = 30"]);
    let rates = exact.replace("[junctions]\n", "[junctions]\nk0 = 1e300\nkon0 = 1e300\n");
    expect_bad_scene(&rates, &["run.t_end = 10", "junction events", "1e15"]);
    let long = exact.replace("t_end = 10.0", "t_end = 1e16").replace("[junctions]\n", "[junctions]\nk0 = 10.0\n");
    expect_bad_scene(&long, &["run.t_end = 10000000000000000", "5.9e16 junction events"]);
}

/// A value too long for `{}` (beyond 20 characters) is shown in exponent form.
#[test]
fn huge_and_tiny_values_are_shown_short() {
    expect_bad_scene(&GOOD.replace("mass = 75.0", "mass = -1e300"), &["plate.mass = -1e300:"]);
    expect_bad_scene(&good_with("run", "t_warmup = 1e300"), &["run.t_warmup = 1e300:", "(10)"]);
}

#[test]
fn massless_plate_without_damping() {
    let text = GOOD.replace("mass = 75.0", "mass = 0.0").replace("eta = 75.0", "eta = 0.0");
    expect_bad_scene(&text, &["plate.eta", "0", "plate.mass"]);
}

#[test]
fn unknown_enum_words() {
    expect_bad_scene(&GOOD.replace("bond = \"strong\"", "bond = \"medium\""), &["junctions.bond", "medium"]);
    expect_bad_scene(&good_with("fixed", "flip = \"sometimes\""), &["fixed.flip", "sometimes"]);
    expect_bad_scene(&GOOD.replace("engine = \"fixed\"", "engine = \"turbo\""), &["run.engine", "turbo"]);
}

#[test]
fn other_ranges() {
    expect_bad_scene("[fixed]\ndt = 0.0\n", &["fixed.dt", "0"]);
    expect_bad_scene("[output]\nsample_dt = 0.0\n", &["output.sample_dt", "0"]);
    expect_bad_scene("[junctions]\ntemperature = 0.0\n", &["junctions.temperature", "0"]);
    expect_bad_scene("[junctions]\nl0 = 0.0\n", &["junctions.l0", "0"]);
    expect_bad_scene("[junctions]\ntau0 = 0.0\n", &["junctions.tau0", "0"]);
    expect_bad_scene("[exact]\nrtol = 0.5\n", &["exact.rtol", "0.5"]);
    expect_bad_scene("[exact]\natol = 0.0\n", &["exact.atol", "0"]);
    expect_bad_scene(
        "[junctions]\ninitial = \"stationary\"\nk0 = 0.0\nkon0 = 0.0\n",
        &["junctions.initial", "stationary"],
    );
    expect_bad_scene("[run]\nengine = \"fixed\"\nt_end = 1e16\n[fixed]\ndt = 1.0\n", &["fixed.dt", "steps"]);
    expect_bad_scene("[run]\nt_end = 1e12\n[output]\nsample_dt = 1.0\n", &["output.sample_dt", "samples"]);
}

#[test]
fn a_key_with_a_line_break_still_gives_one_line() {
    expect_bad_scene("[junctions]\n\"ka\\nppa\" = 1.0\n", &["junctions.ka\\nppa", "unknown field"]);
}

// ---- files and directories ---------------------------------------------------------------

#[test]
fn missing_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    expect_bad_input_in(dir.path(), &["run", "nope.toml"], &["nope.toml", "cannot read"]);
    expect_bad_input_in(dir.path(), &["validate", "nope.toml"], &["nope.toml", "cannot read"]);
}

#[test]
fn scene_path_is_a_directory() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("scenes")).unwrap();
    expect_bad_input_in(dir.path(), &["run", "scenes"], &["scenes", "cannot read"]);
}

#[test]
fn output_directory_under_a_regular_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), GOOD).unwrap();
    std::fs::write(dir.path().join("plain-file"), b"keep me").unwrap();
    expect_bad_input_in(dir.path(), &["run", "scene.toml", "--out", "plain-file/results"], &["plain-file/results"]);
    expect_bad_input_in(dir.path(), &["run", "scene.toml", "--out", "plain-file"], &["plain-file"]);
    assert_eq!(std::fs::read(dir.path().join("plain-file")).unwrap(), b"keep me");
}

#[test]
fn output_directory_that_cannot_be_written() {
    // Reported before the run starts, in one line naming the directory; works as root too
    // (nobody can create a directory under /proc).
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), GOOD).unwrap();
    for extra in [&[][..], &["--checkpoint-every", "1"][..]] {
        let mut args = vec!["run", "scene.toml", "--out", "/proc/stickslip-no/results"];
        args.extend_from_slice(extra);
        expect_bad_input_in(dir.path(), &args, &["output directory /proc/stickslip-no/results", "cannot create"]);
    }
    // A directory without write permission (meaningless as root, who may write anyway).
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } != 0 {
        use std::os::unix::fs::PermissionsExt;
        let ro = dir.path().join("read-only");
        std::fs::create_dir(&ro).unwrap();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
        expect_bad_input_in(dir.path(), &["run", "scene.toml", "--out", "read-only"], &["read-only", "cannot write"]);
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
}

// ---- overrides and arguments -------------------------------------------------------------

#[test]
fn malformed_set() {
    expect_bad_args(&["--set", "plate.v"], &["--set plate.v", "section.key=value"]);
    expect_bad_args(&["--set", "v=0.1"], &["--set v=0.1", "section.key=value"]);
    expect_bad_args(&["--set", "plate.v="], &["--set plate.v=", "empty"]);
    expect_bad_args(&["--set", "junctions=5"], &["--set junctions=5"]);
    expect_bad_args(&["--set"], &["--set"]);
}

#[test]
fn set_with_unknown_key_or_section() {
    expect_bad_args(&["--set", "plate.speed=0.1"], &["plate.speed", "unknown field"]);
    expect_bad_args(&["--set", "platter.v=0.1"], &["platter", "unknown field"]);
}

#[test]
fn set_with_bad_value() {
    expect_bad_args(&["--set", "plate.v=fast"], &["plate.v", "fast"]);
    expect_bad_args(&["--set", "plate.v=-0.5"], &["plate.v", "-0.5"]);
    expect_bad_args(&["--set", "plate.v=nan"], &["plate.v", "NaN"]);
    expect_bad_args(&["--set", "junctions.n=0"], &["junctions.n", "0"]);
    expect_bad_args(&["--set", "junctions.bond=medium"], &["junctions.bond", "medium"]);
    expect_bad_args(&["--set", "run.seed=0"], &["run.seed", "0"]);
    // A number TOML cannot hold is refused as a number, not read as a string.
    for big in ["plate.v=1e400", "run.seed=9223372036854775808", "junctions.n=99999999999999999999"] {
        let line = expect_bad_args(&["--set", big], &[&format!("--set {big}: not a TOML number")]);
        assert!(!line.contains("string"), "{line}");
    }
    // A later override is checked too, and the first bad one is reported.
    expect_bad_args(&["--set", "plate.v=0.1", "--set", "plate.k=-1"], &["plate.k", "-1"]);
}

#[test]
fn seed_flag() {
    expect_bad_args(&["--seed", "abc"], &["--seed", "abc"]);
    expect_bad_args(&["--seed", "-1"], &["-1"]);
    expect_bad_args(&["--seed", "99999999999999999999"], &["--seed", "99999999999999999999"]);
    // A u64 beyond the TOML integers run.seed takes: refused as the flag's value (it was
    // refused as `run.seed: invalid type: string "18446744073709551615"`).
    for big in ["9223372036854775808", "18446744073709551615"] {
        let line = expect_bad_args(&["--seed", big], &["--seed", big, "0..=9223372036854775807"]);
        assert!(!line.contains("string"), "{line}");
    }
    // A number, but not a Park-Miller seed: checked like the scene field it overrides.
    expect_bad_args(&["--seed", "0"], &["run.seed", "0"]);
    expect_bad_args(&["--seed", "2147483647"], &["run.seed", "2147483647"]);
}

#[test]
fn engine_flag() {
    expect_bad_args(&["--engine", "turbo"], &["--engine", "turbo", "exact", "fixed"]);
}

#[test]
fn unknown_and_missing_arguments() {
    let dir = tempfile::tempdir().unwrap();
    expect_bad_args(&["--bogus"], &["--bogus"]);
    expect_bad_args(&["extra.toml"], &["extra.toml"]);
    expect_bad_input_in(dir.path(), &["run"], &["<SCENE>"]);
    expect_bad_input_in(dir.path(), &["validate"], &["<SCENE>"]);
    expect_bad_input_in(dir.path(), &[], &["run", "validate"]);
    expect_bad_input_in(dir.path(), &["simulate", "scene.toml"], &["simulate"]);
}

#[test]
fn stability_command_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    expect_bad_input_in(dir.path(), &["stability", "nope.toml"], &["nope.toml"]);
    std::fs::write(dir.path().join("scene.toml"), GOOD).unwrap();
    expect_bad_input_in(dir.path(), &["stability", "scene.toml", "--set", "fixed.dt=-1"], &["fixed.dt", "-1"]);
    expect_bad_input_in(dir.path(), &["stability", "scene.toml", "--set", "plate.v"], &["--set plate.v"]);
}

/// A fixed-step run beyond the stability limit prints one warning line
/// on stderr and still runs; below the limit it prints none.
#[test]
fn unstable_fixed_step_warns_on_stderr() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), GOOD).unwrap();
    let out = Command::new(BIN).args(["run", "scene.toml"]).current_dir(dir.path()).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let warnings: Vec<&str> = stderr.lines().filter(|l| l.starts_with("warning: ")).collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(warnings[0].contains("fixed.dt = 1") && warnings[0].contains("stability limit"), "{}", warnings[0]);
    let out = Command::new(BIN)
        .args(["run", "scene.toml", "--set", "fixed.dt=0.5"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
    // `stability` prints every integrator's limit.
    let out = Command::new(BIN).args(["stability", "scene.toml"]).current_dir(dir.path()).output().unwrap();
    let table = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0));
    for i in ["semi-implicit-euler *", "explicit-euler", "velocity-verlet", "0.993406"] {
        assert!(table.contains(i), "{i} missing from\n{table}");
    }
}
