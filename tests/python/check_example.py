"""The Python example's numbers against the command line on the same file: its k_of_w.csv
(force, clusters, K and its band) equals `wearcoef wear`'s loads table, and its figure is
written.

Usage: check_example.py EXAMPLE_OUT_DIR WEARCOEF_BIN
"""

import os
import subprocess
import sys
import tempfile

import numpy as np
import pandas as pd

OUT, BIN = sys.argv[1], sys.argv[2]
REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
X3P = os.path.join(REPO, "tests", "measured", "instrument", "x3p-2.x3p")

mine = pd.read_csv(os.path.join(OUT, "k_of_w.csv"), engine="python")
assert os.path.getsize(os.path.join(OUT, "k_of_w.png")) > 10_000, "the figure is missing"
with tempfile.TemporaryDirectory() as work:
    out = os.path.join(work, "wear")
    done = subprocess.run([BIN, "wear", "--input", X3P, "--e-star", "100GPa", "--loads",
                           "0.5N,1N,2N,5N,10N", "--d-star", "1um", "--fill", "harmonic", "-o", out],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    theirs = pd.read_csv(os.path.join(out, "loads.csv"), engine="python")
for c in mine.columns:
    # Both CSVs hold each float in shortest round-trip form, read back exactly by the python
    # engine (correctly rounded): equal values, not close.
    assert np.array_equal(mine[c].to_numpy(), theirs[c].to_numpy()), f"{c}: {mine[c].tolist()} against {theirs[c].tolist()}"
band = (mine["k_archard_band_low"] <= mine["k_archard"]) & (mine["k_archard"] <= mine["k_archard_band_high"])
assert band.all(), mine
print(f"example: K(W) at {len(mine)} forces equal to wearcoef wear's loads.csv; "
      f"K = {', '.join(f'{k:.3f}' for k in mine['k_archard'])} on "
      f"{', '.join(str(n) for n in mine['n_clusters'])} clusters")
