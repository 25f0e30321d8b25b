//! The content-addressed artifact store.
//!
//! Layout under the data directory `D`:
//! - `D/cache/<stage>/<key>/`: one complete stage instance: its output files and
//!   `manifest.json` (written last, inside a temporary directory).
//! - `D/cache/<stage>/.tmp-<key>-<host>-<pid>-<nanos>/`: an instance being written. It is
//!   renamed to `<key>/` only when complete, so a killed process leaves nothing that looks
//!   complete; leftovers of dead processes of the same host are removed by the next run or
//!   by `clean --corrupt` (on a shared file system other hosts' are left alone).
//! - `D/<profile>/index.parquet`, `index.csv`: the catalogs.
//!
//! Two processes may build the same instance at once, on one machine or on several nodes
//! sharing the store: each writes its own temporary directory; the first rename wins and the
//! other discards its copy (instances are pure functions of their key, so both copies are
//! identical). `rename(2)` of a directory onto an existing non-empty one fails on local and
//! network file systems alike, so a stored entry is never replaced. Only the local runner
//! writes catalogs; `wearcoef exec` (the cluster's workers) writes entries alone.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use hash::sha256_file;

mod base;
pub mod cluster_table;
mod fresh;
pub mod hash;
pub mod inputs;
mod layout;
pub mod table;
use base::{io_err, list_dirs, read_manifest};
pub use base::{
    CommitOutcome, EntryProblem, Manifest, OutputFile, Program, Store, StoreError, TempEntry,
    MANIFEST,
};
pub use layout::Contents;

impl Store {
    pub fn new(root: impl Into<PathBuf>) -> Self {
        Self { root: root.into() }
    }

    /// The store a run wrote at `data`, or an input error naming `--data` when there is none
    /// (no `cache/` directory).
    pub fn existing(data: &Path) -> Result<Self, crate::ranges::InputError> {
        if !data.join("cache").is_dir() {
            return Err(crate::ranges::InputError(format!(
                "--data {}: no store there (no cache/ directory); give the data directory a run \
                 wrote (default: data)",
                data.display()
            )));
        }
        Ok(Store::new(data))
    }

    /// The data directory.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// `D/cache`.
    pub fn cache_dir(&self) -> PathBuf {
        self.root.join("cache")
    }

    /// Directory of a complete entry.
    pub fn entry_dir(&self, stage: &str, key: &str) -> PathBuf {
        self.cache_dir().join(stage).join(key)
    }

    /// The manifest of a complete entry, `None` if absent. A present entry must be sound:
    /// its manifest readable and its own (stage, key and parameters hash to where it sits),
    /// every output of the recorded size and, if it changed since it was last hashed, of
    /// the recorded hash. Otherwise an error naming the file and the fix.
    pub fn lookup(&self, stage: &str, key: &str) -> Result<Option<Manifest>, StoreError> {
        let dir = self.entry_dir(stage, key);
        if !dir.exists() {
            return Ok(None);
        }
        let manifest = read_manifest(&dir)?;
        fresh::check_identity(stage, key, &manifest).map_err(|reason| StoreError::Corrupt {
            path: dir.join(MANIFEST).display().to_string(),
            reason,
        })?;
        self.check_outputs_fresh(&dir, &manifest)?;
        Ok(Some(manifest))
    }

    /// The manifest of an entry as it is, unchecked (`None` if absent or unreadable): for
    /// reading what the entry reports, never for using its outputs.
    pub fn manifest(&self, stage: &str, key: &str) -> Option<Manifest> {
        read_manifest(&self.entry_dir(stage, key)).ok()
    }

    /// Path of an output of a complete entry after checking its SHA-256 against the manifest.
    pub fn read_output(&self, manifest: &Manifest, name: &str) -> Result<PathBuf, StoreError> {
        let path = self.entry_dir(&manifest.stage, &manifest.key).join(name);
        let expected = manifest
            .outputs
            .get(name)
            .ok_or_else(|| StoreError::Corrupt {
                path: path.display().to_string(),
                reason: "not listed in the manifest".into(),
            })?;
        let (hash, _) = sha256_file(&path).map_err(io_err(&path))?;
        if hash != expected.sha256 {
            return Err(StoreError::Corrupt {
                path: path.display().to_string(),
                reason: format!(
                    "SHA-256 {hash} differs from the manifest's {}",
                    expected.sha256
                ),
            });
        }
        Ok(path)
    }

    /// Start writing an entry in a fresh temporary directory.
    pub fn begin(&self, stage: &str, key: &str) -> Result<TempEntry, StoreError> {
        let stage_dir = self.cache_dir().join(stage);
        std::fs::create_dir_all(&stage_dir).map_err(io_err(&stage_dir))?;
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0);
        let dir = stage_dir.join(format!(
            ".tmp-{key}-{}-{}-{nanos}",
            host_name(),
            std::process::id()
        ));
        std::fs::create_dir(&dir).map_err(io_err(&dir))?;
        Ok(TempEntry {
            dir,
            final_dir: stage_dir.join(key),
            committed: false,
        })
    }

    /// Remove temporary directories left by processes of this host that no longer run.
    /// Those of other hosts (a store on a shared file system) are left alone: their
    /// processes cannot be seen from here. They never look like entries (their names start
    /// with a dot) and are listed by [`Store::temporaries`].
    /// Also removes the temporary files of dead processes (a catalog, a failure record, a
    /// freshness record killed mid-write) in the store's directories.
    pub fn remove_stale_temporaries(&self) -> Result<usize, StoreError> {
        let mut removed = 0;
        let mut dirs = list_dirs(&self.root)?;
        dirs.extend(list_dirs(&self.cache_dir())?);
        dirs.extend(list_dirs(&self.root.join("failed"))?);
        dirs.extend(list_dirs(&self.root.join(fresh::CHECKED))?);
        for dir in dirs {
            removed += crate::io::atomic::remove_dead_temporaries(&dir).map_err(io_err(&dir))?;
        }
        removed += self.remove_orphan_records()?;
        let here = host_name();
        for (dir, host, pid) in self.temporaries()? {
            let local = host.is_empty() || host == here;
            let alive = pid.is_some_and(|p| Path::new("/proc").join(p.to_string()).exists());
            if local && !alive {
                std::fs::remove_dir_all(&dir).map_err(io_err(&dir))?;
                removed += 1;
            }
        }
        Ok(removed)
    }

    /// Every temporary directory of the store, with the host and pid that wrote it (host
    /// empty for directories of builds that did not record it).
    pub fn temporaries(&self) -> Result<Vec<(PathBuf, String, Option<u32>)>, StoreError> {
        let mut out = Vec::new();
        for stage_dir in list_dirs(&self.cache_dir())? {
            for dir in list_dirs(&stage_dir)? {
                let name = file_name(&dir);
                let Some(rest) = name.strip_prefix(".tmp-") else {
                    continue;
                };
                // <key>-<host>-<pid>-<nanos>; the host may contain '-', the key does not.
                let mut parts = rest.rsplitn(3, '-');
                let (_nanos, pid, head) = (parts.next(), parts.next(), parts.next());
                let pid = pid.and_then(|p| p.parse::<u32>().ok());
                let host = head
                    .and_then(|h| h.split_once('-'))
                    .map_or(String::new(), |(_, host)| host.to_string());
                out.push((dir, host, pid));
            }
        }
        Ok(out)
    }

    /// All complete entries as (stage, key, directory).
    pub fn entries(&self) -> Result<Vec<(String, String, PathBuf)>, StoreError> {
        let mut out = Vec::new();
        for stage_dir in list_dirs(&self.cache_dir())? {
            let stage = file_name(&stage_dir);
            for dir in list_dirs(&stage_dir)? {
                let key = file_name(&dir);
                if !key.starts_with('.') {
                    out.push((stage.clone(), key, dir));
                }
            }
        }
        out.sort();
        Ok(out)
    }

    /// Re-hash every entry against its manifest and recompute its key. Returns the number
    /// of entries checked and every problem found.
    pub fn verify(&self) -> Result<(usize, Vec<EntryProblem>), StoreError> {
        let entries = self.entries()?;
        let mut problems = Vec::new();
        for (stage, key, dir) in &entries {
            if let Err(reason) = check_entry(self, stage, key, dir) {
                problems.push(EntryProblem {
                    path: dir.display().to_string(),
                    reason,
                });
            }
        }
        Ok((entries.len(), problems))
    }

    /// Remove the entries that fail [`Store::verify`]; returns their paths.
    pub fn remove_corrupt(&self) -> Result<Vec<String>, StoreError> {
        let (_, problems) = self.verify()?;
        for p in &problems {
            self.remove_entry(Path::new(&p.path))?;
        }
        Ok(problems.into_iter().map(|p| p.path).collect())
    }
}

/// This machine's host name (`/proc/sys/kernel/hostname`), "" if unknown.
pub fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .and_then(|s| s.to_str())
        .unwrap_or_default()
        .to_string()
}

fn check_entry(store: &Store, stage: &str, key: &str, dir: &Path) -> Result<(), String> {
    let manifest = read_manifest(dir).map_err(|e| e.to_string())?;
    fresh::check_identity(stage, key, &manifest)?;
    if let Some(input) = store.changed_input(&manifest).map_err(|e| e.to_string())? {
        return Err(format!(
            "computed from {input}, whose content has changed since: the next run recomputes it"
        ));
    }
    for (name, file) in &manifest.outputs {
        let path = dir.join(name);
        let (hash, bytes) = sha256_file(&path).map_err(|e| format!("{name}: unreadable ({e})"))?;
        if bytes != file.bytes {
            return Err(format!(
                "{name}: {bytes} bytes, manifest says {}",
                file.bytes
            ));
        }
        if hash != file.sha256 {
            return Err(format!(
                "{name}: SHA-256 {hash} differs from the manifest's {}",
                file.sha256
            ));
        }
    }
    for entry in std::fs::read_dir(dir).map_err(|e| e.to_string())? {
        let name = entry
            .map_err(|e| e.to_string())?
            .file_name()
            .to_string_lossy()
            .to_string();
        if name != MANIFEST && !manifest.outputs.contains_key(&name) {
            return Err(format!("{name}: file not listed in the manifest"));
        }
    }
    Ok(())
}

impl TempEntry {
    /// Directory to write outputs into.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Hash every file written, write the manifest and rename into place.
    /// `manifest.outputs` is filled here from the files present.
    pub fn commit(mut self, mut manifest: Manifest) -> Result<CommitOutcome, StoreError> {
        let mut outputs = BTreeMap::new();
        for entry in std::fs::read_dir(&self.dir).map_err(io_err(&self.dir))? {
            let entry = entry.map_err(io_err(&self.dir))?;
            let name = entry.file_name().to_string_lossy().to_string();
            if name == MANIFEST {
                continue;
            }
            let (sha256, bytes) = sha256_file(&entry.path()).map_err(io_err(&entry.path()))?;
            outputs.insert(name, OutputFile { sha256, bytes });
        }
        manifest.outputs = outputs;
        manifest.results_sha256 = Some(manifest.results_hash());
        let text = serde_json::to_string_pretty(&manifest).expect("manifest serialises");
        let path = self.dir.join(MANIFEST);
        std::fs::write(&path, text + "\n").map_err(io_err(&path))?;
        debug_pause();
        match std::fs::rename(&self.dir, &self.final_dir) {
            Ok(()) => {
                self.committed = true;
                fresh::record_seen(&self.final_dir, &manifest);
                Ok(CommitOutcome::Stored)
            }
            Err(_) if self.final_dir.join(MANIFEST).exists() => Ok(CommitOutcome::AlreadyPresent),
            Err(e) => Err(StoreError::Io {
                path: self.final_dir.display().to_string(),
                source: e,
            }),
        }
    }
}

impl TempEntry {
    /// [`TempEntry::commit`], replacing a stored entry of the same key (`run --force`): the
    /// old entry is moved aside under a temporary name, the new one renamed into place, then
    /// the old one removed; a crash in between leaves either entry complete, or none (the
    /// next run rebuilds it), never a mix.
    pub fn commit_replacing(self, manifest: Manifest) -> Result<CommitOutcome, StoreError> {
        if self.final_dir.exists() {
            let stage_dir = self.final_dir.parent().unwrap_or(Path::new("."));
            let key = file_name(&self.final_dir);
            let aside = stage_dir.join(format!(
                ".tmp-{key}-{}-{}-replaced",
                host_name(),
                std::process::id()
            ));
            std::fs::rename(&self.final_dir, &aside).map_err(io_err(&self.final_dir))?;
            let outcome = self.commit(manifest);
            std::fs::remove_dir_all(&aside).map_err(io_err(&aside))?;
            return outcome;
        }
        self.commit(manifest)
    }
}

impl Drop for TempEntry {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

/// Test hook: `WEARCOEF_DEBUG_PAUSE_BEFORE_COMMIT_MS` makes every commit wait that long
/// after its files are written and before the rename, so a test can kill a run in the
/// middle of a stage deterministically. Unset in normal use.
fn debug_pause() {
    if let Some(ms) = std::env::var("WEARCOEF_DEBUG_PAUSE_BEFORE_COMMIT_MS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        std::thread::sleep(std::time::Duration::from_millis(ms));
    }
}

/// A stage instance whose computation failed (a solve that did not converge, …), kept at
/// `D/failed/<stage>/<key>.json` so that the failure can be audited: `status` and the catalog
/// show it, and the next `run` retries it only with `--retry-failed` (or when a changed
/// parameter gives it a new key). It is never an entry: nothing downstream reads it.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Failure {
    pub stage: String,
    pub key: String,
    pub params: Value,
    pub inputs: Vec<String>,
    pub studies: Vec<String>,
    pub realization: Option<u32>,
    /// The error, as the run printed it.
    pub error: String,
    /// What the stage reported (for a contact sweep: the load, solver status, iterations,
    /// last error and tolerance), `null` when it said nothing structured.
    pub report: Value,
    pub program: Program,
    pub wall_seconds: f64,
}

impl Store {
    /// `D/failed/<stage>/<key>.json`.
    pub fn failure_path(&self, stage: &str, key: &str) -> PathBuf {
        self.root
            .join("failed")
            .join(stage)
            .join(format!("{key}.json"))
    }

    /// Record a failed instance (atomically, replacing an earlier record of the same key).
    pub fn record_failure(&self, failure: &Failure) -> Result<(), StoreError> {
        let path = self.failure_path(&failure.stage, &failure.key);
        let dir = path.parent().unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        let text = serde_json::to_string_pretty(failure).expect("a failure serialises");
        crate::io::atomic::write_atomically(&path, |tmp| Ok(std::fs::write(tmp, text + "\n")?))
            .map_err(|e| StoreError::Write(format!("{e:#}")))
    }

    /// The failure record of an instance, if any (an unreadable one counts as none).
    pub fn failure(&self, stage: &str, key: &str) -> Option<Failure> {
        let text = std::fs::read_to_string(self.failure_path(stage, key)).ok()?;
        serde_json::from_str(&text).ok()
    }

    /// Remove the failure record of an instance (once it has been computed).
    pub fn clear_failure(&self, stage: &str, key: &str) -> Result<(), StoreError> {
        let path = self.failure_path(stage, key);
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(io_err(&path)(e)),
            _ => Ok(()),
        }
    }

    /// Every failure record as (stage, key, path).
    pub fn failures(&self) -> Result<Vec<(String, String, PathBuf)>, StoreError> {
        let mut out = Vec::new();
        let root = self.root.join("failed");
        for stage_dir in list_dirs(&root)? {
            let stage = file_name(&stage_dir);
            for entry in std::fs::read_dir(&stage_dir).map_err(io_err(&stage_dir))? {
                let path = entry.map_err(io_err(&stage_dir))?.path();
                let name = file_name(&path);
                if let Some(key) = name.strip_suffix(".json").filter(|k| !k.starts_with('.')) {
                    out.push((stage.clone(), key.to_string(), path));
                }
            }
        }
        out.sort();
        Ok(out)
    }
}
