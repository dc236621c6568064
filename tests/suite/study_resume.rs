//! Studies that lose nothing (docs/runs.md, "Studies: the journal and resume"): a 1-D
//! sweep, a 2-D map and a compare, killed at seeded random points (SIGTERM, SIGINT, SIGKILL
//! after `k` journal lines) and continued with `stickslip resume`, write the tables of an
//! uninterrupted study with the same arguments, byte for byte (compare.csv without its
//! timing columns); a signal ends a study with one line naming the resume command; a torn
//! last journal line is dropped, a damaged line elsewhere and a journal of another study or
//! scene are refused with one line and nothing changed; a full disk stops a study with one
//! line and leaves a journal that resumes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use stickslip::studies::seeds::mix;

use super::compare::TINY;

const BIN: &str = env!("CARGO_BIN_EXE_stickslip");

/// The fig2 scene, short: about 0.1 s a run.
const SHORT: [&str; 4] = ["--set", "run.t_end=300", "--set", "run.t_warmup=50"];

/// A study: its arguments (without `--out`), its number of runs, and the files compared.
struct Study {
    args: Vec<String>,
    runs: usize,
    files: &'static [&'static str],
}

fn strings(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

/// A copy of scenarios/fig2.toml in `dir` (so that a test may change it).
fn fig2_in(dir: &Path) -> String {
    let path = dir.join("fig2.toml");
    std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/fig2.toml"), &path).unwrap();
    path.to_str().unwrap().to_string()
}

fn sweep_1d(dir: &Path) -> Study {
    let mut args = vec!["sweep".to_string(), fig2_in(dir)];
    args.extend(strings(&["--param", "plate.v", "--values", "0.1,0.3,1,3,8", "--replicas", "2", "--threads", "1"]));
    args.extend(strings(&SHORT));
    Study { args, runs: 10, files: &["sweep.csv", "runs.csv", "sweep.svg"] }
}

fn map_2d(dir: &Path) -> Study {
    let mut args = vec!["sweep".to_string(), fig2_in(dir)];
    args.extend(strings(&["--param", "plate.v", "--log-range", "0.1:10:3", "--param", "plate.k", "--values"]));
    args.extend(strings(&["15,150", "--threads", "1"]));
    args.extend(strings(&SHORT));
    Study { args, runs: 6, files: &["sweep.csv", "runs.csv", "sweep.svg"] }
}

fn compare(dir: &Path) -> Study {
    let scene = dir.join("tiny.toml");
    std::fs::write(&scene, TINY).unwrap();
    let mut args = vec!["compare".to_string(), scene.to_str().unwrap().to_string()];
    args.extend(strings(&["--dts", "0.5,0.25", "--replicas", "4", "--ref-replicas", "8", "--threads", "1"]));
    // 8 reference runs, exact points of 1, 2 and 4 replicas, 2 steps of 4 replicas.
    Study { args, runs: 23, files: &["compare.csv"] }
}

fn with_out(args: &[String], out: &Path) -> Vec<String> {
    let mut a = args.to_vec();
    a.extend(["--out".to_string(), out.to_str().unwrap().to_string()]);
    a
}

fn stickslip(args: &[String]) -> Output {
    Command::new(BIN).args(args).output().expect("the binary runs")
}

fn resume(dir: &Path) -> Output {
    stickslip(&["resume".to_string(), dir.to_str().unwrap().to_string()])
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs that the journal in `dir` holds (whole lines after the header).
fn journaled(dir: &Path) -> usize {
    std::fs::read(dir.join("journal.jsonl")).map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count().saturating_sub(1))
}

/// A file's text; for compare.csv without its timing columns.
fn table(dir: &Path, name: &str) -> String {
    let text = std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| panic!("{}: {e}", dir.join(name).display()));
    if name != "compare.csv" {
        return text;
    }
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    text.lines()
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            (0..cells.len())
                .filter(|&i| !header[i].ends_with("_seconds"))
                .map(|i| cells[i])
                .collect::<Vec<_>>()
                .join(",")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// How a study is ended.
#[derive(Clone, Copy, Debug)]
enum Kill {
    Signal(libc::c_int),
    Abrupt,
}

/// Starts `args` and ends it as `how` once its journal holds `k` runs. Returns its output,
/// or `None` if it finished first.
fn kill_after(args: &[String], out: &Path, k: usize, how: Kill) -> Option<Output> {
    let mut child =
        Command::new(BIN).args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("the binary runs");
    let started = Instant::now();
    while journaled(out) < k || !out.join("journal.jsonl").exists() {
        if child.try_wait().unwrap().is_some() {
            return None;
        }
        assert!(started.elapsed() < Duration::from_secs(120), "the study made no progress");
        std::thread::sleep(Duration::from_millis(2));
    }
    match how {
        // SAFETY: a signal to our own child, which has not been waited for.
        Kill::Signal(s) => assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, s) }, 0),
        Kill::Abrupt => child.kill().unwrap(),
    }
    let o = child.wait_with_output().unwrap();
    if o.status.success() {
        return None; // finished before the signal arrived
    }
    Some(o)
}

/// Runs `study` uninterrupted, then killed at seeded random points and resumed; the tables
/// must be the uninterrupted study's. Every kill mode is used.
fn killed_and_resumed(make: fn(&Path) -> Study, seed: u64) {
    let tmp = tempfile::tempdir().unwrap();
    let study = make(tmp.path());
    let reference = tmp.path().join("reference");
    let o = stickslip(&with_out(&study.args, &reference));
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(journaled(&reference), study.runs);
    let modes = [Kill::Signal(libc::SIGTERM), Kill::Abrupt, Kill::Signal(libc::SIGINT)];
    let mut interrupted = 0;
    for (trial, &how) in modes.iter().enumerate() {
        let k = (mix(seed ^ trial as u64) % (study.runs as u64 - 1)) as usize;
        let out = tmp.path().join(format!("killed-{trial}"));
        let Some(o) = kill_after(&with_out(&study.args, &out), &out, k, how) else { continue };
        interrupted += 1;
        let kept = journaled(&out);
        assert!(kept >= k && kept < study.runs, "{how:?} after {k}: {kept} runs kept");
        for name in study.files {
            assert!(!out.join(name).exists(), "{how:?}: {name} written by an interrupted study");
        }
        if let Kill::Signal(s) = how {
            let e = stderr(&o);
            assert_eq!(o.status.code(), Some(128 + s), "{how:?}: {e}");
            assert_eq!(e.lines().count(), 1, "not one line: {e:?}");
            assert!(e.contains(&format!("stickslip resume {}", out.display())), "{e}");
            assert!(e.contains(&format!("{kept} of {} runs done", study.runs)), "{e}");
        } else {
            // A kill inside a write leaves a torn last line: dropped on resuming.
            let mut j = std::fs::OpenOptions::new().append(true).open(out.join("journal.jsonl")).unwrap();
            std::io::Write::write_all(&mut j, b"{\"run\":0,\"seed\":12,\"res").unwrap();
        }
        let r = resume(&out);
        assert!(r.status.success(), "{how:?}: resume failed: {}", stderr(&r));
        let said = String::from_utf8_lossy(&r.stdout);
        assert!(said.contains(&format!("{kept} of {} runs were already done", study.runs)), "{said}");
        assert_eq!(journaled(&out), study.runs);
        for name in study.files {
            assert_eq!(table(&out, name), table(&reference, name), "{how:?} after {k} runs: {name} differs");
        }
        // The journal reads back whole after the resume appended to it.
        let again = resume(&out);
        assert!(again.status.success(), "{how:?}: {}", stderr(&again));
        let said = String::from_utf8_lossy(&again.stdout);
        assert!(said.contains(&format!("{0} of {0} runs were already done", study.runs)), "{said}");
    }
    assert!(interrupted >= 2, "the study finished before it could be killed");
}

#[test]
fn a_killed_sweep_resumes_to_the_uninterrupted_tables() {
    killed_and_resumed(sweep_1d, 1);
}

#[test]
fn a_killed_map_resumes_to_the_uninterrupted_tables() {
    killed_and_resumed(map_2d, 2);
}

#[test]
fn a_killed_compare_resumes_to_the_uninterrupted_table_and_quotes_its_own_command() {
    killed_and_resumed(compare, 3);
    // From the journal alone (every run done) the files are the same bytes again, timing
    // included, and compare.md quotes the command that started the study.
    let tmp = tempfile::tempdir().unwrap();
    let study = compare(tmp.path());
    let out = tmp.path().join("c");
    let args = with_out(&study.args, &out);
    let o = kill_after(&args, &out, 5, Kill::Abrupt).expect("killed");
    assert!(!o.status.success());
    assert!(resume(&out).status.success());
    let files = ["compare.csv", "compare.md", "compare.svg"];
    let first: Vec<Vec<u8>> = files.iter().map(|n| std::fs::read(out.join(n)).unwrap()).collect();
    let again = resume(&out);
    assert!(again.status.success(), "{}", stderr(&again));
    assert!(String::from_utf8_lossy(&again.stdout).contains("23 of 23 runs were already done"));
    for (n, bytes) in files.iter().zip(&first) {
        assert_eq!(&std::fs::read(out.join(n)).unwrap(), bytes, "{n}");
    }
    let md = String::from_utf8(first[1].clone()).unwrap();
    assert!(md.contains(&format!("Command: `stickslip {}`", args.join(" "))), "{md}");
}

/// Every file under `dir` with its bytes.
/// The files in `dir` with their bytes, but for the lock file a killed study leaves (not an
/// output; a study that is refused takes it, and removes it when it gives the directory up).
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut v: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && !p.ends_with(stickslip::output::lock::FILE))
        .map(|p| (p.clone(), std::fs::read(&p).unwrap()))
        .collect();
    v.sort();
    v
}

fn assert_refused(o: &Output, mentions: &str) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert_eq!(e.lines().count(), 1, "not one line: {e:?}");
    assert!(e.contains(mentions), "{e:?} does not mention {mentions:?}");
}

#[test]
fn a_journal_of_another_study_or_scene_or_a_damaged_one_is_refused_and_nothing_changes() {
    let tmp = tempfile::tempdir().unwrap();
    let study = map_2d(tmp.path());
    let out = tmp.path().join("map");
    let o = kill_after(&with_out(&study.args, &out), &out, 2, Kill::Abrupt).expect("killed");
    assert!(!o.status.success());
    let before = snapshot(&out);
    // Other arguments into the same directory.
    let mut other = study.args.clone();
    *other.iter_mut().find(|a| *a == "15,150").unwrap() = "15,151".into();
    assert_refused(&stickslip(&with_out(&other, &out)), "belongs to another study");
    // The same arguments on another scene: the scene file changed since (a comment alone
    // changes nothing).
    let scene = tmp.path().join("fig2.toml");
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, format!("# a comment\n{text}")).unwrap();
    let same = tmp.path().join("same");
    std::fs::create_dir(&same).unwrap();
    std::fs::copy(out.join("journal.jsonl"), same.join("journal.jsonl")).unwrap();
    let r = resume(&same);
    assert!(r.status.success(), "{}", stderr(&r));
    std::fs::write(&scene, text.replacen("mass = ", "mass = 1", 1)).unwrap();
    assert_ne!(std::fs::read_to_string(&scene).unwrap(), text);
    assert_refused(&stickslip(&with_out(&study.args, &out)), "written for another scene");
    assert_refused(&resume(&out), "written for another scene");
    assert_eq!(snapshot(&out), before);
    // A damaged line that is not the last one (with the scene as it was).
    std::fs::write(&scene, &text).unwrap();
    let path = out.join("journal.jsonl");
    let journal = String::from_utf8(before[0].1.clone()).unwrap();
    let mut lines: Vec<&str> = journal.lines().collect();
    let cut = &lines[1][..lines[1].len() / 2];
    lines[1] = cut;
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    let damaged = snapshot(&out);
    assert_refused(&resume(&out), "journal.jsonl is damaged at line 2");
    assert_eq!(snapshot(&out), damaged);
    // --checkpoint-every has no meaning for a study.
    std::fs::write(&path, &before[0].1).unwrap();
    let args = vec!["resume".to_string(), out.to_str().unwrap().into(), "--checkpoint-every".into(), "1".into()];
    assert_refused(&stickslip(&args), "--checkpoint-every");
    assert_eq!(snapshot(&out), before);
}

/// A directory on a file system of `bytes` (a tmpfs mounted for the test, when the test
/// may mount; else the process's file-size limit, so that writes fail alike).
struct SmallDisk {
    dir: PathBuf,
    mounted: bool,
}

impl SmallDisk {
    fn new(parent: &Path, bytes: usize) -> SmallDisk {
        let dir = parent.join("small");
        std::fs::create_dir(&dir).unwrap();
        let mounted = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={bytes}"), "tmpfs", dir.to_str().unwrap()])
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        SmallDisk { dir, mounted }
    }

    /// `stickslip args` on this disk, and the limit when there is no tmpfs.
    fn run(&self, args: &[String], bytes: u64) -> Output {
        let mut c = Command::new(BIN);
        c.args(args);
        if !self.mounted {
            use std::os::unix::process::CommandExt;
            // SAFETY: only async-signal-safe calls between fork and exec.
            unsafe {
                c.pre_exec(move || {
                    libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
                    let limit = libc::rlimit { rlim_cur: bytes, rlim_max: bytes };
                    libc::setrlimit(libc::RLIMIT_FSIZE, &limit);
                    Ok(())
                });
            }
        }
        c.output().unwrap()
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        if self.mounted {
            let _ = Command::new("umount").arg(&self.dir).status();
        }
    }
}

#[test]
fn a_full_disk_stops_a_study_with_one_line_and_its_journal_resumes() {
    let tmp = tempfile::tempdir().unwrap();
    let study = sweep_1d(tmp.path());
    let reference = tmp.path().join("reference");
    assert!(stickslip(&with_out(&study.args, &reference)).status.success());
    let line = std::fs::read_to_string(reference.join("journal.jsonl")).unwrap().lines().nth(1).unwrap().len();
    // Room for the header and about five runs.
    let bytes = 8 * 1024;
    assert!(line > 800 && line < 1600, "a run's line is {line} bytes");
    let disk = SmallDisk::new(tmp.path(), bytes);
    let out = disk.dir.join("sweep");
    let o = disk.run(&with_out(&study.args, &out), bytes as u64);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert_eq!(e.lines().count(), 1, "not one line: {e:?}");
    assert!(e.contains("journal.jsonl") && e.contains("stickslip resume"), "{e}");
    let kept = journaled(&out);
    assert!((1..study.runs).contains(&kept), "{kept} runs kept");
    // The journal is whole lines: moved to a disk with room, it resumes.
    let text = std::fs::read_to_string(out.join("journal.jsonl")).unwrap();
    assert!(text.ends_with('\n'));
    let moved = tmp.path().join("moved");
    std::fs::create_dir(&moved).unwrap();
    std::fs::write(moved.join("journal.jsonl"), &text).unwrap();
    drop(disk);
    let r = resume(&moved);
    assert!(r.status.success(), "{}", stderr(&r));
    assert!(String::from_utf8_lossy(&r.stdout).contains(&format!("{kept} of 10 runs were already done")));
    for name in study.files {
        assert_eq!(table(&moved, name), table(&reference, name), "{name}");
    }
}
