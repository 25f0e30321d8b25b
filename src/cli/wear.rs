//! `wearcoef wear`: one measured topography file to its wear coefficients, the command
//! line's face of [`wearcoef::wear`]: the file read and prepared (`topography`), the run
//! computed, and its tables and page written whole into `--out`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use wearcoef::wear::{compute, Settings, WearOptions};

use super::checks::InputError;
use super::topography::{prepare, FillArg, PrepareArgs};

#[derive(clap::Args)]
pub struct WearArgs {
    #[command(flatten)]
    pub prepare: PrepareArgs,
    #[command(flatten)]
    pub options: WearOptions,
    /// Also write the contact pressure of every load: pressure.npy, float64 in Pa, shape
    /// (loads, rows, cols).
    #[arg(long)]
    pub pressure_maps: bool,
    /// The output directory (created; if it exists it must be empty).
    #[arg(short, long)]
    pub out: PathBuf,
}

/// The output directory, checked before any work: absent (it is created, whole, when the
/// run ends) or an existing empty directory; never anything else.
fn check_output_dir(out: &Path) -> Result<(), InputError> {
    match std::fs::read_dir(out) {
        Ok(mut entries) => {
            if entries.next().is_some() {
                return Err(InputError(format!(
                    "--out {}: exists and is not empty; name a new directory (nothing is overwritten)",
                    out.display()
                )));
            }
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            super::checks::check_dir("--out", out)
        }
        Err(_) if out.exists() => Err(InputError(format!(
            "--out {}: exists and is not a directory; name a new directory",
            out.display()
        ))),
        Err(e) => Err(InputError(format!("--out {}: {e}", out.display()))),
    }
}

/// A float64 `.npy` of shape `shape` written one block of values at a time, so that the
/// pressure maps of a sweep are never all in memory.
struct NpyStream {
    file: std::io::BufWriter<std::fs::File>,
}

impl NpyStream {
    fn create(path: &Path, shape: &[usize]) -> std::io::Result<Self> {
        use std::io::Write;
        let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
        let mut dict = format!(
            "{{'descr': '<f8', 'fortran_order': False, 'shape': ({},), }}",
            dims.join(", ")
        );
        // Magic (6), version (2), length (2), the dict and a newline: a multiple of 64.
        while (10 + dict.len() + 1) % 64 != 0 {
            dict.push(' ');
        }
        dict.push('\n');
        let mut file = std::io::BufWriter::new(std::fs::File::create(path)?);
        file.write_all(b"\x93NUMPY\x01\x00")?;
        file.write_all(&(dict.len() as u16).to_le_bytes())?;
        file.write_all(dict.as_bytes())?;
        Ok(NpyStream { file })
    }

    fn push(&mut self, values: &[f64]) -> std::io::Result<()> {
        use std::io::Write;
        for v in values {
            self.file.write_all(&v.to_le_bytes())?;
        }
        Ok(())
    }

    fn finish(mut self) -> std::io::Result<()> {
        use std::io::Write;
        self.file.flush()?;
        self.file.get_ref().sync_all()
    }
}

pub fn wear(args: WearArgs) -> anyhow::Result<ExitCode> {
    if args.prepare.preparation.fill == FillArg::Keep {
        return Err(InputError(
            "--fill keep: contact needs every height; choose --fill harmonic or none".into(),
        )
        .into());
    }
    let settings = Settings::new(&args.options)?;
    check_output_dir(&args.out)?;
    let prepared = prepare(&args.prepare)?;
    wearcoef::wear::check_memory(&prepared.map)?;
    let (rows, cols, loads) = (prepared.map.rows, prepared.map.cols, settings.loads.len());
    // Everything is written into a staging directory, moved onto --out when complete.
    let staged = wearcoef::io::atomic::StagedDir::new(&args.out)?;
    let dir = staged.path().to_path_buf();
    let mut pressures = match args.pressure_maps {
        true => Some(NpyStream::create(
            &dir.join("pressure.npy"),
            &[loads, rows, cols],
        )?),
        false => None,
    };
    let bar = load_bar(loads);
    let run = compute(
        prepared,
        &settings,
        &mut |p| match pressures.as_mut() {
            Some(stream) => stream.push(p).map_err(|e| {
                wearcoef::io::cannot_write(&args.out.join("pressure.npy"), &e.to_string())
            }),
            None => Ok(()),
        },
        &|| bar.inc(1),
    )?;
    bar.finish_and_clear();
    pressures.map(NpyStream::finish).transpose()?;
    let drawn = run.write(&dir)?;
    staged.commit()?;
    if !drawn {
        return Ok(ExitCode::FAILURE);
    }
    say_written(loads, rows, cols, &args.out)?;
    Ok(ExitCode::SUCCESS)
}

/// The contact sweep's progress bar over `loads` loads.
fn load_bar(loads: usize) -> indicatif::ProgressBar {
    indicatif::ProgressBar::new(loads as u64).with_style(
        indicatif::ProgressStyle::with_template("contact {bar:30} {pos}/{len} loads, {elapsed}")
            .expect("a valid template"),
    )
}

/// The line that says what was written where.
fn say_written(loads: usize, rows: usize, cols: usize, out: &Path) -> anyhow::Result<()> {
    out!(
        "{} on a {rows} × {cols} map written to {} (index.html, loads.parquet, loads.csv, clusters.parquet, psd.parquet, preparation.json)",
        match loads {
            1 => "1 load".to_string(),
            n => format!("{n} loads"),
        },
        out.display()
    )?;
    Ok(())
}
