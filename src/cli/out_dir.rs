//! The output directory of a run or study: created, checked and held
//! ([`crate::output::lock`]) before any work is done.

use std::path::{Path, PathBuf};

use crate::output::lock::{self, DirLock};

/// An output directory prepared for a run or study: held by this process
/// ([`crate::output::lock`]) until dropped, with the directories that were created for it.
pub(crate) struct OutDir {
    created: Vec<PathBuf>,
    lock: DirLock,
}

impl OutDir {
    /// Releases the directory and removes the directories created for it, as long as they
    /// are empty: a run or study that failed leaves nothing behind.
    pub(crate) fn abandon(self) {
        drop(self.lock);
        remove_if_empty(&self.created);
    }
}

/// Creates `dir`, checks it can be written and holds it, before any work is done and before
/// anything in it is written or removed.
pub(crate) fn prepare_out_dir(dir: &Path) -> Result<OutDir, String> {
    let mut created = Vec::new();
    let mut d = Some(dir);
    while let Some(p) = d.filter(|p| !p.as_os_str().is_empty() && !p.exists()) {
        created.push(p.to_path_buf());
        d = p.parent();
    }
    let fail = |what: &str, e: std::io::Error, created: &[PathBuf]| {
        remove_if_empty(created);
        format!("output directory {}: cannot {what}: {e}", dir.display())
    };
    std::fs::create_dir_all(dir).map_err(|e| fail("create it", e, &created))?;
    let probe = dir.join(".stickslip-write-probe");
    std::fs::write(&probe, b"").map_err(|e| fail("write in it", e, &created))?;
    let _ = std::fs::remove_file(probe);
    match lock::hold(dir) {
        Ok(lock) => Ok(OutDir { created, lock }),
        Err(e) => {
            remove_if_empty(&created);
            Err(e.to_string())
        }
    }
}

/// Removes the directories `prepare_out_dir` created, deepest first, as long as they are
/// empty (`remove_dir` never removes a directory that holds anything).
pub(crate) fn remove_if_empty(created: &[PathBuf]) {
    for d in created {
        if std::fs::remove_dir(d).is_err() {
            break;
        }
    }
}
