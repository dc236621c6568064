//! What the machine has: memory available to this process and free space on a disk.

use std::path::Path;

/// Environment variable that caps the memory the checks take as available, in bytes (to
/// leave room for other work on a shared machine).
pub const MEMORY_ENV: &str = "STICKSLIP_MEMORY_AVAILABLE";

/// Memory available to a new allocation, and where the figure comes from.
#[derive(Clone, Debug, PartialEq)]
pub struct Available {
    pub bytes: u64,
    pub source: &'static str,
}

/// The least of `MemAvailable` (`/proc/meminfo`), the room left under this process's
/// cgroup limit (v2 `memory.max` minus `memory.current`, or v1 `memory.limit_in_bytes`
/// minus `memory.usage_in_bytes`) and [`MEMORY_ENV`]; `None` where none of them can be read.
pub fn available_memory() -> Option<Available> {
    let mut best: Option<Available> = None;
    let mut take = |bytes: Option<u64>, source: &'static str| match (bytes, &best) {
        (Some(bytes), Some(b)) if bytes >= b.bytes => {}
        (Some(bytes), _) => best = Some(Available { bytes, source }),
        (None, _) => {}
    };
    take(mem_available(), "MemAvailable in /proc/meminfo");
    take(cgroup_room(), "the cgroup memory limit");
    take(std::env::var(MEMORY_ENV).ok().and_then(|v| v.trim().parse().ok()), MEMORY_ENV);
    best
}

fn mem_available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

fn read_u64(path: &Path) -> Option<u64> {
    std::fs::read_to_string(path).ok()?.trim().parse().ok()
}

/// Room under the cgroup limit: the process's own cgroup (from `/proc/self/cgroup`), else
/// the root of the hierarchy.
fn cgroup_room() -> Option<u64> {
    let root = Path::new("/sys/fs/cgroup");
    let own = std::fs::read_to_string("/proc/self/cgroup")
        .ok()
        .and_then(|t| t.lines().find_map(|l| l.strip_prefix("0::").map(|p| root.join(p.trim_start_matches('/')))));
    let v2 = |dir: &Path| {
        let max = read_u64(&dir.join("memory.max"))?; // "max" (no limit) does not parse
        Some(max.saturating_sub(read_u64(&dir.join("memory.current")).unwrap_or(0)))
    };
    let v1 = || {
        let dir = root.join("memory");
        let limit = read_u64(&dir.join("memory.limit_in_bytes"))?;
        // v1 reports "no limit" as a huge number.
        (limit < 1 << 60).then(|| limit.saturating_sub(read_u64(&dir.join("memory.usage_in_bytes")).unwrap_or(0)))
    };
    own.as_deref().and_then(v2).or_else(|| v2(root)).or_else(v1)
}

/// Environment variable that makes the command print its peak resident memory on stderr
/// when it ends, to compare with the estimate `stickslip validate` prints.
pub const REPORT_PEAK_ENV: &str = "STICKSLIP_REPORT_PEAK_MEMORY";

/// Peak resident memory of this process (`VmHWM` in `/proc/self/status`), in bytes.
pub fn peak_resident() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = text.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

/// Free bytes for an unprivileged writer on the file system holding `path`, or the
/// nearest existing directory above it (`statvfs`); `None` where it cannot be read.
pub fn free_disk(path: &Path) -> Option<u64> {
    let existing = path.ancestors().find(|d| !d.as_os_str().is_empty() && d.exists()).unwrap_or(Path::new("."));
    statvfs_free(existing)
}

#[cfg(unix)]
fn statvfs_free(path: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).ok()?;
    let mut s = std::mem::MaybeUninit::<libc::statvfs>::uninit();
    // SAFETY: `c` is a NUL-terminated path and `s` is a buffer for one `statvfs`, which the
    // call fills when it returns 0.
    let s = unsafe {
        if libc::statvfs(c.as_ptr(), s.as_mut_ptr()) != 0 {
            return None;
        }
        s.assume_init()
    };
    // A file system without block accounting (`/proc`, some FUSE mounts) reports no blocks:
    // its free space is unknown, not zero.
    #[allow(clippy::unnecessary_cast)] // the field types differ between platforms
    (s.f_blocks > 0).then(|| (s.f_bavail as u64).saturating_mul(s.f_frsize as u64))
}

#[cfg(not(unix))]
fn statvfs_free(_path: &Path) -> Option<u64> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_machine_reports_memory_and_disk() {
        let m = available_memory().expect("Linux has /proc/meminfo");
        assert!(m.bytes > 0);
        let dir = tempfile::tempdir().unwrap();
        let free = free_disk(&dir.path().join("not/yet/there")).expect("statvfs of an existing ancestor");
        assert!(free > 0);
        assert!(free_disk(Path::new("")).is_some());
        assert!(peak_resident().expect("Linux has VmHWM") > 0);
    }
}
