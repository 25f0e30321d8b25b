//! What a store directory holds, checked before anything in it is removed: `wearcoef clean`
//! removes a directory only when every file in it is one the store writes.
//!
//! A store `D` holds `cache/<stage>/<key>/` entries (each with `manifest.json`) and their
//! temporaries `.tmp-…`; `.checked/<stage>/<key>.json`, what was last hashed of each entry;
//! `failed/<stage>/<key>.json`;
//! `campaigns/<profile>/<stamp>/` with a `campaign.json`; and one catalog directory per
//! profile, holding `index.parquet`, `index.csv` and `index_<stage>.parquet`.

use std::path::{Path, PathBuf};

use super::base::{Store, MANIFEST};

/// What a store holds, for `clean` to say what it removes.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Contents {
    pub entries: usize,
    pub failures: usize,
    pub campaigns: usize,
    pub catalogs: Vec<String>,
    pub bytes: u64,
}

impl std::fmt::Display for Contents {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} entries ({:.1} MiB), {} failure records, {} campaign records, catalogs of {} profile(s){}",
            self.entries,
            self.bytes as f64 / (1u64 << 20) as f64,
            self.failures,
            self.campaigns,
            self.catalogs.len(),
            if self.catalogs.is_empty() {
                String::new()
            } else {
                format!(" ({})", self.catalogs.join(", "))
            }
        )
    }
}

/// Whether `name` is a file the catalog of a profile writes, or one's temporary.
fn catalog_file(name: &str) -> bool {
    let plain = name.trim_start_matches('.');
    let plain = plain.split(".tmp-").next().unwrap_or(plain);
    plain == "index.parquet"
        || plain == "index.csv"
        || (plain.starts_with("index_") && plain.ends_with(".parquet"))
}

fn children(dir: &Path) -> Result<Vec<(String, PathBuf, std::fs::Metadata)>, String> {
    let read = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut out = Vec::new();
    for entry in read {
        let entry = entry.map_err(|e| format!("{}: {e}", dir.display()))?;
        let meta = std::fs::symlink_metadata(entry.path())
            .map_err(|e| format!("{}: {e}", entry.path().display()))?;
        out.push((
            entry.file_name().to_string_lossy().into_owned(),
            entry.path(),
            meta,
        ));
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(out)
}

fn foreign(path: &Path) -> String {
    format!("{} is not something a wearcoef store holds", path.display())
}

fn size_of(dir: &Path) -> u64 {
    std::fs::read_dir(dir)
        .map(|r| {
            r.flatten()
                .filter_map(|e| e.metadata().ok())
                .map(|m| m.len())
                .sum()
        })
        .unwrap_or(0)
}

impl Store {
    /// What the store holds, or the first path in it that a store does not hold (then
    /// nothing may be removed wholesale). The root must have a `cache/` directory.
    pub fn contents(&self, stages: &[&str]) -> Result<Contents, String> {
        let root = self.root();
        if !root.join("cache").is_dir() {
            return Err(format!(
                "{} has no cache/ directory: it is not a wearcoef store",
                root.display()
            ));
        }
        let mut c = Contents::default();
        for (name, path, meta) in children(root)? {
            match name.as_str() {
                "cache" => {
                    for (stage, dir, m) in children(&path)? {
                        if !m.is_dir() || !stages.contains(&stage.as_str()) {
                            return Err(foreign(&dir));
                        }
                        for (entry, p, m) in children(&dir)? {
                            if m.is_dir() && entry.starts_with(".tmp-") {
                                continue;
                            }
                            if !m.is_dir() || !p.join(MANIFEST).is_file() {
                                return Err(foreign(&p));
                            }
                            c.entries += 1;
                            c.bytes += size_of(&p);
                        }
                    }
                }
                super::fresh::CHECKED => {
                    for (_, dir, m) in children(&path)? {
                        let records = m.is_dir()
                            && children(&dir)?.iter().all(|(f, _, m)| {
                                m.is_file() && (f.ends_with(".json") || f.contains(".tmp-"))
                            });
                        if !records {
                            return Err(foreign(&dir));
                        }
                    }
                }
                "failed" => {
                    for (stage, dir, m) in children(&path)? {
                        if !m.is_dir() || !stages.contains(&stage.as_str()) {
                            return Err(foreign(&dir));
                        }
                        for (file, p, m) in children(&dir)? {
                            if !m.is_file() || !file.ends_with(".json") && !file.contains(".tmp-") {
                                return Err(foreign(&p));
                            }
                            c.failures += 1;
                        }
                    }
                }
                "campaigns" => {
                    for (_, dir, m) in children(&path)? {
                        if !m.is_dir() {
                            return Err(foreign(&dir));
                        }
                        for (_, p, m) in children(&dir)? {
                            if !m.is_dir() || !p.join("campaign.json").is_file() {
                                return Err(foreign(&p));
                            }
                            c.campaigns += 1;
                        }
                    }
                }
                _ if meta.is_dir() => {
                    for (file, p, m) in children(&path)? {
                        if !m.is_file() || !catalog_file(&file) {
                            return Err(foreign(&p));
                        }
                    }
                    c.catalogs.push(name);
                }
                _ => return Err(foreign(&path)),
            }
        }
        Ok(c)
    }

    /// Remove the store's parts ([`Store::contents`] must have passed), then the root if it
    /// is left empty.
    pub fn remove_contents(&self, contents: &Contents) -> std::io::Result<()> {
        let root = self.root();
        let mut parts: Vec<PathBuf> = ["cache", "failed", "campaigns", super::fresh::CHECKED]
            .iter()
            .map(|p| root.join(p))
            .collect();
        parts.extend(contents.catalogs.iter().map(|p| root.join(p)));
        for p in parts.iter().filter(|p| p.exists()) {
            std::fs::remove_dir_all(p)?;
        }
        // The root itself only when empty (never the files of someone else).
        let _ = std::fs::remove_dir(root);
        Ok(())
    }
}
