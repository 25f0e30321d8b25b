//! What every reader checks before it trusts a file: that the path names a regular file (a
//! device such as /dev/zero, a pipe or a directory would be read forever or not at all),
//! and that every size a header states fits in the bytes the file holds and in this
//! machine's memory (`WEARCOEF_MEMORY_BYTES` overrides it) before anything is allocated.

use std::path::Path;

/// The share of the machine's memory one file's values may take while it is read: the
/// prepared map, its copy and the solver's arrays come on top.
const MEMORY_SHARE: u64 = 4;

/// The length of `path` in bytes, when it names a regular file; otherwise an error saying
/// what it names instead.
pub fn regular_file(path: &Path) -> Result<u64, String> {
    let meta = std::fs::metadata(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => "does not exist".to_string(),
        _ => format!("cannot be read ({e})"),
    })?;
    if meta.is_file() {
        return Ok(meta.len());
    }
    let what = if meta.is_dir() {
        "a directory"
    } else {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_char_device() || t.is_block_device() {
            "a device"
        } else if t.is_fifo() {
            "a pipe"
        } else {
            "a socket"
        }
    };
    Err(format!(
        "is {what}, not a regular file: name a file (save the data to one first)"
    ))
}

/// The bytes this process may allocate for one file's values.
pub fn memory_budget() -> u64 {
    crate::machine::memory_or_default() / MEMORY_SHARE
}

/// Refuse an allocation of `bytes` for `what` above [`memory_budget`], before it is made.
pub fn check_allocation(what: &str, bytes: u128) -> Result<(), String> {
    let budget = memory_budget();
    if bytes > u128::from(budget) {
        return Err(format!(
            "{what} would need {} in memory, more than the {} this machine allows one file (a quarter of its memory; WEARCOEF_MEMORY_BYTES sets it): the header is wrong or the map too large; crop or downsample it",
            human_bytes(bytes),
            human_bytes(u128::from(budget))
        ));
    }
    Ok(())
}

/// The values a header promises, `count` of `width` bytes, checked against the `available`
/// bytes the file holds for them and against memory; returns `count`.
pub fn check_promised(
    what: &str,
    count: u128,
    width: u128,
    available: u64,
) -> Result<usize, String> {
    let bytes = count.saturating_mul(width);
    if bytes > u128::from(available) {
        return Err(format!(
            "{what}: the header promises {count} values ({}), but the file holds {} for them: the header is wrong or the file truncated",
            human_bytes(bytes),
            human_bytes(u128::from(available))
        ));
    }
    check_allocation(what, count.saturating_mul(8))?;
    usize::try_from(count).map_err(|_| format!("{what}: {count} values cannot be addressed"))
}

/// Read all of `path`, a regular file whose length fits the memory budget.
pub fn read_bounded(path: &Path) -> Result<Vec<u8>, String> {
    let len = regular_file(path)?;
    check_allocation("reading the file", u128::from(len))?;
    std::fs::read(path).map_err(|e| format!("cannot be read ({e})"))
}

/// `bytes` in B, KiB, MiB or GiB, three significant figures.
pub fn human_bytes(bytes: u128) -> String {
    let b = bytes as f64;
    match bytes {
        0..1024 => format!("{bytes} B"),
        1024..1_048_576 => format!("{:.3} KiB", b / 1024.0),
        1_048_576..1_073_741_824 => format!("{:.3} MiB", b / 1_048_576.0),
        _ => format!("{:.3} GiB", b / 1_073_741_824.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_pipes_and_directories_are_named() {
        assert!(regular_file(Path::new("/dev/zero"))
            .unwrap_err()
            .contains("a device"));
        assert!(regular_file(Path::new("/"))
            .unwrap_err()
            .contains("a directory"));
        assert!(regular_file(Path::new("/nonexistent/x"))
            .unwrap_err()
            .contains("does not exist"));
    }

    #[test]
    fn promises_beyond_the_file_or_memory_are_refused() {
        assert_eq!(check_promised("x", 10, 8, 80), Ok(10));
        assert!(check_promised("x", 11, 8, 80)
            .unwrap_err()
            .contains("the header promises 11 values (88 B)"));
        // More than memory even where the file were long enough.
        let huge = u128::from(memory_budget()) / 8 + 1;
        assert!(check_promised("x", huge, 1, u64::MAX)
            .unwrap_err()
            .contains("more than the"));
    }
}
