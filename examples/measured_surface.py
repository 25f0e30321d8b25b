"""From a measured topography file to the wear coefficients K(W) and 𝒦(W), with pandas and
matplotlib. Run it as it is to try it on a demonstration map, or give your own file:

    python examples/measured_surface.py [MAP.x3p] [--wearcoef PATH] [--out DIR]

Without a file it writes one: a 1000 × 750 map in µm (pixel 0.5 µm) with a tilt and 40
missing points, as SurfaceTopography (PyPI) writes X3P. Then one command, `wearcoef wear`,
prepares it (plane removed, missing points filled), presses it on an elastic half-space of
E* = 100 GPa at five loads, labels the contact clusters and writes K, 𝒦, the wear rate and
α̂ per load. This script reads that table and plots it (wear_coefficients.png)."""
import argparse
import json
import os
import subprocess

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402


def demonstration_map(path):
    """A self-affine surface (H = 0.8, wavelengths 100 µm to 4 µm, rms slope 0.2) in µm,
    tilted, with 40 missing points, written as X3P by SurfaceTopography."""
    from SurfaceTopography import Topography

    nx, ny, dx = 1000, 750, 0.5  # points along x and y; pixel size in µm
    rng = np.random.default_rng(1)
    q = np.hypot(np.fft.fftfreq(nx, dx)[:, None], np.fft.fftfreq(ny, dx)[None, :])
    amplitude = np.where((q >= 1 / 100) & (q <= 1 / 4), np.maximum(q, 1e-30) ** -1.8, 0)
    h = np.fft.ifft2(amplitude * np.exp(2j * np.pi * rng.random((nx, ny)))).real
    h *= 0.2 / np.sqrt(2 * np.mean((np.diff(h, axis=0) / dx) ** 2))
    x, y = np.meshgrid(np.arange(nx) * dx, np.arange(ny) * dx, indexing="ij")
    h += 0.01 * x + 0.005 * y  # the sample sits tilted in the instrument
    missing = np.zeros(h.shape, dtype=bool)
    missing.flat[rng.choice(h.size, 40, replace=False)] = True
    Topography(np.ma.masked_array(h, missing), (nx * dx, ny * dx), unit="µm",
               periodic=False).to_x3p(path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("map", nargs="?", help="a topography file (.x3p, .nc, ...)")
    parser.add_argument("--wearcoef", default="wearcoef", help="the wearcoef binary")
    parser.add_argument("--out", default="measured_surface", help="output directory")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    path = args.map
    if path is None:
        path = os.path.join(args.out, "demonstration.x3p")
        demonstration_map(path)
    results = os.path.join(args.out, "wear")
    subprocess.run(
        [args.wearcoef, "wear", "--input", path, "--form", "plane", "--fill", "harmonic",
         "--e-star", "100GPa", "--loads", "0.005,0.01,0.02,0.05,0.1", "--d-star", "5um",
         "-o", results],
        check=True)

    prep = json.load(open(os.path.join(results, "preparation.json")))
    print(f"{prep['rows']} × {prep['cols']} map, {prep['missing_points']} missing points "
          f"filled ({prep['fill']}), {prep['form_removed']} removed, "
          f"rms slope {prep['rms_slope']:.3f}")
    loads = pd.read_parquet(os.path.join(results, "loads.parquet"))
    print(loads[["force_n", "real_contact_area_um2", "n_clusters", "k_archard", "k_upscaled",
                 "wear_rate_mm3_per_m", "alpha"]].to_string(index=False))

    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.plot(loads["force_n"], loads["k_archard"], "o-", label="K (Archard, eq. 5)")
    ax.plot(loads["force_n"], loads["k_upscaled"], "s-", label=r"$\mathcal{K}$ (area fraction, eq. 7)")
    ax.set_xlabel("normal force W (N)")
    ax.set_ylabel("wear coefficient")
    ax.set_title(f"A* = {prep['contact']['a_star_um2']:.2f} µm²")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "wear_coefficients.png"), dpi=120)
    print(f"plot: {os.path.join(args.out, 'wear_coefficients.png')}")


if __name__ == "__main__":
    main()
