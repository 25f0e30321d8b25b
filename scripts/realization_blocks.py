#!/usr/bin/env python3
"""How many realizations a study's cluster-area distribution needs, measured on many of them.

For each r, the R realizations of the study are cut into disjoint blocks of r (in realization
order); each block's pooled cluster areas are compared with all R pooled, by the two-sample
Kolmogorov-Smirnov distance, at every load. Printed: the largest distance over the blocks per
load, and the smallest r from which every larger r keeps it within the tolerance at every load.
Unlike "the first r against all", this does not depend on how lucky the first realizations are.

    make figures PROFILE=realizations8   # or: wearcoef run --profile realizations8 clusters
    python3 scripts/realization_blocks.py data realizations8 fig3_ll8 [--tolerance 0.05]

Needs pandas and pyarrow (the client venv of `make test` has them).
"""
import argparse
import sys

import numpy as np
import pandas as pd


def ks_distance(a, b):
    a, b = np.sort(a), np.sort(b)
    x = np.concatenate([a, b])
    fa = np.searchsorted(a, x, side="right") / len(a)
    fb = np.searchsorted(b, x, side="right") / len(b)
    return float(np.max(np.abs(fa - fb)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("data", help="the store (data directory)")
    ap.add_argument("profile")
    ap.add_argument("study")
    ap.add_argument("--tolerance", type=float, default=0.05)
    args = ap.parse_args()
    index = pd.read_parquet(f"{args.data}/{args.profile}/index.parquet")
    rows = index[
        (index.stage == "clusters")
        & (index.studies == args.study)
        & index.file.str.endswith("clusters.parquet")
    ]
    if rows.empty:
        sys.exit(f"no clusters of study {args.study} in {args.data}/{args.profile}: run it first")
    areas = pd.concat(
        pd.read_parquet(p if p.startswith("/") else f"{args.data}/{p}") for p in rows.path
    )
    realizations = sorted(areas.realization.unique())
    total = len(realizations)
    loads = sorted(areas.w_over_w0.unique())
    print(f"{args.study}: {total} realizations; clusters per realization by load:",
          ", ".join(f"{w:g}: {len(areas[areas.w_over_w0 == w]) / total:.0f}" for w in loads))
    worst = {}
    for r in range(1, total // 2 + 1):
        per_load = []
        for w in loads:
            at = areas[areas.w_over_w0 == w]
            everything = at.area_px.values
            blocks = [realizations[i:i + r] for i in range(0, total - r + 1, r)]
            per_load.append(max(
                ks_distance(at[at.realization.isin(b)].area_px.values, everything) for b in blocks
            ))
        worst[r] = max(per_load)
        print(f"r = {r:2d} ({total // r} blocks): largest KS over blocks",
              " ".join(f"{d:.3f}" for d in per_load))
    within = [r for r in worst if all(worst[s] <= args.tolerance for s in worst if s >= r)]
    if within:
        print(f"smallest r within {args.tolerance} from there on: {min(within)}")
    else:
        print(f"no r up to {total // 2} is within {args.tolerance}")


if __name__ == "__main__":
    main()
