//! How much more memory this process may take before an allocation fails:
//! the address-space limit (`ulimit -v`) and the memory limits of its control
//! group and every group above it. A render that cannot fit then fails up
//! front with a sentence, instead of aborting on an allocation midway.

use std::path::Path;

/// Bytes this process may still allocate under its limits; `None` when no
/// limit is set (or none can be read: then the kernel's own policy decides).
pub fn headroom() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok();
    let status = std::fs::read_to_string("/proc/self/status").ok();
    let address_space = limits.as_deref().and_then(address_space_limit).map(|limit| {
        let used = status.as_deref().and_then(|s| status_kib(s, "VmSize:")).unwrap_or(0) * 1024;
        limit.saturating_sub(used)
    });
    let cgroup = std::fs::read_to_string("/proc/self/cgroup").ok().and_then(|c| cgroup_headroom(&c));
    match (address_space, cgroup) {
        (Some(a), Some(c)) => Some(a.min(c)),
        (a, c) => a.or(c),
    }
}

/// The soft "Max address space" of `/proc/self/limits`, in bytes.
fn address_space_limit(limits: &str) -> Option<u64> {
    let line = limits.lines().find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..].split_whitespace().next()?.parse().ok()
}

/// A `kB` field of `/proc/self/status`.
fn status_kib(status: &str, field: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with(field))?;
    line[field.len()..].split_whitespace().next()?.parse().ok()
}

/// The least `memory.max − memory.current` from this process's cgroup (v2)
/// up to the root: a limit on any ancestor binds as well.
fn cgroup_headroom(cgroup: &str) -> Option<u64> {
    let rel = cgroup.lines().find_map(|l| l.strip_prefix("0::"))?;
    let root = Path::new("/sys/fs/cgroup");
    let mut dir = root.join(rel.trim_start_matches('/'));
    let mut least: Option<u64> = None;
    loop {
        let read = |name: &str| std::fs::read_to_string(dir.join(name)).ok();
        if let Some(max) = read("memory.max").and_then(|m| m.trim().parse::<u64>().ok()) {
            let current = read("memory.current").and_then(|c| c.trim().parse::<u64>().ok()).unwrap_or(0);
            let left = max.saturating_sub(current);
            least = Some(least.map_or(left, |l| l.min(left)));
        }
        if dir == root || !dir.pop() || !dir.starts_with(root) {
            return least;
        }
    }
}

/// `bytes` for a message: "3.8 GiB", "512 MiB".
pub fn describe(bytes: u64) -> String {
    const GIB: f64 = (1u64 << 30) as f64;
    const MIB: f64 = (1u64 << 20) as f64;
    let b = bytes as f64;
    if b >= GIB {
        format!("{:.1} GiB", b / GIB)
    } else {
        format!("{:.0} MiB", (b / MIB).max(1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_are_read_from_the_kernels_tables() {
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max stack size            8388608              unlimited            bytes\n\
                      Max address space         2048000000           unlimited            bytes\n";
        assert_eq!(address_space_limit(limits), Some(2_048_000_000));
        let unlimited = "Max address space         unlimited            unlimited            bytes\n";
        assert_eq!(address_space_limit(unlimited), None);
        assert_eq!(status_kib("Name:\tx\nVmSize:\t  123456 kB\n", "VmSize:"), Some(123_456));
        assert_eq!(describe(3 << 30), "3.0 GiB");
        assert_eq!(describe(5 << 20), "5 MiB");
    }
}
