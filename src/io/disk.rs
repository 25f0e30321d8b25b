//! What a write that failed says about its disk.

use std::path::Path;

/// "; the file system of `dir` has N bytes free …" when it is (nearly) full, else "".
pub fn disk_note(dir: &std::path::Path) -> String {
    use std::os::unix::ffi::OsStrExt;
    let Ok(path) = std::ffi::CString::new(dir.as_os_str().as_bytes()) else {
        return String::new();
    };
    let mut stat: libc::statvfs = unsafe { std::mem::zeroed() };
    // SAFETY: `path` is a valid C string and `stat` a writable statvfs.
    if unsafe { libc::statvfs(path.as_ptr(), &mut stat) } != 0 {
        return String::new();
    }
    let free = stat.f_bavail as u64 * stat.f_frsize as u64;
    if free < 64 << 20 {
        format!(
            "; the file system of {} has {free} bytes free: make room and run again",
            dir.display()
        )
    } else {
        String::new()
    }
}

/// "cannot write `path`: `cause`", with [`disk_note`] of its directory when the cause is a
/// full disk or quota (a file system that reports no free space for another reason, such
/// as /proc, gets no advice to make room).
pub fn cannot_write(path: &Path, cause: &str) -> String {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let full = [
        "No space left",
        "Disk quota exceeded",
        "os error 28",
        "os error 122",
    ]
    .iter()
    .any(|c| cause.contains(c));
    let note = if full { disk_note(dir) } else { String::new() };
    format!("cannot write {}: {cause}{note}", path.display())
}
