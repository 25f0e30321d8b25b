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

/// Remove the temporaries of `path` in `dir` left by processes that no longer run: files of
/// [`write_atomically`], directories of [`StagedDir`].
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
            let _ = match entry.file_type() {
                Ok(t) if t.is_dir() => std::fs::remove_dir_all(entry.path()),
                _ => std::fs::remove_file(entry.path()),
            };
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
        anyhow::bail!(super::disk::cannot_write(
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
            anyhow::bail!(super::disk::cannot_write(
                path,
                cause.trim_start_matches([':', ' '])
            ));
        }
        written.push((tmp, path));
    }
    for (i, (tmp, path)) in written.iter().enumerate() {
        if let Err(e) = std::fs::rename(tmp, path) {
            cleanup(&written[i..]);
            anyhow::bail!(super::disk::cannot_write(path, &e.to_string()));
        }
    }
    Ok(())
}

/// A directory written whole or not at all: its files go into a staging sibling
/// `.<name>.tmp-<pid>`, renamed onto the target only when every one is written. The target
/// must be absent or an empty directory then; if another process filled it meanwhile (two
/// runs into one directory), the commit fails and nothing of this run lands there. Dropped
/// without a commit (an error, a refusal), the staging directory and every parent it
/// created are removed.
pub struct StagedDir {
    target: PathBuf,
    staging: PathBuf,
    created: Vec<PathBuf>,
    done: bool,
}

impl StagedDir {
    /// Stage `target`: its missing parents are created (and removed again if nothing is
    /// committed), and stagings of it left by dead processes are removed.
    pub fn new(target: &Path) -> anyhow::Result<Self> {
        let name = target
            .file_name()
            .ok_or_else(|| anyhow::anyhow!("{}: names no directory", target.display()))?
            .to_string_lossy()
            .into_owned();
        let parent = target
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
            .to_path_buf();
        let mut created = Vec::new();
        let mut missing = Vec::new();
        let mut at = parent.as_path();
        while !at.as_os_str().is_empty() && !at.exists() {
            missing.push(at.to_path_buf());
            at = at.parent().unwrap_or(Path::new(""));
        }
        for dir in missing.into_iter().rev() {
            std::fs::create_dir(&dir)
                .map_err(|e| anyhow::anyhow!(super::disk::cannot_write(&dir, &e.to_string())))?;
            created.push(dir);
        }
        let mut staged = StagedDir {
            target: target.to_path_buf(),
            staging: parent.join(format!(".{name}.tmp-{}", std::process::id())),
            created,
            done: false,
        };
        remove_dead_siblings(&parent, target);
        let _ = std::fs::remove_dir_all(&staged.staging);
        if let Err(e) = std::fs::create_dir(&staged.staging) {
            staged.done = false;
            anyhow::bail!(super::disk::cannot_write(target, &e.to_string()));
        }
        Ok(staged)
    }

    /// Where the files are written until the commit.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// Move the staged directory onto the target.
    pub fn commit(mut self) -> anyhow::Result<()> {
        match std::fs::rename(&self.staging, &self.target) {
            Ok(()) => {
                self.done = true;
                Ok(())
            }
            Err(e) if matches!(e.raw_os_error(), Some(libc::ENOTEMPTY | libc::EEXIST)) => {
                anyhow::bail!(
                    "{} was filled by another process while this one ran (two runs into one directory?); nothing of this run was written there: run again into a new directory",
                    self.target.display()
                )
            }
            Err(e) => anyhow::bail!(super::disk::cannot_write(&self.target, &e.to_string())),
        }
    }
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if self.done {
            return;
        }
        let _ = std::fs::remove_dir_all(&self.staging);
        for dir in self.created.iter().rev() {
            let _ = std::fs::remove_dir(dir);
        }
    }
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

    /// A staged directory lands whole; a second into the same target fails and leaves the
    /// first; one dropped uncommitted leaves nothing, not even the parents it made.
    #[test]
    fn staged_directories_land_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("new/out");
        let a = StagedDir::new(&target).unwrap();
        std::fs::write(a.path().join("x"), b"a").unwrap();
        let other = dir.path().join("new/.out.tmp-4194399");
        std::fs::create_dir(&other).unwrap();
        std::fs::write(other.join("y"), b"b").unwrap();
        a.commit().unwrap();
        assert_eq!(std::fs::read(target.join("x")).unwrap(), b"a");
        let c = StagedDir::new(&target).unwrap();
        assert!(!other.exists(), "a dead process's staging is removed");
        std::fs::write(c.path().join("x"), b"c").unwrap();
        let e = c.commit().unwrap_err().to_string();
        assert!(e.contains("filled by another process"), "{e}");
        assert_eq!(std::fs::read(target.join("x")).unwrap(), b"a");
        let left: Vec<_> = std::fs::read_dir(dir.path().join("new")).unwrap().collect();
        assert_eq!(left.len(), 1, "{left:?}");
        drop(StagedDir::new(&dir.path().join("p/q/out")).unwrap());
        assert!(!dir.path().join("p").exists());
    }
}
