"""Pressure-ceiling contact side by side: wearcoef `solve --hardness` against Tamaas's
`KatoSaturated` (PyPI) on the same surface, the same ceiling and the same loads, one thread
each, in one run.

The surface: wearcoef's generator, N², H = 0.8, lambda_l = N/4, lambda_s = 8 grid spacings,
seed 1 (as `make bench-peers`). The ceiling: `hardness` in units of E*·rms slope (the units of
W/W0), so p_max = hardness·E*·slope for both codes. Both sweep the loads in order, warm-started
(Tamaas keeps its solver object, whose pressure is the next load's start). Tolerance 1e-8 on
each code's own error; since `KatoSaturated.solve()` may return 0.0 without having converged,
its final state is also measured by our error (docs/CONVENTIONS.md, under a hardness), from
its pressure and displacement. Compared per load: the time, our error of both states, and the
nodes whose contact (p > 0) or saturation (p = p_max) differ between the two.

With `--cm-python PYTHON` (an interpreter with ContactMechanics 1.8.3 from PyPI): also
ContactMechanics' plastic system (`PlasticNonSmoothContactSystem` on a
`PlasticTopography`, built directly: `make_system` is not used) at each load, from a fresh
system (its plastic displacement accumulates over solves; ours is the displacement of one
load), force-controlled, pentol 1e-10 σ_h: the nodes in contact or saturated in one code
only, the largest pressure difference over 𝓗, and the largest difference of the plastic
displacements over ours (ContactMechanics stores it as a negative height change).

Also, for the same surface: a 30-load warm sweep (W/W0 from 0.005 to 0.15) with and without
the ceiling, ours only: the cost of the ceiling against the elastic sweep.

Usage: python plastic_peers.py WEARCOEF_BIN OUTDIR N HARDNESS W1,W2,... [--cm-python PYTHON]
Prints a markdown table.
"""
import json
import os
import subprocess
import sys
import time

import numpy as np

# The surface's spectral rms slope and Tamaas's model of it, as the elastic peer bench has them.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from contact_peers import rms_slope, tamaas_model  # noqa: E402

TOL = 1e-8


def our_error(p, u, h, pmax):
    """Our complementarity error under a ceiling (docs/CONVENTIONS.md) of a state."""
    w = u - h
    sat = p >= pmax
    level = w[~sat].min()
    work = np.sum(p[~sat] * (w[~sat] - level)) + pmax * np.sum(np.maximum(w[sat] - level, 0))
    return work / (p.sum() * h.std())


def cm_child(path, hardness, loads, out):
    """ContactMechanics' plastic system at each load (fresh each time), 1 thread: the
    pressures and plastic displacements (to `out`, load-major, two fields per load) and the
    seconds, as JSON."""
    from ContactMechanics import PeriodicFFTElasticHalfSpace
    from ContactMechanics.PlasticSystemSpecialisations import PlasticNonSmoothContactSystem
    from SurfaceTopography import Topography
    from SurfaceTopography.Special import PlasticTopography

    h = np.load(path)
    n = h.shape[0]
    slope = rms_slope(h)
    pmax = hardness * slope
    rows, fields = [], []
    for w in loads:
        substrate = PeriodicFFTElasticHalfSpace((n, n), 1.0, physical_sizes=(1.0, 1.0))
        surface = PlasticTopography(Topography(h, physical_sizes=(1.0, 1.0), periodic=True), pmax)
        system = PlasticNonSmoothContactSystem(substrate, surface)
        start = time.perf_counter()
        opt = system.minimize_proxy(external_force=w * slope, pentol=1e-10 * h.std(),
                                    forcetol=1e-10, maxiter=100000)
        seconds = time.perf_counter() - start
        fields.append(np.asarray(opt.jac).reshape(n, n) * n * n)
        fields.append(np.asarray(surface.plastic_displ).reshape(n, n))
        rows.append({"seconds": seconds, "success": bool(opt.success), "pmax": pmax})
    np.stack(fields).tofile(out)
    print(json.dumps(rows))


def plastic_displacement(p, h, saturated):
    """Our plastic displacement of a solved field with its saturated nodes
    (docs/CONVENTIONS.md), E* = 1."""
    n = h.shape[0]
    f = np.fft.fftfreq(n, 1.0 / n)
    k = 2 * np.pi * np.sqrt(np.add.outer(f**2, f**2))
    kernel = np.where(k > 0, 2.0 / np.where(k > 0, k, 1.0), 0.0)
    w = np.real(np.fft.ifft2(np.fft.fft2(p) * kernel)) - h
    return np.where(saturated, w[~saturated].min() - w, 0.0)


def tamaas_child(path, hardness, loads, out):
    """Kato-saturated sweep in this process (1 thread): per load its time, its own error,
    the pressures (to `out`, load-major) and our error of its state, as JSON."""
    import tamaas as tm

    h, n, model, slope = tamaas_model(path)
    pmax = hardness * model.E_star * slope
    solver = tm.KatoSaturated(model, h, TOL, pmax)
    solver.max_iter = 20000
    devnull = os.open(os.devnull, os.O_WRONLY)
    saved = os.dup(1), os.dup(2)
    rows, fields = [], []
    for w in loads:
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        start = time.perf_counter()
        err = solver.solve(w * model.E_star * slope)
        seconds = time.perf_counter() - start
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        p = np.array(model.traction).reshape(n, n)
        u = np.array(model.displacement).reshape(n, n)
        fields.append(p)
        rows.append({"seconds": seconds, "own_error": err,
                     "our_error": our_error(p, u, h, pmax), "pmax": pmax})
    np.stack(fields).tofile(out)
    print(json.dumps(rows))


def main():
    if sys.argv[1] == "--cm-child":
        cm_child(sys.argv[2], float(sys.argv[3]),
                 [float(w) for w in sys.argv[4].split(",")], sys.argv[5])
        return
    if sys.argv[1] == "--tamaas-child":
        tamaas_child(sys.argv[2], float(sys.argv[3]),
                     [float(w) for w in sys.argv[4].split(",")], sys.argv[5])
        return
    wearcoef, outdir, n, hardness, loads = sys.argv[1:6]
    cm_python = sys.argv[7] if len(sys.argv) > 7 and sys.argv[6] == "--cm-python" else None
    n, hardness = int(n), float(hardness)
    loads = [float(w) for w in loads.split(",")]
    os.makedirs(outdir, exist_ok=True)
    path = os.path.join(outdir, f"surface_{n}.npy")
    subprocess.run([wearcoef, "surface", "--n", str(n), "--lambda-l-px", str(max(n // 4, 16)),
                    "--lambda-s-px", "8", "--hurst", "0.8", "--seed", "1", "-o", path],
                   check=True, capture_output=True)
    h = np.load(path)
    one = dict(os.environ, RAYON_NUM_THREADS="1", OMP_NUM_THREADS="1")

    def ours(sweep, extra, out=None):
        args = [wearcoef, "solve", "--surface", path, "--loads",
                ",".join(repr(w) for w in sweep), "--tol", repr(TOL), "--json", *extra]
        if out:
            args += ["--pressure-out", out]
        proc = subprocess.run(args, capture_output=True, env=one, check=True)
        return json.loads(proc.stdout)

    mine = os.path.join(outdir, "ours.npy")
    r_ours = ours(loads, ["--hardness", repr(hardness)], mine)
    theirs_out = os.path.join(outdir, "kato.f64")
    proc = subprocess.run([sys.executable, __file__, "--tamaas-child", path, repr(hardness),
                           ",".join(repr(w) for w in loads), theirs_out],
                          capture_output=True, env=one, check=True)
    r_kato = json.loads(proc.stdout)
    p_ours = np.load(mine).reshape(len(loads), n, n)
    p_kato = np.fromfile(theirs_out).reshape(len(loads), n, n)

    import tamaas
    print(f"Tamaas {tamaas.__version__} KatoSaturated vs wearcoef solve --hardness {hardness:g}; "
          f"{n}², 1 thread each, tol {TOL:g}\n")
    print("| W/W0 | p̄/𝓗 | seconds ours | seconds Kato | ratio | our error, ours | "
          "our error, Kato | Kato's own error | contact nodes | saturated nodes | "
          "nodes in contact in one only | nodes saturated in one only |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    total_ours = total_kato = 0.0
    for k, w in enumerate(loads):
        a, b = r_ours[k], r_kato[k]
        pmax = b["pmax"]
        mine_k, theirs_k = p_ours[k], p_kato[k]
        # Saturated: at the ceiling to rounding (Tamaas clamps to pmax computed in its units).
        sat_a = mine_k >= pmax * (1 - 1e-12)
        sat_b = theirs_k >= pmax * (1 - 1e-12)
        total_ours += a["seconds"]
        total_kato += b["seconds"]
        print(f"| {w:g} | {w / hardness:.3f} | {a['seconds']:.3f} | {b['seconds']:.1f} | "
              f"1/{b['seconds'] / a['seconds']:.0f} | {a['error']:.1e} | {b['our_error']:.1e} | "
              f"{b['own_error']:.1e} | {int((mine_k > 0).sum())} | {int(sat_a.sum())} | "
              f"{int(((mine_k > 0) != (theirs_k > 0)).sum())} | {int((sat_a != sat_b).sum())} |")
    print(f"\nTotal: ours {total_ours:.3f} s, Kato {total_kato:.1f} s: "
          f"1/{total_kato / total_ours:.0f}.")

    if cm_python:
        cm_out = os.path.join(outdir, "cm.f64")
        proc = subprocess.run([cm_python, __file__, "--cm-child", path, repr(hardness),
                               ",".join(repr(w) for w in loads), cm_out],
                              capture_output=True, env=one, check=True)
        r_cm = json.loads(proc.stdout)
        cm = np.fromfile(cm_out).reshape(len(loads), 2, n, n)
        print("\nContactMechanics' plastic system against ours, same surface, ceiling and loads:\n")
        print("| W/W0 | seconds ours | seconds ContactMechanics | converged | "
              "nodes in contact in one only | nodes saturated in one only | "
              "max pressure difference / 𝓗 | max plastic-displacement difference / ours |")
        print("|---|---|---|---|---|---|---|---|")
        for k, w in enumerate(loads):
            pmax = r_cm[k]["pmax"]
            mine_k, (theirs_k, their_plastic) = p_ours[k], cm[k]
            sat_a = mine_k >= pmax * (1 - 1e-12)
            sat_b = theirs_k >= pmax * (1 - 1e-9)
            plastic = plastic_displacement(mine_k, h, sat_a)
            worst = np.abs(-their_plastic - plastic).max() / plastic.max()
            print(f"| {w:g} | {r_ours[k]['seconds']:.3f} | {r_cm[k]['seconds']:.2f} | "
                  f"{r_cm[k]['success']} | {int(((mine_k > 0) != (theirs_k > 0)).sum())} | "
                  f"{int((sat_a != sat_b).sum())} | {np.abs(mine_k - theirs_k).max() / pmax:.1e} | "
                  f"{worst:.1e} |")

    sweep = [0.005 * (i + 1) for i in range(30)]
    cap = [w for w in sweep if w <= hardness]
    best = lambda extra: min(sum(r["seconds"] for r in ours(cap, extra)) for _ in range(3))
    elastic, capped = best([]), best(["--hardness", repr(hardness)])
    print(f"\n{len(cap)}-load warm sweep (W/W0 0.005 … {cap[-1]:g}), ours, 1 thread, least of 3: "
          f"elastic {elastic:.3f} s, hardness {hardness:g} {capped:.3f} s: {capped / elastic:.2f}×.")


if __name__ == "__main__":
    main()
