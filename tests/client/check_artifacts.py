"""Real-client check of a wearcoef data directory: open every artifact the way a user would
(pandas with pyarrow, numpy, Pillow) and check column names, dtypes, row counts, array
shapes and the cross-stage relations documented in docs/CONVENTIONS.md.

Usage: python check_artifacts.py <data dir> <profile>
Exit status 0 when every check passes; otherwise each failure is printed and the status is 1.
"""

import json
import os
import re
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
from PIL import Image

U32, U64, F64, BOOL, STR = "uint32", "uint64", "double", "bool", "string"

# (stage, file) -> [(column, arrow type)] as documented in docs/CONVENTIONS.md.
SCHEMAS = {
    ("contact", "loads.parquet"): [
        ("realization", U32), ("load_index", U32), ("w_over_w0", F64), ("mean_pressure", F64),
        ("area_fraction", F64), ("n_contact_px", U64), ("iterations", U32),
        ("convolutions", U32), ("error", F64), ("converged", BOOL)],
    ("clusters", "clusters.parquet"): [
        ("realization", U32), ("load_index", U32), ("w_over_w0", F64), ("cluster_id", U32),
        ("area_px", U64), ("area_over_ls2", F64), ("perimeter_px", U64),
        ("extent_x_px", U32), ("extent_y_px", U32), ("percolating", BOOL)],
    ("clusters", "loads.parquet"): [
        ("realization", U32), ("load_index", U32), ("w_over_w0", F64), ("n_clusters", U32), ("area_fraction", F64),
        ("largest_area_over_ls2", F64), ("n_percolating", U32)],
    ("statistics", "loads.parquet"): [
        ("load_index", U32), ("w_over_w0", F64),
        ("area_fraction_mean", F64), ("area_fraction_ci95", F64), ("area_fraction_ci95_low", F64), ("area_fraction_ci95_high", F64),
        ("n_clusters_mean", F64), ("n_clusters_ci95", F64), ("n_clusters_ci95_low", F64), ("n_clusters_ci95_high", F64),
        ("largest_area_over_ls2_mean", F64), ("largest_area_over_ls2_ci95", F64), ("largest_area_over_ls2_ci95_low", F64), ("largest_area_over_ls2_ci95_high", F64),
        ("dn_dac_per_ls2_mean", F64), ("dn_dac_per_ls2_ci95", F64), ("dn_dac_per_ls2_ci95_low", F64), ("dn_dac_per_ls2_ci95_high", F64),
        ("realizations", U32), ("realizations_percolating", U32), ("ci95_method", STR)],
    ("statistics", "pdf.parquet"): [
        ("load_index", U32), ("w_over_w0", F64), ("bin", U32), ("lower_over_ls2", F64),
        ("upper_over_ls2", F64), ("centre_over_ls2", F64), ("width_px", U64),
        ("count_pooled", U64), ("pdf_pooled", F64), ("pdf_mean", F64), ("pdf_ci95", F64), ("pdf_ci95_low", F64), ("pdf_ci95_high", F64)],
    ("statistics", "ccdf.parquet"): [
        ("load_index", U32), ("w_over_w0", F64), ("realization", U32), ("area_px", U64),
        ("area_over_ls2", F64), ("ccdf", F64), ("ccdf_mean", F64), ("ccdf_ci95", F64), ("ccdf_ci95_low", F64), ("ccdf_ci95_high", F64)],
    ("statistics", "wear.parquet"): [
        ("load_index", U32), ("w_over_w0", F64), ("a_star_over_ls2", F64),
        ("k_archard_pooled", F64), ("k_archard_pooled_ci95_low", F64),
        ("k_archard_pooled_ci95_high", F64),
        ("k_archard_mean", F64), ("k_archard_ci95", F64), ("k_archard_ci95_low", F64), ("k_archard_ci95_high", F64),
        ("k_upscaled_pooled", F64), ("k_upscaled_pooled_ci95_low", F64),
        ("k_upscaled_pooled_ci95_high", F64),
        ("k_upscaled_mean", F64), ("k_upscaled_ci95", F64), ("k_upscaled_ci95_low", F64), ("k_upscaled_ci95_high", F64),
        ("wear_rate_over_l2_mean", F64), ("wear_rate_over_l2_ci95", F64), ("wear_rate_over_l2_ci95_low", F64), ("wear_rate_over_l2_ci95_high", F64),
        ("clusters_above", U64), ("clusters_above_smallest_realization", U64),
        ("realizations", U32), ("ci95_method", STR)],
    ("statistics", "alpha.parquet"): [
        ("load_index", U32), ("w_over_w0", F64), ("estimator", STR), ("alpha", F64),
        ("std_error", F64), ("ci95_low", F64), ("ci95_high", F64), ("ci95_method", STR),
        ("k_min_px", F64), ("k_max_px", F64), ("k_s_px", F64), ("k_s_over_ls2", F64),
        ("n_fitted", U64), ("ks_distance", F64), ("gof_p", F64), ("alpha_above_k_min", F64),
        ("clusters", U64), ("realizations", U32), ("tail_verdict", STR), ("note", STR)]
    + [(f"lr_{alt}_{what}", F64)
       for alt in ["exponential_cutoff", "lognormal", "exponential", "stretched_exponential"]
       for what in ["normalised_ratio", "p"]],
    ("analytic", "model.parquet"): [
        ("load_index", U32), ("w_over_w0", F64), ("a_star_over_ls2", F64), ("alpha", F64),
        ("a_s_over_ls2", F64), ("a_m_over_ls2", F64), ("k_pl", F64), ("k_upscaled_pl", F64)],
    ("analytic", "plateau.parquet"): [
        ("a_star_over_ls2", F64), ("w_over_w0", F64), ("alpha", F64), ("k_pl_plateau", F64),
        ("k_pl_at_load", F64), ("k_archard_mean", F64), ("k_archard_ci95", F64)],
    ("analytic", "fig6.parquet"): [
        ("alpha", F64), ("a_star_over_a_s", F64), ("a_m_over_a_s", F64), ("k_pl", F64),
        ("k_upscaled_pl", F64)],
}
CONVERGENCE = [
    ("kind", STR), ("study", STR), ("setting", F64), ("realizations", U32), ("load_index", U32),
    ("w_over_w0", F64), ("n_clusters", U64), ("n_clusters_reference", U64),
    ("ks_distance", F64), ("ks_critical_95", F64), ("alpha", F64), ("alpha_reference", F64),
    ("alpha_difference", F64), ("alpha_estimator", STR)]
PLASTIC_ALPHA = [
    ("study", STR), ("inverse_hardness", F64), ("w_over_w0", F64), ("w_over_w0_solved", F64),
    ("estimator", STR), ("alpha", F64), ("ci95_low", F64), ("ci95_high", F64),
    ("k_max_over_ls2", F64), ("n_fitted", U64)]
# The spectrum family's fits (the same, against λ_l/λ_s) and its sign changes of dN/dA_c.
SPECTRUM_ALPHA = [(("lambda_l_over_lambda_s" if c == "inverse_hardness" else c), t)
                  for c, t in PLASTIC_ALPHA]
SPECTRUM_TRANSITION = [
    ("study", STR), ("lambda_l_over_lambda_s", F64), ("w_over_w0_sign_change", F64),
    ("w_over_w0_lowest", F64), ("w_over_w0_highest", F64)]
FIG2_CONVERGENCE = [("realizations", U32)] + [
    (f"{q}_{m}", F64) for m in ["max_rel_deviation", "max_rel_ci95"]
    for q in ["area", "count", "largest"]] + [
    ("count_peak_load_index", U32), ("count_peak_w_over_w0", F64)]
# Two-sided 95 % Student t quantiles for 1 … 10 degrees of freedom.
T975 = [12.706204736, 4.302652730, 3.182446305, 2.776445105, 2.570581836, 2.446911851,
        2.364624252, 2.306004135, 2.262157163, 2.228138852]
CATALOG_COLUMNS = [("profile", STR), ("stage", STR), ("studies", STR), ("realization", U32),
                   ("name", STR), ("state", STR), ("file", STR), ("path", STR), ("key", STR), ("bytes", U64)]
# Key-value metadata of every stored table (`pyarrow.parquet.read_schema(p).metadata`).
TABLE_METADATA = ["wearcoef.stage", "wearcoef.key", "wearcoef.params", "wearcoef.units",
                  "wearcoef.program"]
CATALOG_METADATA = ["wearcoef.profile", "wearcoef.store_root", "wearcoef.units",
                    "wearcoef.program"]


def check_metadata(path, keys, stage=None, key=None):
    """The table's schema metadata names what it is and a unit for every column."""
    meta = {k.decode(): v.decode() for k, v in (pq.read_schema(path).metadata or {}).items()}
    missing = [k for k in keys if k not in meta]
    if not check(not missing, f"{path}: metadata lacks {missing}"):
        return meta
    units = json.loads(meta["wearcoef.units"])
    names = pq.read_schema(path).names
    check(sorted(units) == sorted(names), f"{path}: units for {sorted(units)}, columns {names}")
    check(all(units.get(c) for c in names),
          f"{path}: columns without a unit {[c for c in names if not units.get(c)]}")
    if stage is not None:
        check(meta["wearcoef.stage"] == stage and meta["wearcoef.key"] == key,
              f"{path}: metadata names {meta['wearcoef.stage']}/{meta['wearcoef.key']}")
        json.loads(meta["wearcoef.params"])
    return meta
A_STAR_GRID = 13  # thresholds A*/λ_s² = 1/4 … 1024
ESTIMATORS = 2
FIG6_ROWS = 5 * (121 + 1)

failures = []


# Columns of a figure's data file (src/figures/plot/mod.rs, DATA_COLUMNS).
DATA_COLUMNS = ["panel", "series", "study", "w_over_w0", "a_star_over_ls2",
                "x_quantity", "x", "y_quantity", "y", "y_ci95_low", "y_ci95_high", "hollow"]


def check(cond, message):
    if not cond:
        failures.append(message)
    return cond


def arrow_type(t):
    s = str(t)
    return "string" if s in ("string", "large_string", "string_view") else s


def check_schema(path, expected):
    schema = pq.read_schema(path)
    got = [(f.name, arrow_type(f.type)) for f in schema]
    check(got == expected, f"{path}: columns/types {got} != documented {expected}")


def manifest_of(path):
    with open(os.path.join(os.path.dirname(path), "manifest.json")) as f:
        return json.load(f)


def unpacked_count(packed, n):
    bits = np.unpackbits(packed, axis=1)[:, :n]
    return int(bits.sum())


def check_fig2_convergence(path, clusters_rows):
    """Recompute the Fig. 2 realization-convergence table from the fig2 study's clusters
    tables (docs/CONVENTIONS.md, "Fig. 2 convergence") and compare."""
    per_real = []
    for _, c in clusters_rows.sort_values("realization").iterrows():
        df = pd.read_parquet(c.path)
        g = df.groupby("load_index")["area_over_ls2"]
        per_real.append(pd.DataFrame({"area": g.sum(), "count": g.size(), "largest": g.max()}))
    loads = sorted(set().union(*[set(p.index) for p in per_real]))
    cube = np.array([p.reindex(loads, fill_value=0).to_numpy(float) for p in per_real])
    total = len(per_real)
    table = pd.read_parquet(path)
    check(list(table["realizations"]) == list(range(2, total + 1)),
          f"{path}: realizations {list(table['realizations'])}, expected 2..{total}")
    full = cube.mean(axis=0)
    for _, row in table.iterrows():
        r = int(row["realizations"])
        first = cube[:r]
        mean = first.mean(axis=0)
        half = T975[r - 2] * first.std(axis=0, ddof=1) / np.sqrt(r)
        for q, name in enumerate(["area", "count", "largest"]):
            ok = full[:, q] > 0
            dev = np.max(np.abs(mean[ok, q] - full[ok, q]) / full[ok, q], initial=0.0)
            pos = mean[:, q] > 0
            band = np.max(half[pos, q] / mean[pos, q], initial=0.0)
            check(np.isclose(row[f"{name}_max_rel_deviation"], dev, rtol=1e-9, atol=1e-15),
                  f"{path}: r={r} {name} deviation {row[f'{name}_max_rel_deviation']} != {dev}")
            # The stage's Student t table has 4 decimals.
            check(np.isclose(row[f"{name}_max_rel_ci95"], band, rtol=1e-4),
                  f"{path}: r={r} {name} band {row[f'{name}_max_rel_ci95']} != {band}")
        check(int(row["count_peak_load_index"]) == loads[int(np.argmax(mean[:, 1]))],
              f"{path}: r={r} peak at {row['count_peak_load_index']}")


def ks_two_sample(a, b):
    """Largest distance between the two empirical CDFs (right-continuous)."""
    a, b = np.sort(a), np.sort(b)
    x = np.concatenate([a, b])
    return float(np.max(np.abs(np.searchsorted(a, x, side="right") / len(a)
                               - np.searchsorted(b, x, side="right") / len(b)), initial=0.0))


def check_convergence_ks(path, clusters_rows):
    """Recompute each setting's KS distance to the reference from the studies' clusters
    tables (areas A/λ_s² pooled over realizations, percolating clusters left out). The table
    names settings by label, so the pair of studies is found by the cluster counts it
    states; some pair with those counts must give the stated distance."""
    pooled = {}
    for _, c in clusters_rows.iterrows():
        df = pd.read_parquet(c.path)
        df = df[~df["percolating"]]
        for w, g in df.groupby("w_over_w0"):
            pooled.setdefault(c.study, {}).setdefault(w, []).append(g["area_over_ls2"].to_numpy())
    samples = {s: {w: np.concatenate(v) for w, v in by_w.items()} for s, by_w in pooled.items()}
    table = pd.read_parquet(path)
    checked = 0
    for _, row in table[table["kind"] == "setting"].iterrows():
        w = row["w_over_w0"]
        at = [v[w] for v in samples.values() if w in v]
        cands = [a for a in at if len(a) == row["n_clusters"]]
        refs = [a for a in at if len(a) == row["n_clusters_reference"]]
        ks = [ks_two_sample(a, b) for a in cands for b in refs]
        if check(ks, f"{path}: no studies with {row['n_clusters']} and "
                     f"{row['n_clusters_reference']} clusters at W/W0 = {w}"):
            check(min(abs(k - row["ks_distance"]) for k in ks) <= 1e-12,
                  f"{path}: {row['study']} at W/W0 = {w}: KS {row['ks_distance']}, "
                  f"recomputed {ks}")
            checked += 1
    check(checked > 0, f"{path}: no setting row checked")


def check_fig128_summary(path, table, summary):
    """The manifest's per-setting summary of a λ_l/λ_s = 128 convergence figure agrees with
    its table: the loads with KS ≤ the tolerance, and KS below the 95 % critical value at
    every load."""
    tol = summary["tolerance"]
    for s in summary["settings"]:
        rows = table[(table["kind"] == "setting") & (table["study"] == s["setting"])]
        if not check(len(rows) > 0, f"{path}: no rows for {s['setting']}"):
            continue
        within = sorted(rows.loc[rows["ks_distance"] <= tol, "w_over_w0"])
        check(sorted(s["loads_within_tolerance"]) == within,
              f"{path}: {s['setting']}: loads within {tol}: manifest "
              f"{s['loads_within_tolerance']}, table {within}")
        below = bool((rows["ks_distance"] <= rows["ks_critical_95"]).all())
        check(s["below_critical_at_every_load"] == below,
              f"{path}: {s['setting']}: below the critical value at every load: manifest "
              f"{s['below_critical_at_every_load']}, table {below}")


LOAD_RESOLUTION = [
    ("curve", STR), ("a_star_over_ls2", F64), ("w_over_w0", F64), ("value", F64),
    ("ci95", F64), ("interpolated", F64), ("error_over_ci95", F64), ("at_transition", BOOL),
    ("neighbours", F64), ("neighbour_error_over_ci95", F64), ("within_rule", BOOL)]
# curve name in the table -> (value column, band column) of the statistics wear table.
LOAD_RESOLUTION_CURVES = {
    "k_archard": ("k_archard_pooled", "k_archard_ci95"),
    "k_upscaled": ("k_upscaled_pooled", "k_upscaled_ci95"),
    "wear_rate_over_l2": ("wear_rate_over_l2_mean", "wear_rate_over_l2_ci95"),
}


def check_load_resolution(path, wear_of):
    """Recompute the load-resolution table of Figs. 4b and 5 independently (numpy.interp in
    ln W/W0 of the chosen sweep's curves at the finer sweep's loads) from the two studies'
    wear tables, and the manifest's rule from the table."""
    m = manifest_of(path)
    fine, chosen = wear_of(0), wear_of(1)
    if not check(fine is not None and chosen is not None, f"{path}: wear tables not found"):
        return
    table = pd.read_parquet(path)
    check(len(table) > 0, f"{path}: empty")
    for curve, (col, band) in LOAD_RESOLUTION_CURVES.items():
        for a_star, rows in table[table["curve"] == curve].groupby("a_star_over_ls2"):
            c = chosen[chosen["a_star_over_ls2"] == a_star].sort_values("w_over_w0")
            f = fine[fine["a_star_over_ls2"] == a_star].set_index("w_over_w0")
            x, y = np.log(c["w_over_w0"].values), c[col].values
            interp = np.interp(np.log(rows["w_over_w0"].values), x, y)
            check(np.allclose(interp, rows["interpolated"].values, rtol=1e-9, atol=1e-15),
                  f"{path}: {curve} A* = {a_star}: interpolation differs from numpy's")
            # The finer sweep's own neighbours, where both exist and are not one zero.
            fw, fy = f.index.values, f[col].values
            for w, got in zip(rows["w_over_w0"], rows["neighbours"]):
                i = int(np.searchsorted(fw, w))
                if 0 < i < len(fw) - 1 and (fy[i - 1] == 0) == (fy[i + 1] == 0):
                    want = np.interp(np.log(w), np.log(fw[[i - 1, i + 1]]), fy[[i - 1, i + 1]])
                    check(np.isclose(got, want, rtol=1e-9, atol=1e-15),
                          f"{path}: {curve} A* = {a_star} W = {w}: neighbours {got} != {want}")
                else:
                    check(np.isnan(got), f"{path}: {curve} A* = {a_star} W = {w}: "
                                         f"neighbours {got}, expected NaN")
            check(np.array_equal(f.loc[rows["w_over_w0"], col].values, rows["value"].values)
                  and np.array_equal(f.loc[rows["w_over_w0"], band].values, rows["ci95"].values,
                                     equal_nan=True),
                  f"{path}: {curve} A* = {a_star}: values or bands are not the finer sweep's")
    err = (table["interpolated"] - table["value"]).abs()
    ratio = np.where(err == 0, 0.0, err / table["ci95"])
    check(np.allclose(ratio, table["error_over_ci95"], equal_nan=True),
          f"{path}: error_over_ci95 is not |interpolated - value| / ci95")
    judged = ~table["at_transition"]
    result = m["results"]["load_resolution"]
    within = judged & (table["error_over_ci95"] <= result["tolerance_error_over_ci95"])
    check((within == table["within_rule"]).all(), f"{path}: within_rule disagrees with the table")
    check(len(result["points_beyond_band"]) == int((judged & ~within).sum()),
          f"{path}: points beyond the band disagree with the table")
    met = bool(within[judged].all())
    check(result["rule_met"] == met, f"{path}: rule_met {result['rule_met']}, table says {met}")
    check(result["points_at_transition"] == int(table["at_transition"].sum()),
          f"{path}: points at a transition disagree with the table")


def main(data_dir, profile):
    catalog_path = os.path.join(data_dir, profile, "index.parquet")
    schema = pq.read_schema(catalog_path)
    got = [(f.name, arrow_type(f.type)) for f in schema]
    check(got == CATALOG_COLUMNS, f"catalog columns {got} != {CATALOG_COLUMNS}")
    meta = check_metadata(catalog_path, CATALOG_METADATA)
    check(meta.get("wearcoef.profile") == profile, f"catalog profile {meta.get('wearcoef.profile')}")
    check(os.path.samefile(meta.get("wearcoef.store_root", "/nonexistent"), data_dir),
          f"catalog store root {meta.get('wearcoef.store_root')} is not {data_dir}")
    files = pd.read_parquet(catalog_path, dtype_backend="numpy_nullable")
    check(len(files) > 0, "catalog is empty")
    check(str(files["realization"].dtype) == "UInt32", f"realization as {files['realization'].dtype}")
    check(not files.duplicated(["key", "file"]).any(), "a file is listed twice in the catalog")
    check((files["profile"] == profile).all(), "a catalog row of another profile")
    check((files["state"] == "stored").all(), "a failed instance in the quick profile")
    # Paths are relative to the store root: they open from any directory.
    for p in files["path"]:
        check(not os.path.isabs(p) and os.path.isfile(os.path.join(data_dir, p)),
              f"catalog path {p} is not a file under {data_dir}")
    # Per-stage tables: one row per instance, the study's spectrum as ratios, no empty column.
    for stage in ["surface", "contact", "clusters", "statistics", "analytic", "audits", "figures"]:
        sp = os.path.join(data_dir, profile, f"index_{stage}.parquet")
        if not check(os.path.isfile(sp), f"no per-stage catalog {sp}"):
            continue
        check_metadata(sp, CATALOG_METADATA)
        st = pd.read_parquet(sp, dtype_backend="numpy_nullable")
        check(sorted(st["key"]) == sorted(set(files[files["stage"] == stage]["key"])),
              f"{sp}: instances differ from index.parquet's")
        empty = [c for c in st.columns if st[c].isna().all()]
        check(not empty, f"{sp}: columns null in every row {empty}")
        if stage in ("surface", "contact", "clusters", "statistics"):
            for c in ["l_over_lambda_l", "lambda_l_over_lambda_s", "lambda_s_over_dl", "hurst"]:
                check(c in st.columns and st[c].notna().all(), f"{sp}: no {c} on every row")
        if stage == "surface":
            check(((st["l_over_lambda_l"] * st["lambda_l_over_lambda_s"]
                    * st["lambda_s_over_dl"]) == st["n"]).all(),
                  f"{sp}: L/λl · λl/λs · λs/Δl differs from n")
    surface_n = dict(zip(*pd.read_parquet(os.path.join(data_dir, profile, "index_surface.parquet"))[["key", "n"]].T.values))
    # One row per study of each file, as the README shows; paths made openable from here.
    cat = files.assign(study=files["studies"].str.split()).explode("study")
    cat["path"] = [os.path.join(data_dir, p) for p in cat["path"]]
    cat = cat.astype({"study": object}).fillna({"study": ""})
    # With each instance's parameters and results from its stage's table, as pandas joins them.
    params = pd.concat([
        pd.read_parquet(os.path.join(data_dir, profile, f"index_{s}.parquet"),
                        dtype_backend="numpy_nullable").drop(
            columns=["profile", "stage", "studies", "realization", "name", "state", "path"],
            errors="ignore")
        for s in sorted(set(files["stage"]))])
    cat = cat.merge(params, on="key", how="left", validate="many_to_one")
    for _, r in cat.drop_duplicates(["key", "file"]).iterrows():
        if r.file.endswith(".parquet"):
            check_metadata(r.path, TABLE_METADATA, r.stage, r.key)
            if not pd.isna(r.realization):
                t = pd.read_parquet(r.path)
                check("realization" in t.columns and (t["realization"] == r.realization).all(),
                      f"{r.path}: realization column does not say {r.realization}")
    stages = set(cat["stage"])
    for s in ["surface", "contact", "clusters", "statistics", "analytic", "figures"]:
        check(s in stages, f"no {s} artifact in the catalog")

    def rows(stage, file=None, **eq):
        sel = cat[cat["stage"] == stage]
        if file is not None:
            sel = sel[sel["file"] == file]
        for k, v in eq.items():
            sel = sel[sel[k] == v]
        return sel

    parquet_files = 0
    # Contact: loads table, one packed map per load, pressure fields where kept.
    contact_loads = {}
    for _, r in rows("contact", "loads.parquet").iterrows():
        # Under a hardness (docs/CONVENTIONS.md) the table also holds the ceiling and the
        # saturated nodes, and each saturated map is packed as the contact map is.
        plastic = "hardness_pressure" in pq.read_schema(r.path).names
        check_schema(r.path, SCHEMAS[("contact", "loads.parquet")]
                     + ([("hardness_pressure", F64), ("n_saturated_px", U64)] if plastic else []))
        df = pd.read_parquet(r.path)
        parquet_files += 1
        d = os.path.dirname(r.path)
        maps = sorted(f for f in os.listdir(d) if f.startswith("contact_"))
        check(len(df) == len(maps), f"{r.path}: {len(df)} rows but {len(maps)} contact maps")
        check(bool(df["converged"].all()), f"{r.path}: a stored load did not converge")
        surface_key = manifest_of(r.path)["inputs"][0]
        heights = np.load(rows("surface", "heights.npy", key=surface_key)["path"].iloc[0])
        n = heights.shape[0]
        for i, f in enumerate(maps):
            m = np.load(os.path.join(d, f))
            check(m.dtype == np.uint8 and m.shape == (n, (n + 7) // 8),
                  f"{d}/{f}: dtype {m.dtype} shape {m.shape}, expected uint8 {(n, (n + 7) // 8)}")
            check(unpacked_count(m, n) == int(df["n_contact_px"].iloc[i]),
                  f"{d}/{f}: {unpacked_count(m, n)} contact pixels, table says "
                  f"{df['n_contact_px'].iloc[i]}")
            if plastic:
                sf = os.path.join(d, f.replace("contact_", "saturated_"))
                s = np.load(sf)
                check(unpacked_count(s, n) == int(df["n_saturated_px"].iloc[i])
                      and df["n_saturated_px"].iloc[i] <= df["n_contact_px"].iloc[i],
                      f"{sf}: {unpacked_count(s, n)} saturated pixels, table says "
                      f"{df['n_saturated_px'].iloc[i]} of {df['n_contact_px'].iloc[i]} in contact")
            pf = os.path.join(d, f.replace("contact_", "pressure_"))
            if os.path.exists(pf):
                p = np.load(pf)
                check(p.dtype == np.float64 and p.shape == (n, n) and (p >= 0).all(),
                      f"{pf}: dtype {p.dtype}, shape {p.shape}, min {p.min()}")
                check(abs(p.mean() - df["mean_pressure"].iloc[i]) <= 1e-12 * max(1.0, p.mean()),
                      f"{pf}: mean {p.mean()} != mean_pressure {df['mean_pressure'].iloc[i]}")
                check(((p > 0).sum()) == int(df["n_contact_px"].iloc[i]),
                      f"{pf}: positive pressures do not match the contact pixels")
        contact_loads[(r.study, r.realization)] = df

    # Surfaces: float64 (n, n), finite, zero mean, C order.
    for _, r in rows("surface", "heights.npy").iterrows():
        h = np.load(r.path)
        check(h.dtype == np.float64 and h.ndim == 2 and h.shape[0] == h.shape[1]
              and h.flags["C_CONTIGUOUS"] and np.isfinite(h).all(),
              f"{r.path}: dtype {h.dtype}, shape {h.shape}")
        check(abs(h.mean()) <= 1e-12 * max(h.std(), 1e-300), f"{r.path}: mean {h.mean()}")
        n = int(surface_n[r.key])
        check(h.shape[0] == n, f"{r.path}: shape {h.shape} but n = {n} in index_surface")

    # Clusters: one row per cluster; counts and areas match the per-load table and contact.
    for _, r in rows("clusters", "clusters.parquet").iterrows():
        check_schema(r.path, SCHEMAS[("clusters", "clusters.parquet")])
        cl = pd.read_parquet(r.path)
        lp = os.path.join(os.path.dirname(r.path), "loads.parquet")
        check_schema(lp, SCHEMAS[("clusters", "loads.parquet")])
        loads = pd.read_parquet(lp)
        parquet_files += 2
        counts = cl.groupby("load_index").size().reindex(loads["load_index"], fill_value=0)
        check((counts.values == loads["n_clusters"].values).all(),
              f"{r.path}: clusters per load {counts.values} != n_clusters "
              f"{loads['n_clusters'].values}")
        contact = contact_loads.get((r.study, r.realization))
        if check(contact is not None, f"{r.path}: no contact table for {r.study}/{r.realization}"):
            area = cl.groupby("load_index")["area_px"].sum().reindex(
                contact["load_index"], fill_value=0)
            check((area.values == contact["n_contact_px"].values).all(),
                  f"{r.path}: cluster areas do not add up to the contact pixels")

    # Statistics: row counts per load, PDF normalisation, A* grid, two estimators.
    for _, r in rows("statistics", "loads.parquet").iterrows():
        d = os.path.dirname(r.path)
        tables = {}
        for f in ["loads", "pdf", "ccdf", "wear", "alpha"]:
            path = os.path.join(d, f + ".parquet")
            check_schema(path, SCHEMAS[("statistics", f + ".parquet")])
            tables[f] = pd.read_parquet(path)
            parquet_files += 1
        nl = len(tables["loads"])
        contacts = [v for (s, _), v in contact_loads.items() if s == r.study]
        check(contacts and nl == len(contacts[0]),
              f"{r.path}: {nl} loads, contact stage has {len(contacts[0]) if contacts else 0}")
        check(len(tables["wear"]) == nl * A_STAR_GRID, f"{d}/wear.parquet: {len(tables['wear'])} rows")
        check(len(tables["alpha"]) == nl * ESTIMATORS, f"{d}/alpha.parquet: {len(tables['alpha'])} rows")
        ls = float(r.lambda_s_px)
        pdf = tables["pdf"]
        norm = (pdf["pdf_pooled"] * pdf["width_px"] / ls**2).groupby(pdf["load_index"]).sum()
        check(np.allclose(norm.values, 1.0, atol=1e-12),
              f"{d}/pdf.parquet: Σ p·width per load = {norm.values}, expected 1")
        ccdf = tables["ccdf"]
        check(ccdf["ccdf"].between(0, 1).all(), f"{d}/ccdf.parquet: ccdf outside [0, 1]")

    # Analytic: model rows per load and threshold; Fig. 6 curves.
    for _, r in rows("analytic").iterrows():
        if not r.file.endswith(".parquet"):
            continue
        check_schema(r.path, SCHEMAS[("analytic", r.file)])
        df = pd.read_parquet(r.path)
        parquet_files += 1
        if r.file == "fig6.parquet":
            check(len(df) == FIG6_ROWS, f"{r.path}: {len(df)} rows, expected {FIG6_ROWS}")
        elif r.file == "plateau.parquet":
            # One row per A* (none when no load up to W/W0 = 0.06 has a fit); the model at a
            # finite cut-off stays below its A_m → ∞ plateau, both probabilities.
            check(len(df) in (0, A_STAR_GRID), f"{r.path}: {len(df)} rows")
            check(df["k_pl_plateau"].between(0, 1).all()
                  and (df["k_pl_at_load"] <= df["k_pl_plateau"] + 1e-12).all(),
                  f"{r.path}: plateau values out of order")
        else:
            check(len(df) % A_STAR_GRID == 0 and len(df) > 0, f"{r.path}: {len(df)} rows")

    # Figures: PNG valid and of the size the manifest states, SVG is XML, CSV/NPY readable.
    figures = 0
    for _, r in rows("figures").iterrows():
        stem, ext = os.path.splitext(r.file)
        sizes = manifest_of(r.path)["results"]["png_size_px"]
        if ext == ".png":
            figures += 1
            with Image.open(r.path) as im:
                im.verify()
            with Image.open(r.path) as im:
                im.load()
                check(list(im.size) == sizes[stem] and im.mode == "RGB",
                      f"{r.path}: {im.size} {im.mode}, manifest says {sizes[stem]}")
                check(np.asarray(im).std() > 0, f"{r.path}: a blank image")
        elif ext == ".svg":
            root = ET.parse(r.path).getroot()
            check(root.tag.endswith("svg") and root.get("width") == str(sizes[stem][0]),
                  f"{r.path}: not an SVG of width {sizes[stem][0]}")
            # Publication style: every label as a reader sees it, no markup (K_PL, λ_s,
            # A^2) and no e-notation (1e-4) left.
            for t in root.iter():
                if t.tag.endswith("text") and t.text:
                    label = t.text.strip()
                    check("_" not in label and "^" not in label
                          and not re.search(r"\de[-+]?\d", label),
                          f"{r.path}: label '{label}'")
        elif ext == ".csv":
            df = pd.read_csv(r.path, keep_default_na=False)
            check(list(df.columns) == DATA_COLUMNS, f"{r.path}: columns {list(df.columns)}")
            check(len(df) > 0 and (df["series"] != "").all(),
                  f"{r.path}: no data, or a row without its curve")
            # A band is given whole (both edges) or not at all, its low edge below its high.
            if list(df.columns) == DATA_COLUMNS:
                lo, hi = (pd.to_numeric(df[c].replace("", np.nan)) for c in ("y_ci95_low", "y_ci95_high"))
                check((lo.isna() == hi.isna()).all() and (lo[lo.notna()] <= hi[hi.notna()]).all(),
                      f"{r.path}: a band with one edge, or its low edge above its high")
        elif r.file == "fig45_load_resolution.parquet":
            check_schema(r.path, LOAD_RESOLUTION)
            parquet_files += 1

            def wear_of(i, figure=r.path):
                """Wear table of input i of the load-resolution audit the figure draws
                (0: the finer sweep, 1: the chosen one), found through the manifests."""
                cache = os.path.dirname(os.path.dirname(os.path.dirname(figure)))
                audit = manifest_of(figure)["inputs"][0]
                with open(os.path.join(cache, "audits", audit, "manifest.json")) as f:
                    key = json.load(f)["inputs"][i]
                path = os.path.join(cache, "statistics", key, "wear.parquet")
                return pd.read_parquet(path) if os.path.exists(path) else None

            check_load_resolution(r.path, wear_of)
        elif r.file == "spectrum_transition.parquet":
            # 0: negative from the lowest load; inf: positive at every load; NaN: dN/dA_c
            # undefined at every load (a toy grid); else inside the sweep.
            check_schema(r.path, SPECTRUM_TRANSITION)
            parquet_files += 1
            df = pd.read_parquet(r.path)
            w = df["w_over_w0_sign_change"]
            inside = (w > df["w_over_w0_lowest"]) & (w <= df["w_over_w0_highest"])
            check(len(df) > 0 and (inside | (w == 0) | (w == float("inf")) | w.isna()).all()
                  and df["lambda_l_over_lambda_s"].is_monotonic_increasing,
                  f"{r.path}: a sign change outside its sweep, or widths out of order")
        elif r.file in ("plastic_alpha.parquet", "spectrum_alpha.parquet"):
            # The plastic and spectrum families' fits: each the statistics stage's own at the
            # solved load.
            plastic = r.file == "plastic_alpha.parquet"
            check_schema(r.path, PLASTIC_ALPHA if plastic else SPECTRUM_ALPHA)
            parquet_files += 1
            df = pd.read_parquet(r.path)
            x = df["inverse_hardness" if plastic else "lambda_l_over_lambda_s"]
            check(len(df) > 0 and (x >= 0).all(),
                  f"{r.path}: no rows, or a negative setting")
            for study, group in df.groupby("study"):
                src = rows("statistics", "alpha.parquet", study=study)
                if not check(len(src) == 1, f"{r.path}: {study} has {len(src)} alpha tables"):
                    continue
                alpha = pd.read_parquet(src.path.iloc[0])
                for _, f in group.iterrows():
                    same = alpha[(alpha["w_over_w0"] == f["w_over_w0_solved"])
                                 & (alpha["estimator"] == f["estimator"])]
                    check(len(same) == 1 and (same["alpha"].iloc[0] == f["alpha"]
                                              or (pd.isna(same["alpha"].iloc[0]) and pd.isna(f["alpha"]))),
                          f"{r.path}: {study} {f['estimator']} at {f['w_over_w0_solved']} is not the stored fit")
        elif r.file == "fig2_convergence.parquet":
            check_schema(r.path, FIG2_CONVERGENCE)
            parquet_files += 1
            check_fig2_convergence(r.path, rows("clusters", "clusters.parquet", study="fig2"))
        elif ext == ".parquet":
            check_schema(r.path, CONVERGENCE)
            df = pd.read_parquet(r.path)
            parquet_files += 1
            check(len(df) > 0 and df["ks_distance"].between(0, 1).all()
                  and set(df["kind"]) == {"setting", "realizations"},
                  f"{r.path}: {len(df)} rows, kinds {set(df['kind'])}")
            finest = df[(df["kind"] == "setting") & (df["setting"] == df["setting"].max())]
            check((finest["ks_distance"] == 0).all(), f"{r.path}: finest setting not at 0")
            # fig128_convergence.parquet, or fig128_convergence_h<H>.parquet per Hurst
            # exponent when a profile holds several (the KS check matches studies by counts).
            # fig128_discretisation.parquet: fig3_ll128 against a finer c128_ study.
            prefix = "c128_" if r.file.startswith(("fig128_convergence", "fig128_discretisation")) else {
                "figB1_convergence.parquet": "b1_", "figB2_convergence.parquet": "b2_"}.get(r.file)
            if check(prefix is not None, f"{r.path}: an unknown convergence table"):
                cl = rows("clusters", "clusters.parquet")
                own = cl["study"].str.startswith(prefix)
                if r.file.startswith("fig128_discretisation"):
                    own |= cl["study"] == "fig3_ll128"
                check_convergence_ks(r.path, cl[own])
            if r.file.startswith(("fig128_convergence", "fig128_discretisation")):
                check_fig128_summary(r.path, df, manifest_of(r.path)["results"]["convergence"])
        elif ext == ".npy":
            a = np.load(r.path)
            check(a.ndim == 2 and a.size > 0, f"{r.path}: shape {a.shape}")
    expected = ["fig2a", "fig2b", "fig2c", "fig2d", "fig2e", "fig2f", "fig2_convergence",
                "fig3", "fig4a", "fig4b", "fig5a", "fig5b", "fig6", "figB1", "figB2",
                "figB1_convergence", "figB2_convergence", "fig128_convergence",
                "fig128_discretisation", "fig45_dn_dac", "fig45_load_resolution"]
    drawn = {os.path.splitext(f)[0] for f in rows("figures")["file"] if f.endswith(".png")}
    check(set(expected) <= drawn, f"missing figures: {sorted(set(expected) - drawn)}")

    print(f"checked {len(cat)} catalog rows, {parquet_files} Parquet files, {figures} PNGs; "
          f"{len(failures)} failure(s)")
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
