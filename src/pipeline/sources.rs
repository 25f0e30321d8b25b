//! The files a plan reads from outside the store: a measured study's topography files,
//! hashed and measured when the plan is made, and copied into their entries when run.

use serde::{Deserialize, Serialize};

use crate::config::MeasuredPlan;
use crate::stages::surface::{measured_file_name, MeasuredJob, SurfaceJob};

/// A file outside the store that an instance reads: where it lies (absolute, so that a
/// saved plan runs from any directory), and the name the stage reads it under in its entry.
/// Not part of the key.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SourceFile {
    pub path: std::path::PathBuf,
    pub file: String,
}

/// The surface job of each file of a measured study, keyed by the file's SHA-256, with its
/// source. The files must all be of one shape; an unreadable one is an error naming its
/// field of pipeline.yaml.
pub fn measured_surfaces(m: &MeasuredPlan) -> anyhow::Result<Vec<(SurfaceJob, SourceFile)>> {
    let mut shape = None;
    let mut out = Vec::new();
    let mut seen: Vec<(String, &str)> = Vec::new();
    for (path, field) in m.files.iter().zip(&m.fields) {
        let bad = |why: String| {
            crate::pipeline::error::UsageError(format!("{field} = {}: {why}", path.display()))
        };
        // A device (/dev/zero) or a pipe would be hashed forever: refused by its kind.
        crate::io::guard::regular_file(path).map_err(|e| {
            bad(format!(
                "{e}{}",
                if e.contains("does not exist") {
                    "; paths are relative to the pipeline file"
                } else {
                    ""
                }
            ))
        })?;
        let (sha256, _) = crate::store::hash::sha256_file(path).map_err(|e| {
            bad(format!(
                "cannot be read ({e}); paths are relative to the pipeline file"
            ))
        })?;
        if let Some((_, other)) = seen.iter().find(|(h, _)| *h == sha256) {
            return Err(bad(format!(
                "holds the same bytes as {other} (SHA-256 {}…): one measurement is one realization; list each file once",
                &sha256[..12]
            ))
            .into());
        }
        seen.push((sha256.clone(), field.as_str()));
        let read = crate::io::read_measured(path).map_err(|e| {
            // The reader names the path; the field names it already.
            let text = e.to_string();
            let prefix = format!("{}: ", path.display());
            bad(text.strip_prefix(&prefix).unwrap_or(&text).to_string())
        })?;
        check_preparation(&read, &m.preparation, field).map_err(bad)?;
        crate::io::prepare::check_for_contact(&read, &m.preparation).map_err(bad)?;
        let this = (read.rows, read.cols);
        let first = *shape.get_or_insert(this);
        if first != this {
            return Err(bad(format!(
                "is {} × {}, the study's first file {} × {}: the files of a study share one shape",
                this.0, this.1, first.0, first.1
            ))
            .into());
        }
        let file = measured_file_name(path);
        let job = SurfaceJob::Measured(MeasuredJob {
            file: file.clone(),
            sha256,
            rows: read.rows,
            cols: read.cols,
            preparation: m.preparation.clone(),
            reader: crate::stages::surface::MEASURED_READER,
        });
        let source = SourceFile {
            path: std::path::absolute(path)?,
            file,
        };
        out.push((job, source));
    }
    Ok(out)
}

/// What a file needs from its study's `preparation` that it does not state, refused when the
/// plan is made (naming the field to set) rather than when its surface is computed.
fn check_preparation(
    read: &crate::io::measured::MeasuredMap,
    p: &crate::io::prepare::Preparation,
    field: &str,
) -> Result<(), String> {
    // `studies.<name>.measured.files[i]` → `studies.<name>.measured.preparation`.
    let prep = match field.rfind(".files[") {
        Some(i) => format!("{}.preparation", &field[..i]),
        None => "preparation".to_string(),
    };
    let missing = read.missing();
    if missing > 0 && p.fill == crate::io::prepare::FillArg::None {
        return Err(format!(
            "{missing} of {} points are missing: set {prep}.fill: harmonic to fill them",
            read.rows * read.cols
        ));
    }
    if read.height_unit_m.is_none() && p.height_unit.is_none() {
        return Err(format!(
            "the file states no height unit: set {prep}.height_unit (m, mm, um, nm)"
        ));
    }
    if read.pixel_m.is_none() && read.pixel_file_units.is_none() && p.pixel_size.is_none() {
        return Err(format!(
            "the file states no pixel size: set {prep}.pixel_size (in {prep}.pixel_unit, default the height unit)"
        ));
    }
    Ok(())
}
