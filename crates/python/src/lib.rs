//! `wearcoef._wearcoef`, the Python package's native module: conversions between Python
//! values and the library that the `wearcoef` binary is a face of. No numerical code lives
//! here: a map given as an array is prepared by `io::prepare::prepare_map`, pressed by
//! `wear::compute` and tabulated by `Wear::frames`, exactly as `wearcoef wear` does; a
//! periodic solve is `solve::sweep`, as `wearcoef solve`; a fit is `tail::fit_row`, as
//! `wearcoef fit --json`. Arrays cross as little-endian float64 bytes and tables as Parquet
//! bytes; the Python side (python/wearcoef/__init__.py) turns them into numpy arrays and
//! pandas DataFrames.

use polars::prelude::{DataFrame, ParquetWriter};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use wearcoef::io::measured::{MeasuredMap, Source};
use wearcoef::io::prepare::{prepare_map, Preparation};
use wearcoef::ranges::InputError;
use wearcoef::wear::{Settings, WearOptions};

/// A Python exception carrying the command line's message: `ValueError` for the user's
/// input (where the binary exits with 2), `RuntimeError` otherwise.
fn to_python(e: anyhow::Error) -> PyErr {
    let message = format!("{e:#}");
    if wearcoef::pipeline::is_input_error(&e) {
        PyValueError::new_err(message)
    } else {
        PyRuntimeError::new_err(message)
    }
}

fn input(message: String) -> PyErr {
    to_python(InputError(message).into())
}

/// Little-endian float64 bytes as values, `count` of them.
fn floats(name: &str, bytes: &[u8], count: usize) -> PyResult<Vec<f64>> {
    if bytes.len() != 8 * count {
        return Err(input(format!(
            "{name}: {} bytes for {count} float64 values",
            bytes.len()
        )));
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
        .collect())
}

fn to_bytes(values: &[f64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn parquet(df: &mut DataFrame) -> anyhow::Result<Vec<u8>> {
    let mut buffer = Vec::new();
    ParquetWriter::new(&mut buffer).finish(df)?;
    Ok(buffer)
}

/// A progress callback (no arguments, called once per load solved) as a Rust closure that
/// takes the interpreter for the call; its exceptions are ignored (progress only shows).
fn progress_of(callback: Option<Py<PyAny>>) -> impl Fn() + Send + Sync {
    move || {
        if let Some(cb) = &callback {
            Python::attach(|py| {
                let _ = cb.call0(py);
            });
        }
    }
}

/// `wear`'s results: loads, clusters and PSD as Parquet bytes, the record as JSON, and the
/// pressures as float64 bytes when asked.
type WearOut = (Py<PyAny>, Py<PyAny>, Py<PyAny>, String, Option<Py<PyAny>>);

/// The run of `wear` on a map in metres (`heights`: rows × cols float64, row-major, rows
/// along y, NaN missing) with pixels `pixel_x_m × pixel_y_m`: its loads, clusters and PSD as
/// Parquet bytes, the preparation's record as JSON, and the pressures (Pa, loads × rows ×
/// cols float64 bytes) when asked.
#[pyfunction]
#[pyo3(signature = (
    heights, rows, cols, pixel_x_m, pixel_y_m, name, preparation, resample, e_star, loads,
    a_star=None, d_star=None, hardness=None, tolerance=1e-8, d_star_factors=(0.5, 2.0),
    trust_band=true, resamples=200, pressure_maps=false, progress=None
))]
#[allow(clippy::too_many_arguments)]
fn wear(
    py: Python<'_>,
    heights: &[u8],
    rows: usize,
    cols: usize,
    pixel_x_m: f64,
    pixel_y_m: f64,
    name: &str,
    preparation: &str,
    resample: bool,
    e_star: &str,
    loads: Vec<String>,
    a_star: Option<String>,
    d_star: Option<String>,
    hardness: Option<String>,
    tolerance: f64,
    d_star_factors: (f64, f64),
    trust_band: bool,
    resamples: usize,
    pressure_maps: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<WearOut> {
    let heights = floats("heights", heights, rows.saturating_mul(cols))?;
    let mut p: Preparation = serde_json::from_str(preparation)
        .map_err(|e| input(format!("preparation {preparation}: {e}")))?;
    p.resample = resample;
    let options = WearOptions {
        e_star: e_star.to_string(),
        loads,
        a_star,
        d_star,
        hardness,
        tolerance,
        d_star_factors: vec![d_star_factors.0, d_star_factors.1],
        no_trust_band: !trust_band,
        resamples,
    };
    let map = MeasuredMap {
        rows,
        cols,
        heights,
        height_unit_m: Some(1.0),
        pixel_m: Some((pixel_x_m, pixel_y_m)),
        pixel_file_units: None,
        source: Source::Array,
    };
    let name = name.to_string();
    let step = progress_of(progress);
    let run = py.detach(move || -> anyhow::Result<_> {
        let settings = Settings::new(&options)?;
        let prepared = prepare_map(map, &name, &name, &p)?;
        let mut pressures = Vec::new();
        let run = wearcoef::wear::compute(
            prepared,
            &settings,
            &mut |field| {
                if pressure_maps {
                    pressures.extend_from_slice(field);
                }
                Ok(())
            },
            &step,
        )?;
        let [mut loads, mut clusters, mut psd] = run.frames()?;
        Ok((
            parquet(&mut loads)?,
            parquet(&mut clusters)?,
            parquet(&mut psd)?,
            serde_json::to_string(&run.report)?,
            pressure_maps.then(|| to_bytes(&pressures)),
        ))
    });
    let (loads, clusters, psd, report, pressures) = run.map_err(to_python)?;
    let bytes = |b: Vec<u8>| PyBytes::new(py, &b).into_any().unbind();
    Ok((
        bytes(loads),
        bytes(clusters),
        bytes(psd),
        report,
        pressures.map(bytes),
    ))
}

/// `wearcoef solve`: the contact of square heights (side `n`, float64 little-endian bytes,
/// row-major, a box of side 1, periodic or not) at each load W/W0: the pressures (in units of
/// E*) and, when asked, the gaps (in the heights' unit), each loads × n × n float64 bytes,
/// and the per-load summary as JSON (`solve --json`'s).
#[pyfunction]
#[pyo3(signature = (heights, n, loads, periodic=true, gaps=false, tolerance=1e-8, max_iterations=5000, e_star=1.0, hardness=None))]
#[allow(clippy::too_many_arguments)]
fn solve(
    py: Python<'_>,
    heights: &[u8],
    n: usize,
    loads: Vec<f64>,
    periodic: bool,
    gaps: bool,
    tolerance: f64,
    max_iterations: usize,
    e_star: f64,
    hardness: Option<f64>,
) -> PyResult<(Py<PyAny>, Option<Py<PyAny>>, String)> {
    let heights = floats("heights", heights, n.saturating_mul(n))?;
    let options = wearcoef::solve::SolveOptions {
        tol: tolerance,
        max_iter: max_iterations,
        e_star,
        hardness,
        ..Default::default()
    };
    let run = py.detach(move || -> anyhow::Result<_> {
        options.config(&loads)?;
        wearcoef::solve::check_heights("heights", n, &heights)?;
        let mut pressures = Vec::with_capacity(loads.len() * n * n);
        let mut gap = Vec::new();
        let each = |_, solved: &wearcoef::contact::sweep::Solved| {
            pressures.extend_from_slice(solved.pressure);
            if gaps {
                gap.extend(solved.gap());
            }
            Ok(())
        };
        let results = if periodic {
            wearcoef::solve::sweep(&heights, n, &loads, &options, each)?
        } else {
            wearcoef::solve::sweep_free(&heights, n, &loads, &options, each)?
        };
        let rows = wearcoef::solve::json_rows(&results);
        let gap = gaps.then(|| to_bytes(&gap));
        Ok((to_bytes(&pressures), gap, serde_json::to_string(&rows)?))
    });
    let (pressures, gap, rows) = run.map_err(to_python)?;
    let bytes = |b: Vec<u8>| PyBytes::new(py, &b).into_any().unbind();
    Ok((bytes(pressures), gap.map(bytes), rows))
}

/// `wearcoef fit --json`'s row for one load's cluster areas (whole pixels ≥ 1): the
/// truncated power law above x_min with its bootstrap interval and tail tests, and the
/// plateau + power law, as JSON.
#[pyfunction]
#[pyo3(signature = (areas, resamples=200, seed=1))]
fn fit(py: Python<'_>, areas: Vec<u64>, resamples: usize, seed: u64) -> PyResult<String> {
    if let Some(bad) = areas.iter().find(|&&a| a == 0) {
        return Err(input(format!(
            "areas: {bad} px; cluster areas are whole pixels ≥ 1"
        )));
    }
    wearcoef::ranges::RESAMPLES
        .check_count("resamples", resamples as u64)
        .map_err(input)?;
    let row =
        py.detach(move || wearcoef::tail::fit_row(None, f64::NAN, &areas, 0, resamples, seed));
    serde_json::to_string(&row).map_err(|e| to_python(e.into()))
}

/// The plateau + power-law model of Appendix A (`wearcoef model --json`): K and 𝒦 at
/// `a_star` for α, the plateau's end `a_s` and the cut-off `a_m` (`inf` for none).
#[pyfunction]
fn model(alpha: f64, a_s: f64, a_m: f64, a_star: f64) -> PyResult<(f64, f64)> {
    let bad = |e: wearcoef::analytic::ModelError| input(e.to_string());
    let m = wearcoef::analytic::PlateauPowerLaw::new(alpha, a_s, a_m).map_err(bad)?;
    Ok((
        m.k_archard(a_star).map_err(bad)?,
        m.k_upscaled(a_star).map_err(bad)?,
    ))
}

/// The program that computes: `(name, version, git commit or None)`.
#[pyfunction]
fn program() -> (String, String, Option<String>) {
    let p = wearcoef::store::Program::current();
    (p.name, p.version, p.git_commit)
}

#[pymodule]
fn _wearcoef(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(wear, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(model, m)?)?;
    m.add_function(wrap_pyfunction!(program, m)?)?;
    Ok(())
}
