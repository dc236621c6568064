//! Standard output of the `stickslip` binary (`src/cli/stdout.rs`): when it is a pipe whose
//! reader has gone, every command ends quietly, killed by `SIGPIPE` as other Unix tools
//! are (no message, no panic, no backtrace), after completing what comes before its report
//! (a run's files); any other write error is one line on stderr and exit code 1.

use std::io::{BufRead, BufReader};
use std::os::fd::{FromRawFd, OwnedFd};
use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::{Command, ExitStatus, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

/// A pipe: (read end, write end), closed on exec (so that no child holds the read end open).
fn pipe() -> (OwnedFd, OwnedFd) {
    let mut fds = [0; 2];
    // SAFETY: `pipe2` writes two new descriptors into `fds`, owned from here on.
    unsafe {
        assert_eq!(libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC), 0, "pipe: {}", std::io::Error::last_os_error());
        (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1]))
    }
}

fn command(args: &[&str], dir: &Path) -> Command {
    let mut c = Command::new(BIN);
    // A panic would print its backtrace: the checks below would see it.
    c.args(args).current_dir(dir).env("RUST_BACKTRACE", "1").env_remove("STICKSLIP_PROGRESS");
    c
}

/// Runs `args` with stdout a pipe whose read end is closed before the binary starts.
fn with_stdout_closed(args: &[&str], dir: &Path) -> (ExitStatus, String) {
    let (read, write) = pipe();
    drop(read);
    let out = command(args, dir).stdout(Stdio::from(write)).stderr(Stdio::piped()).output().expect("the binary runs");
    (out.status, String::from_utf8_lossy(&out.stderr).into_owned())
}

fn assert_ended_quietly_by_sigpipe(args: &[&str], status: ExitStatus, stderr: &str) {
    assert_eq!(status.signal(), Some(libc::SIGPIPE), "{args:?}: {status:?}, stderr {stderr:?}");
    assert_eq!(stderr, "", "{args:?}: nothing may be printed on stderr");
}

/// Fig. 1 at a stable step (so that `run` prints no warning), short.
const SCENE: &[&str] = &["scene.toml", "--set", "fixed.dt=0.5", "--set", "run.t_end=20"];

fn scene_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), stickslip_testkit::FIG1).unwrap();
    dir
}

fn args<'a>(command: &[&'a str], more: &[&'a str]) -> Vec<&'a str> {
    let mut a = command.to_vec();
    a.extend_from_slice(SCENE);
    a.extend_from_slice(more);
    a
}

#[test]
fn every_command_ends_quietly_on_a_closed_pipe() {
    let dir = scene_dir();
    let d = dir.path();
    let cases: Vec<Vec<&str>> = vec![
        vec!["--help"],
        vec!["--version"],
        vec!["run", "--help"],
        args(&["validate"], &[]),
        args(&["stability"], &[]),
        args(&["run"], &["--out", "run"]),
        vec!["resume", "run"],
        args(&["sweep"], &["--param", "plate.v", "--values", "0.1,0.2", "--out", "sweep"]),
        args(&["compare"], &["--dts", "1,0.5", "--replicas", "2", "--ref-replicas", "2", "--out", "compare"]),
    ];
    for a in &cases {
        let (status, stderr) = with_stdout_closed(a, d);
        assert_ended_quietly_by_sigpipe(a, status, &stderr);
    }
    // What comes before the report is complete: the run's files, the studies' files.
    for f in ["run/summary.json", "run/trace.csv", "sweep/sweep.csv", "compare/compare.md"] {
        assert!(d.join(f).is_file(), "{f} is missing");
    }
    assert!(!d.join("run/trace.csv.part").exists());
}

#[test]
fn a_pipe_closed_while_the_report_is_written_ends_it_quietly() {
    // 300 sweep values print about 25 KB, line by line, into a pipe of one page: the
    // binary blocks on a write, the reader takes the first line and goes away.
    let dir = scene_dir();
    let a = args(&["sweep"], &["--set", "junctions.n=10", "--param", "plate.v", "--range", "0.01:3:300", "--out", "s"]);
    let (read, write) = pipe();
    // SAFETY: fcntl on a descriptor we own.
    let size = unsafe { libc::fcntl(std::os::fd::AsRawFd::as_raw_fd(&write), libc::F_SETPIPE_SZ, 4096) };
    assert!(size >= 4096, "F_SETPIPE_SZ: {}", std::io::Error::last_os_error());
    let child = command(&a, dir.path()).stdout(Stdio::from(write)).stderr(Stdio::piped()).spawn().unwrap();
    let mut reader = BufReader::new(std::fs::File::from(read));
    let mut first = String::new();
    reader.read_line(&mut first).unwrap();
    assert!(first.starts_with("sweep of plate.v over 300 values"), "{first:?}");
    drop(reader);
    let out = child.wait_with_output().unwrap();
    assert_ended_quietly_by_sigpipe(&a, out.status, &String::from_utf8_lossy(&out.stderr));
    assert!(dir.path().join("s/sweep.csv").is_file());
}

#[test]
fn other_write_errors_are_one_line_and_exit_code_1() {
    if !Path::new("/dev/full").exists() {
        eprintln!("no /dev/full: skipped");
        return;
    }
    let dir = scene_dir();
    let d = dir.path();
    for a in [vec!["--help"], args(&["validate"], &[]), args(&["stability"], &[]), args(&["run"], &["--out", "run"])] {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let out = command(&a, d).stdout(Stdio::from(full)).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{a:?}: {:?}, stderr {stderr:?}", out.status);
        assert_eq!(stderr, "error: cannot write to standard output: No space left on device (os error 28)\n", "{a:?}");
    }
    // The run itself succeeded: its files are there.
    assert!(d.join("run/summary.json").is_file());
}

/// A scene whose file name holds a newline: every command's report names it on one line,
/// escaped (`a\nb`), and `validate`'s report (a scene file) still reads back as TOML.
#[test]
fn a_scene_name_with_a_newline_stays_on_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("a\nb.toml");
    std::fs::copy(concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/fig1.toml"), &scene).unwrap();
    let scene = scene.to_str().unwrap();
    let run = |args: &[&str]| {
        let out = command(args, dir.path()).output().expect("the binary runs");
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8(out.stdout).unwrap()
    };
    let validated = run(&["validate", scene]);
    assert!(validated.starts_with("# scene a\\nb is valid"), "{validated}");
    let _: toml::Table = toml::from_str(&validated).expect("validate's report reads back");
    // The default output directory, out/a\nb, holds the newline too.
    let ran = run(&["run", scene, "--set", "output.trace=false", "--set", "run.t_end=10"]);
    assert!(ran.starts_with("scene a\\nb ("), "{ran}");
    assert_eq!(ran.lines().count(), 4, "{ran}");
    assert!(ran.trim_end().ends_with("output in out/a\\nb"), "{ran}");
}
