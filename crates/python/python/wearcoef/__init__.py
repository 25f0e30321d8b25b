"""wearcoef from Python: the same Rust as the `wearcoef` command line, on numpy arrays and
SurfaceTopography topographies, with pandas tables.

    import SurfaceTopography as st, wearcoef
    run = wearcoef.wear(st.read_topography("scan.x3p"), e_star="100GPa",
                        loads=["1N", "5N"], d_star="1um")
    run.loads[["force_n", "k_archard", "k_archard_band_low", "k_archard_band_high"]]

Units: lengths in metres, pressures and moduli in pascals, forces in newtons, unless a
value is given as text with its unit ("1um", "100GPa", "0.5N", "10MPa"), read exactly as
the command line reads it. Column names carry their unit (docs/CONVENTIONS.md).
"""

import io
import json
import math
import os
import warnings
from dataclasses import dataclass
from typing import Optional

import numpy as np
import pandas as pd

from . import _wearcoef

__all__ = ["wear", "solve", "fit", "model", "open_store", "Wear", "Solved", "Catalog",
           "__version__", "__commit__"]

# The version names the commit it was built from, as a PEP 440 local label ("0.1.0+g1a2b3c4d5e6f");
# __commit__ is the whole hash (None when built outside a git clone).
_name, _release, __commit__ = _wearcoef.program()
__version__ = _release if __commit__ is None else f"{_release}+g{__commit__[:12]}"

# Metres per unit, as the command line's --height-unit names them and SurfaceTopography's
# `unit` attribute spells them.
_METRES = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6, "nm": 1e-9, "A": 1e-10, "Å": 1e-10}


def _metres_per(unit):
    try:
        return _METRES[unit]
    except KeyError:
        raise ValueError(f"unit {unit!r}: one of {', '.join(_METRES)}") from None


def _with_unit(value, unit, what):
    """A quantity as the command line's text: a float is in `unit`, text carries its own."""
    if value is None:
        return None
    if isinstance(value, str):
        return value
    if isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool):
        return f"{float(value)!r}{unit}"
    raise TypeError(f"{what}: a number in {unit} or text with its unit, not {type(value).__name__}")


def _load_text(value):
    if isinstance(value, str):
        return value
    return repr(float(value))


def _map_of(topography, pixel_size, unit):
    """Heights in metres (rows along y, NaN missing), the pixel (Δx, Δy) in metres, a name."""
    if hasattr(topography, "heights") and hasattr(topography, "physical_sizes"):
        if pixel_size is not None or unit is not None:
            raise ValueError("pixel_size and unit come from the topography; give them only with an array")
        if getattr(topography, "dim", 2) != 2:
            raise ValueError("a line scan: wear needs a 2-D map")
        to_m = _metres_per(topography.unit)
        heights = np.ma.filled(np.ma.asarray(topography.heights(), dtype=np.float64), np.nan)
        # SurfaceTopography indexes heights [x, y]; rows here run along y.
        heights = np.ascontiguousarray(heights.T) * to_m
        nx, ny = topography.nb_grid_pts
        sx, sy = topography.physical_sizes
        pixel = (sx / nx * to_m, sy / ny * to_m)
        info = getattr(topography, "info", {}) or {}
        name = str(info.get("datafile", {}).get("name", "topography")) if isinstance(info, dict) else "topography"
        return heights, pixel, name
    heights = np.asarray(topography, dtype=np.float64)
    if heights.ndim != 2:
        raise ValueError(f"heights: a 2-D array (rows along y), not {heights.ndim}-D")
    if pixel_size is None or unit is None:
        raise ValueError("an array needs pixel_size (one number, or (Δx, Δy)) and unit (of heights and pixel: m, mm, um, nm)")
    to_m = _metres_per(unit)
    dx, dy = (pixel_size, pixel_size) if np.ndim(pixel_size) == 0 else pixel_size
    return np.ascontiguousarray(heights) * to_m, (float(dx) * to_m, float(dy) * to_m), "array"


def _progress(total, progress, what):
    """A callable that advances a bar of `total` steps (tqdm when installed), and its close."""
    if progress is False or total == 0:
        return None, lambda: None
    if callable(progress):
        return progress, lambda: None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None, lambda: None
    bar = tqdm(total=total, desc=what, unit="load", leave=False)
    return (lambda: bar.update(1)), bar.close


def _table(parquet_bytes):
    return pd.read_parquet(io.BytesIO(parquet_bytes))


@dataclass
class Wear:
    """A run of `wear`: the tables `wearcoef wear` writes, as DataFrames."""

    loads: pd.DataFrame
    """One row per load: W/W0, force_n, mean_pressure_pa, K, 𝒦, α̂, the trust band…"""
    clusters: pd.DataFrame
    """One row per contact cluster of every load (load_index, area_px, area_um2, touches_edge…)."""
    psd: pd.DataFrame
    """The prepared map's radially averaged PSD (q in rad/m, C in m⁴)."""
    preparation: dict
    """The preparation's record (units, pixel sizes, form, fill, PSD fit, warnings, contact)."""
    pressure: Optional[np.ndarray] = None
    """With pressure_maps=True: the contact pressure (Pa), shape (loads, rows, cols)."""


def wear(topography, *, e_star, loads, d_star=None, a_star=None, hardness=None,
         pixel_size=None, unit=None, form="plane", fill="none", resample=False,
         tolerance=1e-8, d_star_factors=(0.5, 2.0), trust_band=True, resamples=200,
         pressure_maps=False, progress=None):
    """K(W) of a measured map, as `wearcoef wear` computes it, bit for bit.

    topography: a SurfaceTopography topography (any of its readers; its unit, physical
        sizes and missing points are used), or a 2-D array of heights (rows along y) with
        `pixel_size` (Δx, or (Δx, Δy)) and `unit` (of the heights and pixel: m, mm, um, nm).
    e_star: E* = E/(1 − ν²), Pa (or text: "210GPa").
    loads: W/W0 (numbers), or text with a unit: forces ("0.5N") or mean pressures ("10MPa").
    d_star (m, or "1.2um") or a_star (m², or "2um2"): the critical junction size.
    hardness: Pa (or "3GPa"): pressures capped at it. None: elastic.
    form: "plane" (default), "mean", "curvature" or "none"; fill: "none" or "harmonic".
    resample: put rectangular pixels on square ones (never needed).
    progress: None shows a tqdm bar when tqdm is installed; False none; or a callable
        called once per load.
    Returns a `Wear` of DataFrames; its preparation's warnings are also issued as Python
    warnings. Errors in the input raise ValueError with the command line's message.
    """
    if (d_star is None) == (a_star is None):
        raise ValueError("give the critical junction size: d_star (m, or '1.2um') or a_star (m², or '2um2'), not both")
    heights, (dx, dy), name = _map_of(topography, pixel_size, unit)
    if isinstance(loads, (str, int, float)):
        loads = [loads]
    step, close = _progress(len(loads), progress, "contact")
    preparation = json.dumps({"form": form, "fill": fill})
    try:
        out = _wearcoef.wear(
            heights.astype("<f8").tobytes(), heights.shape[0], heights.shape[1], dx, dy, name,
            preparation, bool(resample), _with_unit(e_star, "Pa", "e_star"),
            [_load_text(w) for w in loads],
            a_star=_with_unit(a_star, "m2", "a_star"), d_star=_with_unit(d_star, "m", "d_star"),
            hardness=_with_unit(hardness, "Pa", "hardness"), tolerance=float(tolerance),
            d_star_factors=tuple(float(f) for f in d_star_factors), trust_band=bool(trust_band),
            resamples=int(resamples), pressure_maps=bool(pressure_maps), progress=step)
    finally:
        close()
    loads_pq, clusters_pq, psd_pq, report, pressure = out
    report = json.loads(report)
    for w in report.get("warnings", []):
        warnings.warn(f"{name}: {w}", stacklevel=2)
    if pressure is not None:
        rows, cols = heights.shape
        pressure = np.frombuffer(pressure, dtype="<f8").reshape(len(loads), rows, cols).copy()
    return Wear(_table(loads_pq), _table(clusters_pq), _table(psd_pq), report, pressure)


@dataclass
class Solved:
    """A solve: pressures, gaps and the per-load summary of `wearcoef solve --json`."""

    pressure: np.ndarray
    """Contact pressure in units of E*: (n, n) for one load, (loads, n, n) for several."""
    gap: np.ndarray
    """Gap between the rigid surface and the deformed half-space, in the heights' unit,
    shaped as `pressure`: 0 on the contact, > 0 off it; under a hardness, minus the plastic
    displacement on the saturated nodes."""
    summary: pd.DataFrame
    """Per load: w_over_w0, mean_pressure, area_fraction, n_contact_px, iterations, error…"""

    @property
    def contact(self):
        """The contact map (pressure > 0), shaped as `pressure`."""
        return self.pressure > 0


def solve(heights, loads, *, periodic=True, hardness=None, e_star=1.0, tolerance=1e-8,
          max_iterations=5000):
    """The frictionless contact of rigid heights on an elastic half-space, as `wearcoef solve`
    computes it (bit for bit; `--non-periodic` for periodic=False).

    heights: a square array of even side n, a box of side 1 (pixels 1/n, in the heights'
        unit); periodic=True: one period of a periodic surface; periodic=False: one map on
        the free-boundary half-space, nothing beyond its edges, as `wear` solves a measured map.
    loads: W/W0, one number or several, solved in order as one warm-started sweep, with
        W0 = E*·rms slope·L² (periodic: the spectral rms slope; not periodic: the map's
        slope without wrap-around), so that the mean pressure is (W/W0)·E*·rms slope.
    hardness: in units of E*·rms slope as the loads: pressures capped at it. None: elastic.
    e_star: the effective modulus E*; pressures come out in its unit.
    tolerance: on the complementarity error (docs/CONVENTIONS.md); max_iterations per load.
    Returns a `Solved`: pressure and gap arrays, (n, n) for one load, (loads, n, n) for
    several, and the per-load summary. A load that does not converge raises ValueError.
    """
    h = np.ascontiguousarray(heights, dtype="<f8")
    if h.ndim != 2 or h.shape[0] != h.shape[1]:
        raise ValueError(f"heights: a square 2-D array, not shape {h.shape}")
    single = np.ndim(loads) == 0
    w = [float(loads)] if single else [float(x) for x in loads]
    n = h.shape[0]
    pressure, gap, rows = _wearcoef.solve(
        h.tobytes(), n, w, periodic=bool(periodic), gaps=True, tolerance=float(tolerance),
        max_iterations=int(max_iterations), e_star=float(e_star),
        hardness=None if hardness is None else float(hardness))
    p, g = (np.frombuffer(b, dtype="<f8").reshape(len(w), n, n).copy() for b in (pressure, gap))
    if single:
        p, g = p[0], g[0]
    return Solved(p, g, pd.DataFrame(json.loads(rows)))


def fit(areas, *, resamples=200, seed=1):
    """α of cluster areas (whole pixels ≥ 1, one load) as `wearcoef fit --json` gives it:
    the truncated power law above x_min with its bootstrap interval, Clauset et al.'s
    goodness of fit and likelihood-ratio tests, and the plateau + power law.

    areas: a 1-D array of cluster areas in pixels (the clusters table's `area_px`).
    resamples: bootstrap replicates of the interval (and of the KS p-value); seed: theirs.
    Returns a dict of `fit --json`'s fields: α dimensionless, x_min, A_s and the cut-off in
    pixels, the tests' normalised log-likelihood ratios R and p-values (docs/CONVENTIONS.md).
    """
    a = np.asarray(areas)
    if a.ndim != 1 or not (np.issubdtype(a.dtype, np.integer) or np.all(np.mod(a, 1) == 0)):
        raise ValueError("areas: a 1-D array of whole pixels")
    if np.any(a < 1):
        raise ValueError("areas: cluster areas are whole pixels ≥ 1")
    if not math.isfinite(float(resamples)):
        raise ValueError("resamples: a whole number")
    return json.loads(_wearcoef.fit([int(x) for x in a], resamples=int(resamples), seed=int(seed)))


def model(alpha, a_s, a_m, a_star):
    """K (eq. 5) and 𝒦 (eq. 7) of the plateau + power-law model of Appendix A, as
    `wearcoef model --json`: α, the plateau's end A_s, the cut-off A_m (math.inf for none)
    and A*, areas in any one unit. `a_star` may be an array. A dict {"K", "K_upscaled"}."""
    values = [_wearcoef.model(float(alpha), float(a_s), float(a_m), float(a))
              for a in np.atleast_1d(a_star)]
    k, kk = (np.array(v) for v in zip(*values))
    if np.ndim(a_star) == 0:
        return {"K": float(k[0]), "K_upscaled": float(kk[0])}
    return {"K": k, "K_upscaled": kk}


class Catalog(pd.DataFrame):
    """A store's catalog: one row per file and study (stage, study, realization, file, path,
    key…), as `{data}/{profile}/index.parquet` lists them. Select rows as in pandas; `load()`
    on one row reads its file: .npy as a numpy array (contact maps stay bit-packed, as
    stored), .parquet and .csv as a DataFrame, .json as a dict."""

    _metadata = ["root"]

    @property
    def _constructor(self):
        return Catalog

    def path(self):
        """The one selected file's path."""
        if len(self) != 1:
            raise ValueError(f"{len(self)} rows selected: narrow the selection to one file "
                             "(stage, study, realization, file)")
        return os.path.join(self.root, self["path"].iloc[0])

    def load(self):
        """The one selected file, read."""
        path = self.path()
        if path.endswith(".npy"):
            return np.load(path)
        if path.endswith(".parquet"):
            return pd.read_parquet(path)
        if path.endswith(".csv"):
            return pd.read_csv(path)
        if path.endswith(".json"):
            with open(path, encoding="utf-8") as f:
                return json.load(f)
        raise ValueError(f"{path}: not a table, an array or a record")


def open_store(data="data", profile="default"):
    """The catalog of the store `data` for `profile` (what `wearcoef run --profile P --data
    D` wrote) as a `Catalog`, one row per file and study."""
    index = os.path.join(data, profile, "index.parquet")
    if not os.path.isfile(index):
        raise FileNotFoundError(
            f"{index}: no catalog; run `wearcoef run --profile {profile} --data {data}` first")
    files = pd.read_parquet(index, dtype_backend="numpy_nullable")
    rows = files.assign(study=files.studies.str.split()).explode("study").reset_index(drop=True)
    catalog = Catalog(rows)
    catalog.root = data
    return catalog
