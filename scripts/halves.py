#!/usr/bin/env python3
"""Disjoint halves: each study's realizations split into two halves (first and second half
by realization index), each fitted apart by `wearcoef fit --json` (intervals over
realizations); counts the loads where the two halves' 95 % intervals are disjoint, per
estimator. Two calibrated 95 % intervals of independent halves are disjoint at about 1 % of
loads (5.6 % if each covered 95 % and they were equally wide: P(|Z1 - Z2| > 1.96 √2) = 0.6 %
for equal widths; a few percent allows for unequal ones).

usage: halves.py DATA PROFILE BINARY [STUDY ...]   (studies with at least 10 realizations
by default; pandas needed)
"""
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import pandas as pd

data, profile, binary = Path(sys.argv[1]), sys.argv[2], sys.argv[3]
wanted = set(sys.argv[4:])
index = pd.read_parquet(data / profile / "index.parquet")
clusters = index[(index.stage == "clusters") & (index.file == "clusters.parquet")]
by_study = {}
for _, row in clusters.iterrows():
    for study in str(row.studies).split(","):
        by_study.setdefault(study, []).append((int(row.realization), data / row.path))
total = {"truncated": [0, 0], "plateau": [0, 0]}
with tempfile.TemporaryDirectory() as tmp:
    for study, files in sorted(by_study.items()):
        files.sort()
        r = len(files)
        if (wanted and study not in wanted) or (not wanted and r < 10):
            continue
        fits = []
        for half, chosen in enumerate([files[: r // 2], files[r // 2:]]):
            frames = []
            for realization, path in chosen:
                d = pd.read_parquet(path, columns=["load_index", "area_px", "percolating"])
                d["realization"] = realization
                frames.append(d)
            table = Path(tmp) / f"{study}_{half}.parquet"
            pd.concat(frames).to_parquet(table)
            out = subprocess.run([binary, "fit", "--areas", str(table), "--json"],
                                 check=True, capture_output=True, text=True).stdout
            fits.append({row["load_index"]: row for row in json.loads(out)})
        counts = {}
        for name in total:
            disjoint = judged = 0
            for load, a in fits[0].items():
                b = fits[1].get(load)
                if b is None:
                    continue
                if name == "plateau":
                    a, b = a.get("plateau", {}), b.get("plateau", {})
                lo_a, hi_a = a.get("realization_ci95_low"), a.get("realization_ci95_high")
                lo_b, hi_b = b.get("realization_ci95_low"), b.get("realization_ci95_high")
                if None in (lo_a, hi_a, lo_b, hi_b):
                    continue
                judged += 1
                disjoint += hi_a < lo_b or hi_b < lo_a
            counts[name] = (disjoint, judged)
            total[name][0] += disjoint
            total[name][1] += judged
        print(f"{study}: {r} realizations; disjoint/judged loads: "
              + ", ".join(f"{k} {d}/{j}" for k, (d, j) in counts.items()), flush=True)
for name, (d, j) in total.items():
    print(f"all: {name}: {d} of {j} loads disjoint ({100 * d / max(j, 1):.1f} %)")
