//! What this machine can do: the bounds of every count a user can type (threads, jobs,
//! realizations, loads, iterations) are derived from here, checked before any work.

/// Total memory of this machine (`MemTotal` of /proc/meminfo), if known; the environment
/// variable `WEARCOEF_MEMORY_BYTES` overrides it (plan for a smaller share of a node).
pub fn memory_bytes() -> Option<u64> {
    if let Ok(v) = std::env::var("WEARCOEF_MEMORY_BYTES") {
        match v.trim().parse() {
            Ok(bytes) => return Some(bytes),
            Err(_) => crate::note!(
                "warning: WEARCOEF_MEMORY_BYTES={v:?} is not a whole number of bytes; using /proc/meminfo"
            ),
        }
    }
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Memory to reckon with: the machine's, or 1 GiB where it cannot be read.
pub fn memory_or_default() -> u64 {
    memory_bytes().unwrap_or(1 << 30)
}

/// Cores this process may use.
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Threads this process may start in all (`/proc/sys/kernel/threads-max` shared with the
/// rest of the machine; a quarter of it, and at most 4096, is taken as this program's share).
pub fn max_threads() -> usize {
    let system = std::fs::read_to_string("/proc/sys/kernel/threads-max")
        .ok()
        .and_then(|t| t.trim().parse::<usize>().ok())
        .unwrap_or(4096);
    (system / 4).clamp(1, 4096)
}

/// The process's peak resident memory since it started or since [`reset_peak_rss`]
/// (`VmHWM` of /proc/self/status), if known.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Start measuring the peak resident memory afresh (writing 5 to /proc/self/clear_refs
/// resets `VmHWM`); false where the kernel does not allow it.
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Refuse work whose estimated peak memory (`bytes`) exceeds this machine's, before
/// allocating it; `what` names the work and `fix` what to do.
pub fn check_memory(what: &str, bytes: u64, fix: &str) -> Result<(), crate::ranges::InputError> {
    match memory_bytes() {
        Some(total) if bytes > total => Err(crate::ranges::InputError(format!(
            "{what} needs about {:.1} GiB, more than this machine's {:.1} GiB; {fix}",
            bytes as f64 / (1u64 << 30) as f64,
            total as f64 / (1u64 << 30) as f64
        ))),
        _ => Ok(()),
    }
}
