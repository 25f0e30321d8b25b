//! A profile's gallery: its figures copied from the store to `<figures>/<profile>/` (`run
//! --figures`, default `figures/` in the working directory), with `provenance.json` saying
//! which store instances drew them.
//!
//! `provenance.json` is written by the program, never by hand: for every figure the profile
//! declares, the figures-stage instance key, the files it wrote, and the instances it was
//! drawn from (stage, key, studies). Since keys are content hashes of the jobs, the record
//! of a committed gallery can be compared with what its profile would build now
//! ([`expected`]), without drawing anything.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::plan::Instance;
use crate::store::Store;

/// The record's file name.
pub const PROVENANCE: &str = "provenance.json";

/// Extensions of the files a figure writes. A run removes only files of these kinds that the
/// gallery's previous `provenance.json` lists and the profile no longer draws; anything
/// else in the directory is left alone.
const FIGURE_FILES: [&str; 5] = ["png", "svg", "csv", "npy", "parquet"];

/// One instance a figure was drawn from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DrawnFrom {
    pub stage: String,
    pub key: String,
    /// The studies of the profile that use it.
    pub studies: Vec<String>,
}

/// One figure of a gallery.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FigureRecord {
    /// The figure's name in pipeline.yaml.
    pub figure: String,
    /// Its figures-stage instance key.
    pub key: String,
    /// The files it wrote (once the figure is drawn; empty in [`expected`]).
    pub files: Vec<String>,
    pub drawn_from: Vec<DrawnFrom>,
}

/// A gallery's `provenance.json`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Provenance {
    pub profile: String,
    /// Ordered by figure name.
    pub figures: Vec<FigureRecord>,
}

/// Directory the figures of `profile` are copied to: `<figures>/<profile>/`.
pub fn dir(figures: &Path, profile: &str) -> PathBuf {
    figures.join(profile)
}

/// The record of the figures instances among `all` (files left empty).
pub fn expected(all: &[Instance], profile: &str) -> Provenance {
    let by_key: BTreeMap<&str, &Instance> = all.iter().map(|i| (i.key.as_str(), i)).collect();
    let mut figures: Vec<FigureRecord> = all
        .iter()
        .filter(|i| i.stage == "figures")
        .map(|i| FigureRecord {
            figure: i.name.clone().unwrap_or_default(),
            key: i.key.clone(),
            files: Vec::new(),
            drawn_from: i
                .inputs
                .iter()
                .map(|r| DrawnFrom {
                    stage: r.stage.clone(),
                    key: r.key.clone(),
                    studies: by_key
                        .get(r.key.as_str())
                        .map(|i| i.studies.clone())
                        .unwrap_or_default(),
                })
                .collect(),
        })
        .collect();
    figures.sort_by(|a, b| a.figure.cmp(&b.figure));
    Provenance {
        profile: profile.to_string(),
        figures,
    }
}

/// Copy every stored figure file of the profile to [`dir`], each through a temporary file
/// renamed into place. With `record` (a whole profile, not some targets), also write
/// `provenance.json` and remove figure files the profile no longer draws, so the gallery
/// holds exactly its declared figures; returns the record then.
pub fn export(
    store: &Store,
    figures: &Path,
    all: &[Instance],
    profile: &str,
    record: bool,
) -> anyhow::Result<Option<Provenance>> {
    let out = dir(figures, profile);
    let mut provenance = expected(all, profile);
    // The files this program wrote here before (the last record): the only ones it removes.
    let before: BTreeSet<String> = std::fs::read_to_string(out.join(PROVENANCE))
        .ok()
        .and_then(|t| serde_json::from_str::<Provenance>(&t).ok())
        .map(|p| p.figures.into_iter().flat_map(|f| f.files).collect())
        .unwrap_or_default();
    let mut written: BTreeMap<String, String> = BTreeMap::new();
    for fig in &mut provenance.figures {
        let Some(manifest) = store.lookup("figures", &fig.key)? else {
            continue;
        };
        std::fs::create_dir_all(&out)?;
        crate::io::atomic::remove_dead_temporaries(&out)?;
        for file in manifest.outputs.keys() {
            if let Some(other) = written.insert(file.clone(), fig.figure.clone()) {
                anyhow::bail!(
                    "figures {other} and {} of profile {profile} both write {file}: give each \
                     profile one figure of a kind whose files have fixed names",
                    fig.figure
                );
            }
            let src = store.read_output(&manifest, file)?;
            crate::io::atomic::write_atomically(&out.join(file), |tmp| {
                std::fs::copy(&src, tmp)?;
                Ok(())
            })?;
            fig.files.push(file.clone());
        }
        fig.files.sort();
    }
    if !record || !out.is_dir() {
        return Ok(None);
    }
    for name in before.difference(&written.keys().cloned().collect()) {
        let path = out.join(name);
        let ours = path
            .extension()
            .is_some_and(|e| FIGURE_FILES.iter().any(|f| e == *f));
        if ours && path.is_file() && !name.contains('/') {
            std::fs::remove_file(&path)?;
        }
    }
    let text = serde_json::to_string_pretty(&provenance)? + "\n";
    crate::io::atomic::write_atomically(&out.join(PROVENANCE), |tmp| {
        Ok(std::fs::write(tmp, text)?)
    })?;
    Ok(Some(provenance))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stages::InputRef;
    use serde_json::json;

    fn inst(
        stage: &str,
        key: &str,
        name: Option<&str>,
        inputs: &[&str],
        studies: &[&str],
    ) -> Instance {
        Instance {
            stage: stage.into(),
            key: key.into(),
            params: json!({}),
            inputs: inputs
                .iter()
                .map(|k| InputRef {
                    stage: "statistics".into(),
                    key: (*k).into(),
                })
                .collect(),
            level: 0,
            studies: studies.iter().map(|s| s.to_string()).collect(),
            realization: None,
            name: name.map(str::to_string),
            cached: false,
            estimate: Default::default(),
            source: None,
        }
    }

    #[test]
    fn the_record_names_each_figure_with_the_studies_it_was_drawn_from() {
        let all = vec![
            inst("statistics", "s1", None, &[], &["fig3_ll8"]),
            inst("statistics", "s2", None, &[], &["fig3_ll128", "fig45"]),
            inst("figures", "f2", Some("fig6"), &[], &[]),
            inst("figures", "f1", Some("fig3_fig4a"), &["s1", "s2"], &[]),
        ];
        let p = expected(&all, "default");
        let names: Vec<&str> = p.figures.iter().map(|f| f.figure.as_str()).collect();
        assert_eq!(names, ["fig3_fig4a", "fig6"]);
        assert_eq!(p.figures[0].key, "f1");
        assert_eq!(p.figures[0].drawn_from[1].studies, ["fig3_ll128", "fig45"]);
        assert!(p.figures[1].drawn_from.is_empty());
    }
}
