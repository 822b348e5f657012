//! What the machine lets a run use: the memory this process may still allocate, checked by the
//! front ends before a grid, a trajectory or a sweep is allocated (a refusal with the estimate
//! rather than an out-of-memory kill).

use std::path::{Path, PathBuf};

/// Assumed when nothing can be read (not Linux, no /proc).
const UNKNOWN: u64 = 8 << 30;

/// Bytes this process may still allocate: the smaller of the kernel's estimate of available
/// memory (`MemAvailable` in /proc/meminfo) and the room left under the memory limit of the
/// process's cgroup (v2: `memory.max − memory.current`; v1: `memory.limit_in_bytes −
/// memory.usage_in_bytes`), which a container or a batch scheduler's job sets and
/// `MemAvailable` does not see. 8 GiB where neither can be read.
pub fn memory_available() -> u64 {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        t.lines()
            .find(|l| l.starts_with("MemAvailable:"))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|kb| kb.parse::<u64>().ok())
            .map(|kb| kb * 1024)
    });
    let cgroup = std::fs::read_to_string("/proc/self/cgroup")
        .ok()
        .and_then(|t| cgroup_room(&t, Path::new("/sys/fs/cgroup")));
    match (meminfo, cgroup) {
        (Some(a), Some(b)) => a.min(b),
        (Some(a), None) | (None, Some(a)) => a,
        (None, None) => UNKNOWN,
    }
}

/// Room under the memory limit of the cgroup named in `proc_self_cgroup` (the text of
/// /proc/self/cgroup), with the cgroup file systems mounted at `root`; `None` without a limit.
/// The process's own group is tried first, then the mount's top (inside a cgroup namespace the
/// listed path need not exist under the mount).
pub fn cgroup_room(proc_self_cgroup: &str, root: &Path) -> Option<u64> {
    let read = |p: PathBuf| -> Option<u64> {
        std::fs::read_to_string(p)
            .ok()
            .and_then(|s| s.trim().parse::<u64>().ok())
    };
    // (directory of the group, limit file, usage file); a limit near u64::MAX is "no limit"
    let room = |dir: PathBuf, limit: &str, usage: &str| -> Option<u64> {
        let l = read(dir.join(limit))?;
        if l >= 1 << 60 {
            return None;
        }
        Some(l.saturating_sub(read(dir.join(usage)).unwrap_or(0)))
    };
    let mut best: Option<u64> = None;
    for line in proc_self_cgroup.lines() {
        let mut f = line.splitn(3, ':');
        let (_, controllers, path) = (f.next(), f.next().unwrap_or(""), f.next().unwrap_or(""));
        let rel = path.trim_start_matches('/');
        let found = if controllers.is_empty() {
            let base = root.join("unified").is_dir().then(|| root.join("unified"));
            let base = base.unwrap_or_else(|| root.to_path_buf());
            room(base.join(rel), "memory.max", "memory.current")
                .or_else(|| room(base.clone(), "memory.max", "memory.current"))
        } else if controllers.split(',').any(|c| c == "memory") {
            let base = root.join("memory");
            room(
                base.join(rel),
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
            )
            .or_else(|| {
                room(
                    base.clone(),
                    "memory.limit_in_bytes",
                    "memory.usage_in_bytes",
                )
            })
        } else {
            None
        };
        if let Some(r) = found {
            best = Some(best.map_or(r, |b| b.min(r)));
        }
    }
    best
}
