//! Files written whole or not at all: through a temporary sibling `.<name>.tmp-<pid>` and a
//! rename. A process killed mid-write (kill -9 cannot be caught) leaves its temporary
//! behind; the next write of the same file, and every `wearcoef run` or `gc` in the
//! directories it owns, removes the temporaries whose process is gone.

use std::path::{Path, PathBuf};

/// The temporary of `path` for process `pid`.
fn temporary(path: &Path, pid: u32) -> PathBuf {
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    path.with_file_name(format!(".{name}.tmp-{pid}"))
}

/// The pid a temporary's name ends with, when it is one of ours: `.<name>.tmp-<pid>`.
fn temporary_pid(name: &str) -> Option<u32> {
    let (head, pid) = name.rsplit_once(".tmp-")?;
    if !head.starts_with('.') || head.len() < 2 {
        return None;
    }
    pid.parse().ok()
}

/// Whether process `pid` runs on this machine.
fn alive(pid: u32) -> bool {
    Path::new("/proc").join(pid.to_string()).exists()
}

/// Remove the temporary files `.<name>.tmp-<pid>` in `dir` whose process no longer runs
/// (not recursive; directories are left alone). Returns how many were removed.
pub fn remove_dead_temporaries(dir: &Path) -> std::io::Result<usize> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(0);
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = temporary_pid(&name) else {
            continue;
        };
        if entry.file_type()?.is_file() && pid != std::process::id() && !alive(pid) {
            std::fs::remove_file(entry.path())?;
            removed += 1;
        }
    }
    Ok(removed)
}

/// Remove the temporaries of `path` in `dir` left by processes that no longer run.
fn remove_dead_siblings(dir: &Path, path: &Path) {
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let other = entry.file_name().to_string_lossy().into_owned();
        let stale = other
            .strip_prefix('.')
            .and_then(|o| o.strip_prefix(name.as_ref()))
            .and_then(|o| o.strip_prefix(".tmp-"))
            .and_then(|pid| pid.parse::<u32>().ok())
            .is_some_and(|pid| pid != std::process::id() && !alive(pid));
        if stale {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Write `path` through a temporary sibling and a rename, so that a failure leaves no
/// partial file. Earlier temporaries of the same file left by dead processes are removed
/// first. An error names `path`, never the temporary, with the free space when the disk is
/// (nearly) full.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if path.file_name().is_none() {
        anyhow::bail!("{}: names no file", path.display());
    }
    remove_dead_siblings(dir, path);
    let tmp = temporary(path, std::process::id());
    let result = write(&tmp).and_then(|_| Ok(std::fs::rename(&tmp, path)?));
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        let cause = format!("{e:#}").replace(&tmp.display().to_string(), "");
        anyhow::bail!(super::cannot_write(
            path,
            cause.trim_start_matches([':', ' '])
        ));
    }
    Ok(())
}

/// What writes one file of [`write_all_atomically`] (given the temporary path to write).
pub type FileWriter<'a> = Box<dyn FnOnce(&Path) -> anyhow::Result<()> + 'a>;

/// Write several files all or none: each is written to its temporary first, and only when
/// every one is written are they renamed into place. A failure removes every temporary.
pub fn write_all_atomically(files: Vec<(&Path, FileWriter<'_>)>) -> anyhow::Result<()> {
    let mut written: Vec<(PathBuf, &Path)> = Vec::new();
    let cleanup = |written: &[(PathBuf, &Path)]| {
        for (tmp, _) in written {
            let _ = std::fs::remove_file(tmp);
        }
    };
    for (path, write) in files {
        let dir = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        remove_dead_siblings(dir, path);
        let tmp = temporary(path, std::process::id());
        if let Err(e) = write(&tmp) {
            let _ = std::fs::remove_file(&tmp);
            cleanup(&written);
            let cause = format!("{e:#}").replace(&tmp.display().to_string(), "");
            anyhow::bail!(super::cannot_write(
                path,
                cause.trim_start_matches([':', ' '])
            ));
        }
        written.push((tmp, path));
    }
    for (i, (tmp, path)) in written.iter().enumerate() {
        if let Err(e) = std::fs::rename(tmp, path) {
            cleanup(&written[i..]);
            anyhow::bail!(super::cannot_write(path, &e.to_string()));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dead_temporaries_go_and_live_ones_stay() {
        let dir = tempfile::tempdir().unwrap();
        // A pid above the kernel's maximum (2^22) never runs.
        let dead = dir.path().join(".index.csv.tmp-4194399");
        let live = temporary(&dir.path().join("index.csv"), std::process::id());
        let other = dir.path().join("notes.tmp-4194399");
        for p in [&dead, &live, &other] {
            std::fs::write(p, b"x").unwrap();
        }
        assert_eq!(remove_dead_temporaries(dir.path()).unwrap(), 1);
        assert!(!dead.exists() && live.exists() && other.exists());
        // The next write of a file removes its own dead temporaries too.
        std::fs::write(&dead, b"x").unwrap();
        let path = dir.path().join("index.csv");
        write_atomically(&path, |tmp| Ok(std::fs::write(tmp, b"ok")?)).unwrap();
        assert!(!dead.exists());
        assert_eq!(std::fs::read(&path).unwrap(), b"ok");
    }

    #[test]
    fn a_failed_write_of_several_files_leaves_none() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.npy"), dir.path().join("b.npy"));
        let result = write_all_atomically(vec![
            (
                a.as_path(),
                Box::new(|t: &Path| Ok(std::fs::write(t, b"a")?)),
            ),
            (
                b.as_path(),
                Box::new(|_: &Path| Err(anyhow::anyhow!("disk full"))),
            ),
        ]);
        let e = result.unwrap_err().to_string();
        assert!(e.contains("b.npy") && e.contains("disk full"), "{e}");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert!(left.is_empty(), "{left:?}");
    }
}
