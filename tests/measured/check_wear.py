"""The output of examples/measured_surface.py (a 1000 × 750 X3P in µm with a tilt and 40
missing points, written by SurfaceTopography, through `wearcoef wear`) checked with pandas:
the preparation it states, and every number of the loads table recomputed from the cluster
table and the stated constants; the trust band recomputed (its edge and d* columns from the
cluster table, its halves by `wear` on numpy's cuts of the prepared map at the same
pressures). Usage: python check_wear.py EXAMPLE_OUT WEARCOEF_BIN"""
import json
import os
import sys

import numpy as np
import pandas as pd

out = os.path.join(sys.argv[1], "wear")
prep = json.load(open(os.path.join(out, "preparation.json")))
assert (prep["rows"], prep["cols"]) == (750, 1000), prep
assert prep["format"] == "x3p" and prep["height_unit_from"] == "the file"
assert prep["pixel_size_x_m"] == prep["pixel_size_y_m"] and abs(prep["pixel_size_x_m"] / 0.5e-6 - 1) < 1e-12
assert prep["missing_points"] == 40 and prep["filled_points"] == 40 and prep["fill"] == "harmonic"
# The tilt written (0.01 along x, 0.005 along y) is what the plane removal found, to the
# slope the random surface itself has over the map (rms slope 0.2 over 500 µm: ~1e-3).
_, bx, by = prep["form_coefficients_m"]
assert abs(bx - 0.01) < 1e-3 and abs(by - 0.005) < 1e-3, (bx, by)
# The PSD's self-affine fit against the spectrum the example generated (H = 0.8, λ_l = 100
# µm, λ_s = 4 µm; bins of a tenth of a decade, the Hann window blurring the lowest ones).
fit = prep["psd_fit"]
assert abs(fit["hurst"] - 0.8) < 0.1, fit
assert 50e-6 < fit["lambda_l_m"] < 150e-6 and 3e-6 < fit["lambda_s_m"] < 6e-6, fit
psd = pd.read_parquet(os.path.join(out, "psd.parquet"))
assert (psd["c_m4"] > 0).all() and psd["q_low_per_m"].is_monotonic_increasing
c = prep["contact"]
loads = pd.read_parquet(os.path.join(out, "loads.parquet"))
clusters = pd.read_parquet(os.path.join(out, "clusters.parquet"))
assert list(loads["w_over_w0"]) == [0.005, 0.01, 0.02, 0.05, 0.1]
csv = pd.read_csv(os.path.join(out, "loads.csv"))
assert np.allclose(csv["k_upscaled"], loads["k_upscaled"], rtol=1e-15)
pixel_um2 = prep["pixel_size_x_m"] * prep["pixel_size_y_m"] * 1e12
for i, row in loads.iterrows():
    a = clusters[clusters["load_index"] == i]
    assert np.allclose(a["area_um2"], a["area_px"] * pixel_um2)
    above = a[a["area_px"] > c["a_star_px"]]
    assert row["n_clusters"] == len(a)
    assert np.isclose(row["real_contact_area_um2"], a["area_um2"].sum(), rtol=1e-12)
    assert np.isclose(row["k_archard"], len(above) / len(a), rtol=1e-12)
    assert np.isclose(row["k_upscaled"], above["area_px"].sum() / a["area_px"].sum(), rtol=1e-12)
    # eq. 6: ω Σ_{A > A*} A with ω = 1/3; 1 µm² = 1e-12 m³/m = 1e-3 mm³/m
    assert np.isclose(row["wear_rate_mm3_per_m"], above["area_um2"].sum() / 3 * 1e-3, rtol=1e-12)
    assert np.isclose(row["force_n"], row["w_over_w0"] * c["w0_n"], rtol=1e-12)
    assert np.isclose(row["mean_pressure_pa"] * c["map_area_um2"] * 1e-12, row["force_n"], rtol=1e-12)
    assert row["n_clusters_touching_edge"] == a["touches_edge"].sum()
    assert row["solver_error"] <= c["tolerance"]
    assert row["alpha_ci95_low"] <= row["alpha"] <= row["alpha_ci95_high"]
# The trust band. Edge and d*: from the cluster table.
lo, hi = prep["trust_band"]["d_star_factors"]
assert (lo, hi) == (0.5, 2.0) and prep["trust_band"]["notes"] == [], prep["trust_band"]
for i, row in loads.iterrows():
    a = clusters[clusters["load_index"] == i]
    inner = a[~a["touches_edge"]]
    for name, areas, a_star in [("no_edge", inner["area_px"], c["a_star_px"]),
                                ("d_star_low", a["area_px"], c["a_star_px"] * lo**2),
                                ("d_star_high", a["area_px"], c["a_star_px"] * hi**2)]:
        assert np.isclose(row[f"k_archard_{name}"], (areas > a_star).mean(), rtol=1e-12), name
        assert np.isclose(row[f"k_upscaled_{name}"], areas[areas > a_star].sum() / areas.sum(),
                          rtol=1e-12), name
    for kind in ["k_archard", "k_upscaled"]:
        variants = [row[kind]] + [row[f"{kind}_{v}"] for v in [
            "no_edge", "d_star_low", "d_star_high", "pixel_x2", "halves_min", "halves_max",
            "quarters_min", "quarters_max"]]
        assert row[f"{kind}_band_low"] == min(variants) and row[f"{kind}_band_high"] == max(variants)
        assert row[f"{kind}_halves_min"] <= row[f"{kind}_halves_max"]
# Halves: the prepared map cut by numpy across its longer side, each solved alone by `wear`
# with the same mean pressures given in Pa: their smallest and largest K are the band's.
import subprocess
import tempfile
BIN = sys.argv[2]
with tempfile.TemporaryDirectory() as tmp:
    prepared = os.path.join(tmp, "prepared.npy")
    subprocess.run([BIN, "topography", "--input", os.path.join(sys.argv[1], "demonstration.x3p"),
                    "--form", "plane", "--fill", "harmonic", "-o", prepared],
                   check=True, capture_output=True)
    h = np.load(prepared)
    half = h.shape[1] // 2
    pressures = ",".join(f"{p!r}Pa" for p in loads["mean_pressure_pa"])
    ks = []
    for j, cut in enumerate([h[:, :half], h[:, half:2 * half]]):
        np.save(os.path.join(tmp, f"half{j}.npy"), np.ascontiguousarray(cut))
        run = subprocess.run(
            [BIN, "wear", "--input", os.path.join(tmp, f"half{j}.npy"), "--height-unit", "m",
             "--pixel-size", repr(prep["pixel_size_x_m"]), "--form", "none",
             "--fill", "none", "--e-star", "100GPa", "--loads", pressures, "--d-star", "5um",
             "--no-trust-band", "-o", os.path.join(tmp, f"half{j}")],
            capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        ks.append(pd.read_parquet(os.path.join(tmp, f"half{j}", "loads.parquet")))
    for kind in ["k_archard", "k_upscaled"]:
        both = np.array([k[kind] for k in ks])
        assert np.allclose(both.min(axis=0), loads[f"{kind}_halves_min"], rtol=1e-12), kind
        assert np.allclose(both.max(axis=0), loads[f"{kind}_halves_max"], rtol=1e-12), kind
print(f"trust band: K from {loads['k_archard_band_low'].min():.3f} to "
      f"{loads['k_archard_band_high'].max():.3f} over the loads; edge, d* and halves recomputed")
# The page: index.html shows wear.png (which decodes) and every load's row.
from PIL import Image
html = open(os.path.join(out, "index.html"), encoding="utf-8").read()
assert 'src="wear.png"' in html and html.count("<tr>") == len(loads) + 1
with Image.open(os.path.join(out, "wear.png")) as im:
    im.load()
    assert im.size[0] > 1000, im.size
print(f"PSD fit: H = {fit['hurst']:.3f}, λ_l = {fit['lambda_l_m'] * 1e6:.1f} µm, "
      f"λ_s = {fit['lambda_s_m'] * 1e6:.2f} µm (generated 0.8, 100 µm, 4 µm)")
print(f"wear: {len(loads)} loads, every K, 𝒦, wear rate and force recomputed from "
      f"{len(clusters)} clusters; preparation as stated (tilt {bx:.4f}, {by:.4f})")
