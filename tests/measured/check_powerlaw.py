"""The tail tests of `wearcoef fit --json` against the `powerlaw` package (PyPI 2.0.0) on the
same cluster areas: a rough surface pressed by `wearcoef solve`, labelled by `wearcoef
clusters`, at three loads. Part of `make test-measured`.

Usage: check_powerlaw.py WEARCOEF_BINARY WORK_DIR

For each load, at our x_min (`tail_tests.k_min_px`), `powerlaw.Fit(..., xmin=k_min,
discrete=True, estimate_discrete=False)` fits the same discrete distributions
(its lognormal and stretched exponential discretised by rounding, as ours are):

- α of the power law above x_min agrees to 1e-3 (powerlaw's Nelder–Mead stops at tol 1e-4);
- each alternative's log-likelihood is at least powerlaw's, less 1e-6 relative: ours is the
  exact maximum, theirs an optimiser's stop;
- where the two maxima agree to 0.01 in log-likelihood (the same fit), the normalised ratio
  agrees to 2e-3 relative plus 2e-3 (parameter differences of ~1e-4 relative move the
  per-cluster differences, hence σ, by about that), and ln p to 2 % plus 0.01 (ln p of a
  Gaussian tail moves by about |R/σ√n| times the change of R/σ√n);
- at least 3 of 4 comparisons meet that agreement (the others are powerlaw's optimiser
  stopping early, where ours is the likelier by more than 0.01).
"""
import json
import math
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import powerlaw

warnings.filterwarnings("ignore")
binary, work = sys.argv[1], Path(sys.argv[2])
work.mkdir(parents=True, exist_ok=True)


def run(*args):
    out = subprocess.run([binary, *map(str, args)], check=True, capture_output=True, text=True)
    return out.stdout


loads = "0.005,0.02,0.06"
run("surface", "--n", 1024, "--lambda-l-px", 512, "--lambda-s-px", 4, "--hurst", 0.8,
    "--seed", 3, "-o", work / "h.npy")
run("solve", "--surface", work / "h.npy", "--loads", loads, "--contact-out", work / "c.npy")
run("clusters", "--contact", work / "c.npy", "--out", work / "clusters.parquet")
rows = json.loads(run("fit", "--areas", work / "clusters.parquet", "--json", "--resamples", 40))
rows = rows if isinstance(rows, list) else rows["loads"]
table = pd.read_parquet(work / "clusters.parquet")

PEER = {
    "exponential_cutoff": "truncated_power_law",
    "lognormal": "lognormal",
    "exponential": "exponential",
    "stretched_exponential": "stretched_exponential",
}
failures, compared, total = [], 0, 0
for r in rows:
    t = r["tail_tests"]
    k_min = t["k_min_px"]
    at = table[(table.load_index == r["load_index"]) & ~table.percolating]
    areas = at.area_px.to_numpy()
    fit = powerlaw.Fit(areas, xmin=k_min, discrete=True, estimate_discrete=False, verbose=False)
    where = f"load {r['load_index']} ({len(areas)} clusters, x_min {k_min}, n {t['n']})"
    if abs(t["alpha_power_law"] - fit.power_law.alpha) > 1e-3:
        failures.append(f"{where}: α {t['alpha_power_law']} against {fit.power_law.alpha}")
    for ours_name, peer_name in PEER.items():
        total += 1
        ours = t["tests"][ours_name]
        peer = getattr(fit, peer_name)
        r_peer, p_peer = fit.distribution_compare("power_law", peer_name, normalized_ratio=True)
        l_ours, l_peer = ours["loglikelihood"], float(peer.loglikelihood)
        line = (f"{where} {ours_name}: ours L {l_ours:.4f} R/σ√n {ours['normalised_ratio']:+.4f} "
                f"p {ours['p']:.4g}; powerlaw L {l_peer:.4f} R/σ√n {r_peer:+.4f} p {p_peer:.4g}")
        print(line)
        if l_ours < l_peer - 1e-6 * abs(l_peer):
            failures.append(f"{line}: powerlaw's maximum is the higher")
            continue
        if l_ours - l_peer > 0.01:
            continue  # powerlaw's optimiser stopped short; nothing more to compare
        compared += 1
        r_ours = ours["normalised_ratio"]
        if abs(r_ours - r_peer) > 2e-3 * abs(r_peer) + 2e-3:
            failures.append(f"{line}: normalised ratios differ")
        lp_ours, lp_peer = math.log(ours["p"]), math.log(p_peer)
        if abs(lp_ours - lp_peer) > 0.02 * abs(lp_peer) + 0.01:
            failures.append(f"{line}: p-values differ")
if compared < 0.75 * total:
    failures.append(f"only {compared} of {total} comparisons had the same maximum in both")
if failures:
    print("\n".join(["FAILED:"] + failures), file=sys.stderr)
    sys.exit(1)
print(f"powerlaw agrees: α at {len(rows)} loads, {compared} of {total} ratio tests compared")
