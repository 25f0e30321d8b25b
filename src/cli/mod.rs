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

/// Write through a temporary sibling file and rename, so a failure leaves no partial file.
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
    let result = write(&tmp).and_then(|_| {
        std::fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
