//! What a run checks before it reuses an entry, cheaply enough to do every time:
//! - the manifest sits where its key says and its parameters still hash to that key;
//! - each output file is unchanged since it was last hashed: its size, inode, modification
//!   and change times are compared with those recorded then (`D/.checked/<stage>/<key>.json`);
//!   any difference, or no record, hashes the file again (as DVC does);
//! - each input still holds what the entry was computed from: the manifest records the
//!   digest of every input's outputs and results, so an entry computed from an input that
//!   was damaged and later rebuilt is recomputed instead of reused.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::base::{io_err, list_dirs, read_manifest, Manifest, Store, StoreError, MANIFEST};
use super::hash::{canonical_json, instance_key, sha256_file, sha256_hex};

/// What says whether a file changed since it was hashed.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
struct Seen {
    bytes: u64,
    dev: u64,
    ino: u64,
    mtime_ns: i128,
    ctime_ns: i128,
}

fn seen(path: &Path) -> std::io::Result<Seen> {
    use std::os::unix::fs::MetadataExt;
    let m = std::fs::metadata(path)?;
    Ok(Seen {
        bytes: m.len(),
        dev: m.dev(),
        ino: m.ino(),
        mtime_ns: m.mtime() as i128 * 1_000_000_000 + m.mtime_nsec() as i128,
        ctime_ns: m.ctime() as i128 * 1_000_000_000 + m.ctime_nsec() as i128,
    })
}

impl Manifest {
    /// The digest of what the entry holds (its outputs' hashes and its results but for
    /// their timings, every one named `*_seconds`), which the entries computed from it
    /// record: the same for every computation of the same instance.
    pub fn content_digest(&self) -> String {
        fn untimed(v: &serde_json::Value) -> serde_json::Value {
            match v {
                serde_json::Value::Object(m) => m
                    .iter()
                    .filter(|(k, _)| !k.ends_with("_seconds"))
                    .map(|(k, x)| (k.clone(), untimed(x)))
                    .collect(),
                serde_json::Value::Array(a) => a.iter().map(untimed).collect(),
                other => other.clone(),
            }
        }
        let v = serde_json::json!({"outputs": self.outputs, "results": untimed(&self.results)});
        sha256_hex(canonical_json(&v).as_bytes())
    }
}

/// The manifest found at `<stage>/<key>` belongs there: it names that stage and key, its
/// parameters hash to the key, and its results to their recorded hash.
pub(super) fn check_identity(stage: &str, key: &str, manifest: &Manifest) -> Result<(), String> {
    if manifest.stage != stage || manifest.key != key {
        return Err(format!(
            "manifest names {}/{} but the entry sits at {stage}/{key}",
            manifest.stage, manifest.key
        ));
    }
    // Outputs are plain file names in the entry (a forged "../x" would be read, or copied
    // into a gallery, outside the store).
    if let Some(name) = manifest.outputs.keys().find(|n| {
        n.is_empty()
            || n.starts_with('.')
            || n.len() > 255
            || !n
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
    }) {
        return Err(format!(
            "manifest lists an output {name:?}, which is not a plain file name of the entry"
        ));
    }
    let recomputed = instance_key(stage, manifest.version, &manifest.params, &manifest.inputs);
    if recomputed != key {
        return Err(format!(
            "manifest parameters hash to {recomputed}, not to the entry's key"
        ));
    }
    if let Some(recorded) = &manifest.results_sha256 {
        let hash = manifest.results_hash();
        if &hash != recorded {
            return Err(format!(
                "manifest results hash to {hash}, not to the recorded {recorded}: a result was edited"
            ));
        }
    }
    Ok(())
}

/// Where the [`Seen`] of the outputs of entry `D/cache/<stage>/<key>` are recorded when they
/// were last hashed: `D/.checked/<stage>/<key>.json`, out of the way of anything that lists
/// the cache.
fn seen_path(dir: &Path) -> PathBuf {
    let key = dir.file_name().unwrap_or_default().to_string_lossy();
    let stage_dir = dir.parent().unwrap_or(Path::new("."));
    let stage = stage_dir.file_name().unwrap_or_default();
    let root = stage_dir
        .parent()
        .and_then(Path::parent)
        .unwrap_or(Path::new("."));
    root.join(CHECKED).join(stage).join(format!("{key}.json"))
}

/// The directory of the records of what was hashed, under the store's root.
pub(super) const CHECKED: &str = ".checked";

/// Record the outputs of the entry just stored in `dir` as hashed (its commit hashed them).
pub(super) fn record_seen(dir: &Path, manifest: &Manifest) {
    let now: Option<BTreeMap<String, Seen>> = manifest
        .outputs
        .keys()
        .map(|name| Some((name.clone(), seen(&dir.join(name)).ok()?)))
        .collect();
    if let Some(now) = now {
        write_seen(&seen_path(dir), &now);
    }
}

/// Write a record (a record that cannot be written only means hashing again next time).
fn write_seen(path: &Path, seen: &BTreeMap<String, Seen>) {
    let text = serde_json::to_string(seen).expect("stats serialise");
    if let Some(dir) = path.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    let _ = crate::io::atomic::write_atomically(path, |tmp| Ok(std::fs::write(tmp, text)?));
}

impl Store {
    /// Check the outputs of the entry in `dir` against `manifest`: sizes always, hashes of
    /// the files whose size, inode or times changed since they were last hashed. Records
    /// what it hashed (a record that cannot be written only means hashing again next time).
    pub(super) fn check_outputs_fresh(
        &self,
        dir: &Path,
        manifest: &Manifest,
    ) -> Result<(), StoreError> {
        let record = seen_path(dir);
        let before: BTreeMap<String, Seen> = std::fs::read_to_string(&record)
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or_default();
        let mut now = BTreeMap::new();
        for (name, file) in &manifest.outputs {
            let path = dir.join(name);
            let corrupt = |reason: String| StoreError::Corrupt {
                path: path.display().to_string(),
                reason,
            };
            let s = seen(&path).map_err(|e| corrupt(format!("output file unreadable ({e})")))?;
            if s.bytes != file.bytes {
                return Err(corrupt(format!(
                    "size {} bytes, manifest says {}",
                    s.bytes, file.bytes
                )));
            }
            if before.get(name) != Some(&s) {
                let (hash, _) = sha256_file(&path).map_err(io_err(&path))?;
                if hash != file.sha256 {
                    return Err(corrupt(format!(
                        "SHA-256 {hash} differs from the manifest's {}: the file changed after it was stored",
                        file.sha256
                    )));
                }
            }
            now.insert(name.clone(), s);
        }
        if now != before {
            write_seen(&record, &now);
        }
        Ok(())
    }

    /// Remove an entry directory and its record of what was hashed.
    pub fn remove_entry(&self, dir: &Path) -> Result<(), StoreError> {
        std::fs::remove_dir_all(dir).map_err(io_err(dir))?;
        let _ = std::fs::remove_file(seen_path(dir));
        Ok(())
    }

    /// Remove the records of what was hashed whose entry is gone; returns how many.
    pub(super) fn remove_orphan_records(&self) -> Result<usize, StoreError> {
        let mut removed = 0;
        for stage_dir in list_dirs(&self.root().join(CHECKED))? {
            let stage = stage_dir.file_name().unwrap_or_default().to_owned();
            let Ok(read) = std::fs::read_dir(&stage_dir) else {
                continue;
            };
            for e in read.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                let Some(key) = name.strip_suffix(".json") else {
                    continue;
                };
                let entry = self.cache_dir().join(&stage).join(key);
                if !entry.is_dir() && std::fs::remove_file(e.path()).is_ok() {
                    removed += 1;
                }
            }
        }
        Ok(removed)
    }

    /// The stage and directory of the entry with `key`, whatever its stage.
    fn find_key(&self, key: &str) -> Result<Option<(String, PathBuf)>, StoreError> {
        for stage_dir in list_dirs(&self.cache_dir())? {
            let dir = stage_dir.join(key);
            if dir.join(MANIFEST).is_file() {
                let stage = stage_dir
                    .file_name()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                return Ok(Some((stage, dir)));
            }
        }
        Ok(None)
    }

    /// The first input of `manifest` whose content differs from what the entry was
    /// computed from (`stage/key`); inputs absent from the store, and entries of builds
    /// that recorded no digests, have nothing to compare.
    pub fn changed_input(&self, manifest: &Manifest) -> Result<Option<String>, StoreError> {
        for (key, digest) in &manifest.input_digests {
            let Some((stage, dir)) = self.find_key(key)? else {
                continue;
            };
            // An input that is itself unsound is reported, and rebuilt, on its own; this
            // entry is outdated only if the rebuilt input then differs from what it read.
            let Ok(input) = read_manifest(&dir) else {
                continue;
            };
            if check_identity(&stage, key, &input).is_err() {
                continue;
            }
            if &input.content_digest() != digest {
                return Ok(Some(format!("{stage}/{key}")));
            }
        }
        Ok(None)
    }

    /// The manifest of an entry a run may reuse: present, sound ([`Store::lookup`]) and
    /// computed from its inputs as they are now. `Ok(None)` also when it is outdated.
    pub fn reusable(&self, stage: &str, key: &str) -> Result<Option<Manifest>, StoreError> {
        let Some(manifest) = self.lookup(stage, key)? else {
            return Ok(None);
        };
        Ok(self.changed_input(&manifest)?.is_none().then_some(manifest))
    }
}
