"""Time scipy.ndimage.label (8-connectivity) plus the periodic merge and the area count on
the maps written by benches/labelling.rs, check that the clusters agree with wearcoef's, and
print the comparison table. Usage: labelling_scipy.py <wearcoef binary> <maps dir> <criterion dir>"""
import json
import os
import subprocess
import sys
import time

import numpy as np
import scipy
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

wearcoef, maps, criterion = sys.argv[1:4]
STRUCTURE = np.ones((3, 3), dtype=bool)


def periodic_areas(m):
    """Cluster areas on the torus: label the open box, then join labels across the edges."""
    lab, count = ndimage.label(m, structure=STRUCTURE)
    a, b = [], []
    for d in (-1, 0, 1):
        top, bottom = lab[0, :], np.roll(lab[-1, :], d)
        k = (top > 0) & (bottom > 0)
        a.append(top[k]); b.append(bottom[k])
        left, right = lab[:, 0], np.roll(lab[:, -1], d)
        k = (left > 0) & (right > 0)
        a.append(left[k]); b.append(right[k])
    a, b = np.concatenate(a), np.concatenate(b)
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(count + 1, count + 1))
    _, comp = connected_components(graph, directed=False)
    areas = np.bincount(comp[lab[m]])
    return np.sort(areas[areas > 0])[::-1]


def median_seconds(f, repeats):
    times = []
    for _ in range(repeats):
        t = time.perf_counter(); f(); times.append(time.perf_counter() - t)
    return float(np.median(times))


def ours(n, percent):
    path = os.path.join(criterion, "label8", f"percent{percent}", str(n), "new", "estimates.json")
    with open(path) as f:
        return json.load(f)["median"]["point_estimate"] * 1e-9


print(f"scipy {scipy.__version__}, numpy {np.__version__} (1 thread); wearcoef 1 thread\n")
print("| map | scipy label + periodic merge + areas (ms) | wearcoef label (ms) | ratio wearcoef/scipy | clusters | identical areas |")
print("|---|---|---|---|---|---|")
for n in (1024, 4096):
    for percent in (1, 20):
        path = os.path.join(maps, f"map_{n}_{percent}.npy")
        m = np.load(path)
        ref = periodic_areas(m)
        t_scipy = median_seconds(lambda: periodic_areas(m), 15 if n <= 1024 else 5)
        out = subprocess.run([wearcoef, "clusters", "--contact", path, "--json"],
                             check=True, capture_output=True, text=True)
        got = np.array(json.loads(out.stdout)["areas_px"])
        same = len(got) == len(ref) and bool(np.all(got == ref))
        t_ours = ours(n, percent)
        print(f"| {n}², {percent} % | {t_scipy*1e3:.1f} | {t_ours*1e3:.1f} | {t_ours/t_scipy:.2f} | {len(ref)} | {'yes' if same else 'NO'} |")
