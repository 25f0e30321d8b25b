//! What the commands share: the store's arguments, the pipeline file's loading, and the checks
//! of their output paths, directories and thread counts (each error naming its option).

use std::path::{Path, PathBuf};

use wearcoef::config::Pipeline;

#[derive(clap::Args, Clone)]
pub struct StoreArgs {
    /// Pipeline description.
    #[arg(long, default_value = "pipeline.yaml")]
    pub config: PathBuf,
    /// Data directory (artifact store and catalogs).
    #[arg(long, default_value = "data")]
    pub data: PathBuf,
}

pub use wearcoef::machine::check_memory;
pub use wearcoef::ranges::InputError;

pub fn load(path: &Path) -> anyhow::Result<Pipeline> {
    Ok(Pipeline::load(path)?)
}

/// An output file of a given kind, checked before any work: `path` must end in `.{ext}`
/// (the error says what the file is, `what`), then [`check_outputs`] against `inputs`.
pub fn check_output_named(
    option: &str,
    path: &Path,
    ext: &str,
    what: &str,
    inputs: &[(&str, &Path)],
) -> Result<(), InputError> {
    if path.extension().is_none_or(|e| e != ext) {
        return Err(InputError(format!(
            "{option} {}: {what}; name it FILE.{ext}",
            path.display()
        )));
    }
    check_outputs(&[(option, path)], inputs)
}

/// Check a command's output files before any work is done: each names a file (not a
/// directory, a device or a pipe) in a directory that exists and can be written, no two name
/// the same file, none is one of the command's `inputs` (under any name: hard links and
/// `./` count), and none lies inside a store's `cache/` or `failed/`, which only `wearcoef
/// run` writes. `outputs` and `inputs` pair each option with the user's path; errors name
/// both (exit 2).
pub fn check_outputs(
    outputs: &[(&str, &Path)],
    inputs: &[(&str, &Path)],
) -> Result<(), InputError> {
    let mut seen: Vec<(&str, PathBuf)> = Vec::new();
    for &(option, path) in outputs {
        let bad = |why: String| InputError(format!("{option} {}: {why}", path.display()));
        let Some(name) = path.file_name() else {
            return Err(bad("names no file".into()));
        };
        if name.len() > 255 {
            return Err(bad(format!(
                "the file name has {} bytes, more than the 255 a file system allows; choose a shorter one",
                name.len()
            )));
        }
        let dir = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let dir = match dir.canonicalize() {
            Ok(d) if d.is_dir() => d,
            Ok(_) => return Err(bad(format!("{} is not a directory", dir.display()))),
            Err(_) => {
                return Err(bad(format!(
                    "the directory {} does not exist; create it first",
                    dir.display()
                )))
            }
        };
        if !writable(&dir) {
            return Err(bad(format!(
                "the directory {} cannot be written by this user; choose another",
                dir.display()
            )));
        }
        if let Ok(meta) = std::fs::metadata(path) {
            if !meta.is_file() {
                return Err(bad(format!(
                    "exists and is not a regular file ({}); name a file to write",
                    if meta.is_dir() {
                        "a directory"
                    } else {
                        "a device, pipe or socket"
                    }
                )));
            }
        }
        for &(input, from) in inputs {
            if same_file(path, from) {
                return Err(bad(format!(
                    "is the file {input} reads ({}); writing it would destroy the input: name another file",
                    from.display()
                )));
            }
        }
        let full = dir.join(name);
        if let Some(store) = inside_store(&full) {
            return Err(bad(format!(
                "lies inside the store {} (its cache/ and failed/ are written only by `wearcoef run`); name a file outside it",
                store.display()
            )));
        }
        if let Some((other, _)) = seen.iter().find(|(_, p)| *p == full) {
            return Err(bad(format!(
                "is also the path of {other}; give each output its own file"
            )));
        }
        seen.push((option, full));
    }
    Ok(())
}

/// Check a command's output files against every file its pipeline reads: the pipeline file
/// (`--config`) and each measured study's topography files, before anything is written.
pub fn check_outputs_of_pipeline(
    outputs: &[(&str, &Path)],
    config: &Path,
    pipeline: &Pipeline,
) -> Result<(), InputError> {
    let files = pipeline.read_files(&config.display().to_string());
    let mut inputs: Vec<(&str, &Path)> = vec![("--config", config)];
    inputs.extend(files.iter().map(|(f, p)| (f.as_str(), p.as_path())));
    check_outputs(outputs, &inputs)
}

/// Whether two directory options name one directory (both existing, or the same path).
pub fn same_dir(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => std::path::absolute(a).ok() == std::path::absolute(b).ok(),
    }
}

/// Whether `a` and `b` are one file: the same device and inode when both exist, else the
/// same canonical path.
fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => false,
    }
}

/// Whether this user may create files in `dir` (`access(2)` with `W_OK`).
fn writable(dir: &Path) -> bool {
    use std::os::unix::ffi::OsStrExt;
    let Ok(c) = std::ffi::CString::new(dir.as_os_str().as_bytes()) else {
        return false;
    };
    // SAFETY: `c` is a valid NUL-terminated path.
    unsafe { libc::access(c.as_ptr(), libc::W_OK) == 0 }
}

/// The store whose `cache/` or `failed/` holds `path` (an absolute path whose parent
/// exists), if any: an ancestor named `cache` or `failed` whose own parent has a `cache/`.
/// Returned relative to the working directory when it lies below it, as the user wrote it.
pub fn inside_store(path: &Path) -> Option<PathBuf> {
    let mut at = path.parent();
    while let Some(dir) = at {
        let named = dir
            .file_name()
            .is_some_and(|n| n == "cache" || n == "failed");
        if let Some(root) = dir.parent().filter(|_| named) {
            if root.join("cache").is_dir() {
                let here = std::env::current_dir().and_then(|d| d.canonicalize());
                return Some(match here {
                    Ok(here) if root.starts_with(&here) && root != here => {
                        root.strip_prefix(&here).unwrap_or(root).to_path_buf()
                    }
                    _ => root.to_path_buf(),
                });
            }
        }
        at = dir.parent();
    }
    None
}

/// Check a directory option before any work: it is a directory, or does not exist yet and
/// its nearest existing ancestor is a directory (so it can be created). Exit 2 otherwise.
pub fn check_dir(option: &str, path: &Path) -> Result<(), InputError> {
    let mut at = path;
    loop {
        match std::fs::metadata(at) {
            Ok(meta) if meta.is_dir() => {
                // The existing part made absolute, then what is still to be created.
                let rest = path.strip_prefix(at).unwrap_or(path);
                let full = at.canonicalize().unwrap_or(at.to_path_buf()).join(rest);
                if !writable(at) {
                    return Err(InputError(format!(
                        "{option} {}: {} cannot be written by this user; choose another directory",
                        path.display(),
                        at.display()
                    )));
                }
                if let Some(store) = inside_store(&full.join("x")) {
                    return Err(InputError(format!(
                        "{option} {}: lies inside the store {} (its cache/ and failed/ are written only by `wearcoef run`); name a directory outside it",
                        path.display(),
                        store.display()
                    )));
                }
                return Ok(());
            }
            Ok(_) => {
                return Err(InputError(format!(
                    "{option} {}: {} exists and is not a directory; name a directory",
                    path.display(),
                    at.display()
                )))
            }
            Err(_) => match at.parent() {
                Some(parent) if !parent.as_os_str().is_empty() => at = parent,
                Some(_) => at = Path::new("."),
                None => return Ok(()),
            },
        }
    }
}

pub use wearcoef::io::atomic::write_atomically;

/// Check a run's threads before any start: `at_once` instances side by side, each on a pool
/// of `threads`, at least one of each and together within what this machine allows this
/// program ([`wearcoef::machine::max_threads`]). `what` names the options.
pub fn check_threads(what: &str, at_once: usize, threads: usize) -> Result<(), InputError> {
    let max = wearcoef::machine::max_threads();
    if at_once == 0 || threads == 0 {
        return Err(InputError(format!("{what}: must be ≥ 1")));
    }
    if at_once.saturating_mul(threads) > max {
        return Err(InputError(format!(
            "{what}: {at_once} instances at once on {threads} threads each would start {} threads, more than the {max} this machine allows this program (it has {} cores): choose at most {}",
            at_once as u128 * threads as u128,
            wearcoef::machine::cores(),
            (max / threads).max(1)
        )));
    }
    Ok(())
}
