"""K(W) of a real instrument file from Python: SurfaceTopography reads it, wearcoef presses it
on an elastic half-space, matplotlib draws K against the force with its trust band.

    pip install SurfaceTopography matplotlib ./crates/python
    python examples/python_wear.py [MAP] [--out DIR]

Without a file it takes the confocal map tests/measured/instrument/x3p-2.x3p (650 × 650
pixels of 0.128 × 0.315 µm). It writes k_of_w.png and k_of_w.csv (force, K and its band)
into --out."""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import SurfaceTopography as st  # noqa: E402

import wearcoef  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT = os.path.join(HERE, "..", "tests", "measured", "instrument", "x3p-2.x3p")

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("map", nargs="?", default=DEFAULT, help="a topography file SurfaceTopography reads")
parser.add_argument("--out", default="python_wear", help="output directory")
args = parser.parse_args()
os.makedirs(args.out, exist_ok=True)

# Read with SurfaceTopography (its unit and pixel sizes come along), then wear: E* of a
# steel pair, forces in newtons, junctions of diameter d* = 1 µm.
topography = st.read_topography(args.map)
run = wearcoef.wear(topography, e_star="100GPa", loads=["0.5N", "1N", "2N", "5N", "10N"],
                    d_star="1um", fill="harmonic")

table = run.loads[["force_n", "n_clusters", "k_archard", "k_archard_band_low",
                   "k_archard_band_high"]]
table.to_csv(os.path.join(args.out, "k_of_w.csv"), index=False)
print(table.to_string(index=False))

fig, ax = plt.subplots(figsize=(5, 3.5))
ax.fill_between(table["force_n"], table["k_archard_band_low"], table["k_archard_band_high"],
                alpha=0.25, label="trust band (edge, d* ×½ and ×2, pixel ×2, halves, quarters)")
ax.plot(table["force_n"], table["k_archard"], "o-", label="K (eq. 5)")
ax.set_xscale("log")
ax.set_ylim(0, 1)
ax.set_xlabel("normal force W (N)")
ax.set_ylabel("K = P(A > A*)")
ax.set_title(os.path.basename(args.map), fontsize=9)
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(os.path.join(args.out, "k_of_w.png"), dpi=150)
print(f"written: {args.out}/k_of_w.png, {args.out}/k_of_w.csv")
