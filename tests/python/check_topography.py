"""The Python package on SurfaceTopography topographies read from real instrument files:
`wear` gives the command line's numbers, bit for bit, on the same file; and a format the
command line does not read (Digital Surf .sur) reaches K(W) in three lines.

Usage: check_topography.py WEARCOEF_BIN WORK_DIR
"""

import json
import os
import subprocess
import sys

import numpy as np
import pandas as pd
import SurfaceTopography as st

import common
import wearcoef
from common import same_frame

BIN, WORK = sys.argv[1], sys.argv[2]
REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
INSTRUMENT = os.path.join(REPO, "tests", "measured", "instrument")
os.makedirs(WORK, exist_ok=True)


def run(*args):
    return common.run(BIN, *args)


def against_the_file(name, loads, d_star_m, trust_band):
    """wear(SurfaceTopography's topography) against `wearcoef wear --input FILE`."""
    path = os.path.join(INSTRUMENT, name)
    topography = st.read_topography(path)
    mine = wearcoef.wear(topography, e_star="100GPa", loads=loads, d_star=d_star_m,
                         trust_band=trust_band, resamples=40, progress=False)
    out = os.path.join(WORK, name)
    run("wear", "--input", path, "--e-star", "100GPa", "--loads", ",".join(loads),
        "--d-star", f"{d_star_m!r}m", "--resamples", "40", "-o", out,
        *([] if trust_band else ["--no-trust-band"]))
    for table in ["loads", "clusters", "psd"]:
        same_frame(getattr(mine, table), pd.read_parquet(os.path.join(out, f"{table}.parquet")),
                   f"{name} {table}")
    k = ", ".join(f"{v:.3f}" for v in mine.loads["k_archard"])
    print(f"{name} ({topography.nb_grid_pts[0]} × {topography.nb_grid_pts[1]}, "
          f"{topography.unit}): K = {k} with {mine.loads['n_clusters'].tolist()} clusters, "
          f"equal to wearcoef wear's on the file bit for bit")


def a_format_only_surfacetopography_reads():
    """Digital Surf .sur: refused by the command line, K(W) in three lines of Python; the
    same numbers as the command line on the heights SurfaceTopography read (as .npy)."""
    path = os.path.join(INSTRUMENT, "sur-2.sur")
    refused = subprocess.run([BIN, "topography", "--input", path], capture_output=True, text=True)
    assert refused.returncode == 2 and "Digital Surf" in refused.stderr, refused.stderr
    # The three lines a user writes:
    t = st.read_topography(path)
    run_ = wearcoef.wear(t, e_star="100GPa", loads=[0.05, 0.1, 0.2], d_star="20um", fill="harmonic")
    print(run_.loads[["w_over_w0", "force_n", "k_archard", "k_archard_band_low", "k_archard_band_high"]])
    loads = run_.loads
    assert len(loads) == 3 and loads["n_clusters"].min() >= 10, loads["n_clusters"]
    assert ((loads["k_archard_band_low"] <= loads["k_archard"])
            & (loads["k_archard"] <= loads["k_archard_band_high"])).all()
    assert run_.preparation["filled_points"] == 117, run_.preparation["filled_points"]
    # The command line on the same heights, in metres, as a .npy.
    heights = np.ma.filled(np.ma.asarray(t.heights(), dtype=float), np.nan).T * 1e-3
    npy = os.path.join(WORK, "sur-2.npy")
    np.save(npy, heights)
    dx, dy = (float(s) / n * 1e-3 for s, n in zip(t.physical_sizes, t.nb_grid_pts))
    out = os.path.join(WORK, "sur-2")
    run("wear", "--input", npy, "--height-unit", "m", "--pixel-size", repr(dx),
        "--pixel-size-y", repr(dy), "--pixel-unit", "m", "--fill", "harmonic",
        "--e-star", "100GPa", "--loads", "0.05,0.1,0.2", "--d-star", "20um", "-o", out)
    for table in ["loads", "clusters", "psd"]:
        same_frame(getattr(run_, table), pd.read_parquet(os.path.join(out, f"{table}.parquet")),
                   f"sur-2 {table}")
    print("sur-2.sur: refused by the command line; K(W) in three lines of Python, equal to the "
          "command line's on the same heights bit for bit")


against_the_file("x3p-2.x3p", ["1N", "5N"], 1e-6, trust_band=True)
against_the_file("matrix-3.txt", ["0.05", "0.2"], 2e-7, trust_band=False)
a_format_only_surfacetopography_reads()
