//! Command groups of the `wearcoef` binary: running and inspecting a store ([`store`]),
//! plans and their execution ([`plan`]), Slurm campaigns ([`submit`]), single-stage tools on plain files ([`tools`]).

use std::path::{Path, PathBuf};

use anyhow::Context;

use wearcoef::config::Pipeline;

/// `println!` that returns the write's error instead of panicking: a reader that closes the
/// pipe early (`wearcoef status | head -1`) ends the command cleanly (exit 0, see `main`).
macro_rules! out {
    () => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock())
    }};
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
    }};
}

pub mod plan;
pub mod store;
pub mod submit;
pub mod tools;

#[derive(clap::Args, Clone)]
pub struct StoreArgs {
    /// Pipeline description.
    #[arg(long, default_value = "pipeline.yaml")]
    pub config: PathBuf,
    /// Data directory (artifact store and catalogs).
    #[arg(long, default_value = "data")]
    pub data: PathBuf,
}

/// An error that means "your input is wrong" (exit 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct InputError(pub String);

pub fn load(path: &Path) -> anyhow::Result<Pipeline> {
    Ok(Pipeline::load(path)?)
}

/// Check a command's output files before any work is done: each names a file (not a
/// directory, a device or a pipe) in a directory that exists, and no two name the same
/// file. `outputs` pairs each option with the user's path; errors name both (exit 2).
pub fn check_outputs(outputs: &[(&str, &Path)]) -> Result<(), InputError> {
    let mut seen: Vec<(&str, PathBuf)> = Vec::new();
    for &(option, path) in outputs {
        let bad = |why: String| InputError(format!("{option} {}: {why}", path.display()));
        let Some(name) = path.file_name() else {
            return Err(bad("names no file".into()));
        };
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
        let full = dir.join(name);
        if let Some((other, _)) = seen.iter().find(|(_, p)| *p == full) {
            return Err(bad(format!(
                "is also the path of {other}; give each output its own file"
            )));
        }
        seen.push((option, full));
    }
    Ok(())
}

/// Check a directory option before any work: it is a directory, or does not exist yet and
/// its nearest existing ancestor is a directory (so it can be created). Exit 2 otherwise.
pub fn check_dir(option: &str, path: &Path) -> Result<(), InputError> {
    let mut at = path;
    loop {
        match std::fs::metadata(at) {
            Ok(meta) if meta.is_dir() => return Ok(()),
            Ok(_) => {
                return Err(InputError(format!(
                    "{option} {}: {} exists and is not a directory; name a directory",
                    path.display(),
                    at.display()
                )))
            }
            Err(_) => match at.parent() {
                Some(parent) if !parent.as_os_str().is_empty() => at = parent,
                _ => return Ok(()),
            },
        }
    }
}

/// Write through a temporary sibling file and rename, so a failure leaves no partial file.
/// An error names `path`, never the temporary (exit 1: the input was fine, the write failed).
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path.file_name().context("output path has no file name")?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = write(&tmp).and_then(|_| Ok(std::fs::rename(&tmp, path)?));
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        let cause = format!("{:#}", e).replace(&tmp.display().to_string(), "");
        anyhow::bail!(wearcoef::io::cannot_write(
            path,
            cause.trim_start_matches([':', ' '])
        ));
    }
    Ok(())
}

/// Refuse work whose estimated peak memory exceeds this machine's, before allocating it.
pub fn check_memory(what: &str, bytes: u64, fix: &str) -> Result<(), InputError> {
    match wearcoef::pipeline::cost::machine_memory_bytes() {
        Some(total) if bytes > total => Err(InputError(format!(
            "{what} needs about {:.1} GiB, more than this machine's {:.1} GiB; {fix}",
            bytes as f64 / (1u64 << 30) as f64,
            total as f64 / (1u64 << 30) as f64
        ))),
        _ => Ok(()),
    }
}
