//! A run's or a study's hold on its output directory: an exclusive advisory lock
//! (`flock(LOCK_EX | LOCK_NB)`) on the file [`FILE`] in it, taken before anything in the
//! directory is written or removed and held until the work is done. A second run or study
//! into the same directory is refused at once ([`LockError::Held`], with the holder's
//! process id, which the holder writes into the file). The kernel releases the lock when
//! its holder's process ends, however it ends: a file left behind by a killed process
//! blocks nothing. A finished holder removes the file.

use std::fs::{File, OpenOptions};
use std::io::{self, Read, Seek, Write};
use std::os::fd::AsRawFd;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// The lock file's name in an output directory.
pub const FILE: &str = ".stickslip.lock";

#[derive(Debug, thiserror::Error)]
pub enum LockError {
    #[error(
        "output directory {dir} is in use by process {pid} (a run or study writing there); \
         wait for it to finish or choose another directory"
    )]
    Held { dir: PathBuf, pid: String },
    #[error("output directory {dir}: cannot lock {}: {source}", FILE)]
    Io { dir: PathBuf, source: io::Error },
}

/// The hold on an output directory, released (its file removed, then the lock) when
/// dropped.
#[derive(Debug)]
pub struct DirLock {
    /// Open while held: closing it releases the lock.
    _file: File,
    path: PathBuf,
}

impl DirLock {
    /// The lock file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        // Removed while still locked: whoever opened it before sees, once it has the lock,
        // that the name no longer leads to it, and opens the name again (`hold`).
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Holds the existing directory `dir` for this process: refuses at once if another holder
/// has it.
pub fn hold(dir: &Path) -> Result<DirLock, LockError> {
    let path = dir.join(FILE);
    let io_err = |source| LockError::Io { dir: dir.to_path_buf(), source };
    loop {
        let mut file =
            OpenOptions::new().read(true).write(true).create(true).truncate(false).open(&path).map_err(io_err)?;
        // SAFETY: `flock` on a descriptor this process owns; it touches no memory.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
            let e = io::Error::last_os_error();
            if e.kind() != io::ErrorKind::WouldBlock {
                return Err(io_err(e));
            }
            return Err(LockError::Held { dir: dir.to_path_buf(), pid: holder(&mut file) });
        }
        // The holder before may have removed the file between our open and our lock: then
        // the lock is on a file no one else can reach any more.
        let same = match (file.metadata(), std::fs::metadata(&path)) {
            (Ok(a), Ok(b)) => (a.dev(), a.ino()) == (b.dev(), b.ino()),
            _ => false,
        };
        if !same {
            continue;
        }
        file.set_len(0).and_then(|()| writeln!(file, "{}", std::process::id())).map_err(io_err)?;
        return Ok(DirLock { _file: file, path });
    }
}

/// The process id the holder wrote into the lock file: waits a moment for a holder that
/// has just taken the lock and not yet written it.
fn holder(file: &mut File) -> String {
    for _ in 0..50 {
        let mut text = String::new();
        if file.rewind().and_then(|()| file.read_to_string(&mut text)).is_ok() {
            let pid = text.trim();
            if !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()) {
                return pid.to_string();
            }
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    "unknown".to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_hold_is_refused_with_the_holders_pid_and_a_released_one_is_free() {
        let tmp = tempfile::tempdir().unwrap();
        let first = hold(tmp.path()).unwrap();
        let text = std::fs::read_to_string(first.path()).unwrap();
        assert_eq!(text, format!("{}\n", std::process::id()));
        // flock belongs to the open file, so a second hold in the same process is refused too.
        match hold(tmp.path()) {
            Err(LockError::Held { dir, pid }) => {
                assert_eq!((dir.as_path(), pid), (tmp.path(), std::process::id().to_string()))
            }
            other => panic!("{other:?}"),
        }
        drop(first);
        assert!(!tmp.path().join(FILE).exists(), "a released hold removes its file");
        let again = hold(tmp.path()).unwrap();
        drop(again);
        assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
    }

    #[test]
    fn a_lock_file_left_behind_blocks_nothing() {
        let tmp = tempfile::tempdir().unwrap();
        std::fs::write(tmp.path().join(FILE), "999999999\n").unwrap();
        let held = hold(tmp.path()).unwrap();
        assert_eq!(std::fs::read_to_string(held.path()).unwrap(), format!("{}\n", std::process::id()));
    }

    #[test]
    fn a_missing_directory_is_an_error() {
        let tmp = tempfile::tempdir().unwrap();
        let e = hold(&tmp.path().join("absent")).unwrap_err();
        assert!(matches!(e, LockError::Io { .. }), "{e:?}");
    }
}
