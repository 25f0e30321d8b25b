#!/usr/bin/env python3
"""The numbers of docs/FIDELITY.md, measured from a store: one line per quantitative statement
of the paper, with a 95 % interval where the store has one.

    python3 scripts/fidelity.py DATA PROFILE [--json OUT]

DATA is a store a `wearcoef run --profile PROFILE` filled (the default gallery's, or the paper
campaign's); nothing is computed beyond reading its tables and manifests. Needs pandas and
pyarrow (the client venv of `make test` has them). Statements whose studies the profile lacks
are printed as "absent".
"""
import argparse
import json
import math
import os
import sys

import numpy as np
import pandas as pd

A_STARS = [2.0, 8.0, 32.0, 128.0, 512.0]
FIG3_LOADS = [0.005, 0.02, 0.06]


class Store:
    def __init__(self, data, profile):
        self.data = data
        path = os.path.join(data, profile, "index.parquet")
        if not os.path.exists(path):
            sys.exit(f"{path}: no catalog; run `wearcoef run --profile {profile} --data {data}` first")
        self.index = pd.read_parquet(path)

    def _path(self, p):
        return p if os.path.isabs(p) else os.path.join(self.data, p)

    def table(self, stage, study, file):
        rows = self.index[
            (self.index.stage == stage) & (self.index.studies == study) & (self.index.file == file)
        ]
        if rows.empty:
            return None
        return pd.read_parquet(self._path(rows.path.iloc[0]))

    def audit(self, figure):
        rows = self.index[(self.index.stage == "audits") & (self.index.name == figure)]
        if rows.empty:
            return None
        manifest = os.path.join(os.path.dirname(self._path(rows.path.iloc[0])), "manifest.json")
        with open(manifest) as f:
            return json.load(f)["results"]


def nearest(values, target):
    values = np.asarray(sorted(set(values)))
    return float(values[np.argmin(np.abs(np.log(values) - math.log(target)))])


def fmt(x, digits=3):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    if x == 0:
        return "0"
    if abs(x) < 1e-3 or abs(x) >= 1e4:
        return f"{x:.{max(digits - 1, 1)}e}"
    return f"{x:.{digits}g}"


def interval(r, low="ci95_low", high="ci95_high", digits=3):
    """' [low, high]' where the store has an interval, else ''."""
    lo, hi = r[low], r[high]
    if pd.notna(lo) and pd.notna(hi):
        return f" [{fmt(lo, digits)}, {fmt(hi, digits)}]"
    return ""


def alpha_rows(store, study, loads, out, key):
    a = store.table("statistics", study, "alpha.parquet")
    if a is None:
        out[key] = "absent"
        return
    cells = []
    for estimator, name in [
        ("discrete_plateau_power_law_mle", "plateau + power law"),
        ("discrete_truncated_mle", "truncated power law"),
    ]:
        parts = []
        for t in loads:
            w = nearest(a.w_over_w0, t)
            r = a[(a.w_over_w0 == w) & (a.estimator == estimator)].iloc[0]
            ci = interval(r) or f" (no interval: {r.ci95_method})"
            counts = ""
            if "clusters" in r and pd.notna(r.clusters):
                counts = f", {int(r.clusters)} clusters, {int(r.realizations)} realizations"
            tail = ""
            if estimator == "discrete_truncated_mle" and "gof_p" in r and pd.notna(r.gof_p):
                tail = f"; GOF p = {r.gof_p:.2f}; {r.tail_verdict}"
            parts.append(f"{fmt(r.alpha)}{ci} at {fmt(w, 2)}{counts}{tail}")
        cells.append(f"{name}: " + "; ".join(parts))
    out[key] = " | ".join(cells)


def tentative(r):
    """Drawn hollow: fewer than 10 clusters above A*, or a pooled interval reaching 0."""
    lo = r.get("k_archard_pooled_ci95_low", np.nan)
    return r.clusters_above < 10 or (pd.notna(lo) and lo <= 0)


def k_cell(r, column, digits):
    """A pooled K or 𝒦 with its interval over realizations and the counts behind it."""
    ci = interval(r, f"{column}_pooled_ci95_low", f"{column}_pooled_ci95_high", digits)
    flag = ", tentative" if tentative(r) else ""
    return (
        f"{fmt(r[f'{column}_pooled'], digits)}{ci} "
        f"({int(r.clusters_above)} clusters, fewest in a realization {int(r.clusters_above_smallest_realization)}{flag})"
    )


def wear_rows(store, study, out):
    wear = store.table("statistics", study, "wear.parquet")
    if wear is None:
        for k in ["K_transition", "K_levels", "K_after", "K_range", "Kup_at_max", "rate_slope"]:
            out[k] = "absent"
        return
    loads = sorted(wear.w_over_w0.unique())
    w_max = loads[-1]
    transitions, growth, kup, slopes, levels = [], [], [], [], []
    positive = []
    for a_star in A_STARS:
        rows = wear[wear.a_star_over_ls2 == a_star].sort_values("w_over_w0")
        k = rows.k_archard_pooled.values
        w = rows.w_over_w0.values
        nz = np.nonzero(k > 0)[0]
        if len(nz) == 0:
            transitions.append(f"{fmt(a_star, 3)} λ_s²: none up to {fmt(w_max, 2)}")
            continue
        first = nz[0]
        # The transition lies between the last load with K = 0 and the first with K > 0.
        if first == 0:
            transitions.append(f"{fmt(a_star, 3)} λ_s²: below {fmt(w[0], 2)}")
        else:
            transitions.append(f"{fmt(a_star, 3)} λ_s²: {fmt(w[first - 1], 2)}–{fmt(w[first], 2)}")
        # Growth of K from the first load after the transition to the largest load.
        growth.append(
            f"{fmt(a_star, 3)} λ_s²: ×{fmt(k[-1] / k[first], 2)} "
            f"(from {k_cell(rows.iloc[first], 'k_archard', 2)})"
        )
        positive.extend((k[i], rows.iloc[i]) for i in range(first, len(k)) if k[i] > 0)
        last = rows.iloc[-1]
        levels.append(f"{fmt(a_star, 3)} λ_s²: {k_cell(last, 'k_archard', 2)}")
        kup.append(f"{fmt(a_star, 3)} λ_s²: {k_cell(last, 'k_upscaled', 3)}")
        # Wear rate against load in log–log over the upper half of the sweep.
        r = rows.wear_rate_over_l2_mean.values
        upper = (w >= math.sqrt(w[first] * w_max)) & (r > 0)
        if upper.sum() >= 3:
            slope = np.polyfit(np.log(w[upper]), np.log(r[upper]), 1)[0]
            slopes.append(f"{fmt(a_star, 3)} λ_s²: {slope:.2f}")
    out["K_transition"] = "; ".join(transitions)
    out["K_levels"] = "; ".join(levels) + f" at W/W0 = {fmt(w_max, 2)}"
    out["K_after"] = "; ".join(growth) + f" (from the first load after the transition to W/W0 = {fmt(w_max, 2)})"
    if positive:
        lo = min(positive, key=lambda p: p[0])[1]
        hi = max(positive, key=lambda p: p[0])[1]
        firm = [p for p in positive if not tentative(p[1])]
        text = (
            f"{k_cell(lo, 'k_archard', 2)} to {k_cell(hi, 'k_archard', 2)} "
            "(pooled K > 0, A* = 2–512 λ_s², all loads)"
        )
        if firm:
            f = min(firm, key=lambda p: p[0])[1]
            text += f"; the smallest not tentative: {k_cell(f, 'k_archard', 2)} at W/W0 = {fmt(f.w_over_w0, 2)}, A* = {fmt(f.a_star_over_ls2, 3)} λ_s²"
        out["K_range"] = text
    out["Kup_at_max"] = "; ".join(kup) + f" at W/W0 = {fmt(w_max, 2)}"
    out["rate_slope"] = "; ".join(slopes) + " (d ln R / d ln W over the upper half of each post-transition range)"


def regime(store, study, out, key):
    loads = store.table("statistics", study, "loads.parquet")
    if loads is None:
        out[key] = "absent"
        return
    w = loads.w_over_w0.values
    d = loads.dn_dac_per_ls2_mean.values
    n = loads.n_clusters_mean.values
    peak = w[int(np.argmax(n))]
    neg = w[d < 0]
    sign = f"dN/dA_c < 0 from W/W0 = {fmt(neg[0], 2)}" if len(neg) else f"dN/dA_c > 0 at every load ({fmt(w[0], 2)}–{fmt(w[-1], 2)})"
    lo, hi = loads.dn_dac_per_ls2_ci95_low.values, loads.dn_dac_per_ls2_ci95_high.values
    resolved = f"; interval above 0 at {int(np.sum(lo > 0))}, below 0 at {int(np.sum(hi < 0))} of {len(w)} loads" if np.isfinite(lo).any() else "; no interval"
    out[key] = f"{sign}; N peaks at W/W0 = {fmt(peak, 2)}{resolved} ({int(loads.realizations.iloc[0])} realizations)"


def ks(a, b):
    a, b = np.sort(a), np.sort(b)
    x = np.concatenate([a, b])
    return float(np.max(np.abs(np.searchsorted(a, x, "right") / len(a) - np.searchsorted(b, x, "right") / len(b))))


def hurst(store, out):
    c = {}
    for study in ["fig3_h06", "fig3_h07", "fig3_ll128"]:
        t = store.table("statistics", study, "ccdf.parquet")
        if t is None:
            out["hurst"] = "absent"
            return
        w = nearest(t.w_over_w0, 0.06)
        c[study] = t[(t.w_over_w0 == w) & t.realization.isna()]
    parts = []
    for study, h in [("fig3_h06", "0.6"), ("fig3_h07", "0.7"), ("fig3_ll128", "0.8")]:
        t = c[study]
        at = lambda a: float(np.interp(a, t.area_over_ls2.values, t.ccdf.values, right=0.0))
        parts.append(f"H = {h}: P(A > 10 λ_s²) = {fmt(at(10.0), 2)}, P(A > 100 λ_s²) = {fmt(at(100.0), 2)}")
    a = store.table("statistics", "fig3_h06", "alpha.parquet")
    b = store.table("statistics", "fig3_ll128", "alpha.parquet")
    est = "discrete_plateau_power_law_mle"
    ra = a[(a.estimator == est)].iloc[0]
    rb = b[(b.estimator == est) & (b.w_over_w0 == nearest(b.w_over_w0, 0.06))].iloc[0]
    h7 = store.table("statistics", "fig3_h07", "alpha.parquet")
    rc = h7[(h7.estimator == est)].iloc[0]
    parts.append(
        f"plateau + power-law α̂: H = 0.6 {fmt(ra.alpha)}{interval(ra)} ({int(ra.realizations)} realizations), "
        f"H = 0.7 {fmt(rc.alpha)}{interval(rc)} ({int(rc.realizations)}), "
        f"H = 0.8 {fmt(rb.alpha)}{interval(rb)} ({int(rb.realizations)})"
    )
    out["hurst"] = "; ".join(parts) + " (W/W0 = 0.06, equal boxes)"


def settings(store, figure, out, key):
    r = store.audit(figure)
    if r is None:
        out[key] = "absent"
        return
    parts = []
    for s in r["settings"]:
        by_load = ", ".join(f"{fmt(k, 2)} at {fmt(w, 2)}" for w, k in s["ks_by_load"])
        parts.append(f"{s['setting']}: KS {by_load}")
    out[key] = f"reference {r['reference']}: " + "; ".join(parts) + f"; the rule's choice: {fmt(r.get('smallest_converged_setting'))}"


def area_load(store, out):
    loads = store.table("statistics", "fig3_ll128", "loads.parquet")
    if loads is None:
        out["area_load"] = "absent"
        return
    w = loads.w_over_w0.values
    ac = loads.area_fraction_mean.values
    ratio = ac / w
    slope = np.polyfit(np.log(w), np.log(ac), 1)[0]
    lo = loads.area_fraction_ci95_low.values / w
    hi = loads.area_fraction_ci95_high.values / w
    out["area_load"] = (
        f"A_c/(L² W/W0) = {fmt(ratio[0])} [{fmt(lo[0])}, {fmt(hi[0])}] at {fmt(w[0], 2)}, "
        f"{fmt(ratio[-1])} [{fmt(lo[-1])}, {fmt(hi[-1])}] at {fmt(w[-1], 2)} "
        f"({int(loads.realizations.iloc[0])} realizations); "
        f"log–log slope {slope:.3f} (λ_l/λ_s = 128)"
    )


PLASTIC = [("plastic_elastic", "∞"), ("plastic_h2", "2"), ("plastic_h1", "1"), ("plastic_h05", "0.5"), ("plastic_h02", "0.2")]


def plastic(store, out):
    """The plastic family: α̂ by both estimators at the Fig. 3 loads, 𝒦 and K at W/W0 = 0.06
    for two thresholds, and the saturated share of the contact area, per hardness."""
    for study, h in PLASTIC:
        alpha_rows(store, study, FIG3_LOADS, out, f"plastic_alpha_H{h}")
        regime(store, study, out, f"plastic_regime_H{h}")
        wear = store.table("statistics", study, "wear.parquet")
        if wear is None:
            continue
        w_max = wear.w_over_w0.max()
        last = wear[wear.w_over_w0 == w_max]
        cells = []
        for a_star in [2.0, 32.0, 128.0]:
            r = last[last.a_star_over_ls2 == a_star].iloc[0]
            cells.append(f"A* = {fmt(a_star, 3)} λ_s²: K {k_cell(r, 'k_archard', 2)}, 𝒦 {k_cell(r, 'k_upscaled', 3)}")
        out[f"plastic_wear_H{h}"] = "; ".join(cells) + f" at W/W0 = {fmt(w_max, 2)}"
        lt = store.table("statistics", study, "loads.parquet")
        if lt is not None:
            out[f"plastic_area_H{h}"] = "; ".join(
                f"A_c/L² {fmt(r.area_fraction_mean)} at W/W0 = {fmt(r.w_over_w0, 2)}"
                for r in [lt.iloc[0], lt.iloc[-1]]
            ) + f"; N {fmt(lt.n_clusters_mean.iloc[-1], 3)} and largest cluster {fmt(lt.largest_area_over_ls2_mean.iloc[-1], 3)} λ_s² at {fmt(lt.w_over_w0.iloc[-1], 2)}"
        rows = store.index[(store.index.stage == "contact") & (store.index.studies == study) & (store.index.file == "loads.parquet")]
        shares = []
        for path in rows.path:
            t = pd.read_parquet(store._path(path))
            if "n_saturated_px" in t:
                shares.append((t.n_saturated_px / t.n_contact_px).values)
        if shares:
            m = np.mean(shares, axis=0)
            out[f"plastic_saturated_H{h}"] = f"{fmt(m[0], 2)} at W/W0 = {fmt(t.w_over_w0.iloc[0], 2)} to {fmt(m[-1], 2)} at {fmt(t.w_over_w0.iloc[-1], 2)}"


SPECTRUM = [("spec_ll8", 8), ("spec_ll32", 32), ("spec_ll128", 128), ("spec_ll256", 256), ("spec_ll512", 512), ("spec_ll1024", 1024)]


def above(ccdf, n_pooled, a_star):
    """K = P(A > A*) from a pooled exact CCDF, and the clusters above A* (K times the pool)."""
    rows = ccdf[ccdf.area_over_ls2 <= a_star]
    k = 1.0 if rows.empty else float(rows.ccdf.iloc[-1])
    return k, int(round(k * n_pooled))


def spectrum(store, out):
    """Per width at W/W0 = 0.06: α̂ by both estimators, the largest cluster, K and 𝒦 at fixed
    A*/λ_s² with counts, and K at A* = λ_l²/32 and λ_l²/128 with the clusters above."""
    for study, width in SPECTRUM:
        a = store.table("statistics", study, "alpha.parquet")
        if a is None:
            out[f"spectrum_{width}"] = "absent"
            continue
        alpha_rows(store, study, [0.06], out, f"spectrum_alpha_{width}")
        loads = store.table("statistics", study, "loads.parquet")
        w = nearest(loads.w_over_w0, 0.06)
        lr = loads[loads.w_over_w0 == w].iloc[0]
        n_pooled = lr.n_clusters_mean * lr.realizations
        wear = store.table("statistics", study, "wear.parquet")
        last = wear[wear.w_over_w0 == w]
        cells = [
            f"largest cluster {fmt(lr.largest_area_over_ls2_mean, 3)} λ_s² (mean), "
            f"{int(round(n_pooled))} clusters in {int(lr.realizations)} realizations"
        ]
        for a_star in [2.0, 512.0]:
            r = last[last.a_star_over_ls2 == a_star]
            if not r.empty:
                r = r.iloc[0]
                cells.append(f"A* = {fmt(a_star, 3)} λ_s²: K {k_cell(r, 'k_archard', 2)}, 𝒦 {k_cell(r, 'k_upscaled', 3)}")
        c = store.table("statistics", study, "ccdf.parquet")
        pooled = c[(c.w_over_w0 == w) & c.realization.isna()].sort_values("area_over_ls2")
        for div in [32, 128]:
            k, n = above(pooled, n_pooled, width * width / div)
            cells.append(f"A* = λ_l²/{div}: K {fmt(k, 2)} on {n} clusters")
        out[f"spectrum_{width}"] = "; ".join(cells) + f" at W/W0 = {fmt(w, 2)}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("data")
    ap.add_argument("profile")
    ap.add_argument("--json", help="also write the values to this file")
    args = ap.parse_args()
    store = Store(args.data, args.profile)
    out = {}
    alpha_rows(store, "fig3_ll128", FIG3_LOADS, out, "alpha128")
    alpha_rows(store, "fig3_ll32", FIG3_LOADS, out, "alpha32")
    alpha_rows(store, "fig3_ll8", FIG3_LOADS, out, "alpha8")
    regime(store, "fig2", out, "regime8")
    regime(store, "fig3_ll128", out, "regime128")
    wear_rows(store, "fig3_ll128", out)
    hurst(store, out)
    area_load(store, out)
    settings(store, "figB1", out, "b1")
    settings(store, "figB2", out, "b2")
    plastic(store, out)
    spectrum(store, out)
    for k, v in out.items():
        print(f"{k}: {v}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1, ensure_ascii=False)


if __name__ == "__main__":
    main()
