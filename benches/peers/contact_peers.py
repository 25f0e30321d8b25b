"""Side-by-side contact sweeps: wearcoef vs Tamaas (PyPI) on the same surfaces.

For each N: wearcoef generates a surface (H = 0.8, lambda_l = N/4, lambda_s = 8 grid
spacings, unit rms slope); both codes solve the same 30-load sweep, W/W0 log-spaced in
[0.001, 0.06], warm-started, tolerance TOL on each code's own error (ours is never smaller
than Tamaas's at the same state, so equal tolerances favour Tamaas). Each solve runs in its
own process, which reports its own peak resident memory (VmHWM, reset at exec, unlike
ru_maxrss which keeps the forking parent's pages); the memory of the same program at N/2 is
subtracted, so that the memory reported is the marginal cost per grid node, in units of N²
doubles (fixed costs such as the binary or the interpreter cancel). Ours is the least peak
of three runs at each size (the peaks vary by about ±0.3 MB between runs, which matters at
256²); Tamaas's is one run.

Usage: python contact_peers.py WEARCOEF_BIN OUTDIR [N ...]
Prints a markdown table.

Also: python contact_peers.py --alternate OLD_BIN NEW_BIN OUTDIR ROUNDS [N ...] (used by
benches/peers/alternate.sh): per N, Tamaas once, then the two binaries' 1-thread sweeps in
turn, ROUNDS each, on the same surface; prints each binary's least and median time against
Tamaas's, NEW's median over OLD's, and whether both did the same iterations and pixel counts.

Also: python contact_peers.py --tamaas-maps SURFACE.npy TOL W1,W2,... OUT.u8 (used by
`make speed-accuracy`): solves the sweep with Tamaas, writes the contact maps (one byte per
node, load-major, 1 = contact) to OUT.u8 and prints the seconds of the solves as JSON.
"""
import json
import os
import subprocess
import sys
import time

import numpy as np

TOL = 1e-8
LOADS = np.exp(np.linspace(np.log(0.001), np.log(0.06), 30))


def peak_rss_bytes():
    """This process's peak resident memory (VmHWM)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    return None


def run_child(args, env=None):
    """Run a command printing a JSON list of per-load rows; return (rows, peak memory)."""
    proc = subprocess.run(args, capture_output=True, env=env)
    if proc.returncode != 0:
        raise RuntimeError(f"{args[0]} failed: {proc.stderr.decode()[-2000:]}")
    rows = json.loads(proc.stdout)
    return rows, max(r["peak_rss_bytes"] for r in rows)


def tamaas_model(path):
    """Tamaas model of the surface at `path` (E* = 1) and the surface's spectral rms slope
    (as wearcoef computes it, for W0 = E* rms slope L²)."""
    import tamaas as tm

    h = np.load(path)
    n = h.shape[0]
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [1.0, 1.0], [n, n])
    model.E, model.nu = 1.0, 0.0
    return h, n, model, rms_slope(h)


def rms_slope(h):
    """The spectral rms slope of `h` on the unit box (as wearcoef computes it)."""
    n = h.shape[0]
    q = 2 * np.pi * np.fft.fftfreq(n, 1.0 / n)
    qx, qy = np.meshgrid(q, q)
    return np.sqrt(np.sum((qx**2 + qy**2) * np.abs(np.fft.fft2(h)) ** 2) / n**4)


def tamaas_child(path, tol):
    """Solve the sweep with Tamaas in this process; print JSON."""
    import tamaas as tm

    h, n, model, slope = tamaas_model(path)
    solver = tm.PolonskyKeerRey(model, h, tol)
    solver.max_iter = 5000
    # Iterations are only printed by Tamaas's logger (C level); capture fd 1 and 2.
    log = os.open(path + ".tamaas.log", os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    saved = os.dup(1), os.dup(2)
    rows = []
    for w in LOADS:
        os.dup2(log, 1)
        os.dup2(log, 2)
        start = time.perf_counter()
        err = solver.solve(w * model.E_star * slope)
        seconds = time.perf_counter() - start
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        rows.append({"w_over_w0": w, "seconds": seconds, "error": err,
                     "n_contact_px": int((model.traction > 0).sum())})
    os.close(log)
    # The log holds, per solve, a header and lines "iter cost error"; the last line of
    # each solve carries its final iteration count.
    iters, last = [], None
    with open(path + ".tamaas.log") as f:
        for line in f:
            parts = line.split()
            if parts[:1] == ["Iter"]:
                if last is not None:
                    iters.append(last)
                last = None
            elif len(parts) == 3 and parts[0].isdigit():
                last = int(parts[0])
    iters.append(last)
    for row, it in zip(rows, iters):
        row["iterations"] = it
        row["converged"] = row["error"] <= tol
        row["peak_rss_bytes"] = peak_rss_bytes()
    print(json.dumps(rows))


def tamaas_maps(path, tol, loads, out):
    """Tamaas's contact maps of a warm-started sweep (see the module docstring)."""
    import tamaas as tm

    h, n, model, slope = tamaas_model(path)
    solver = tm.PolonskyKeerRey(model, h, tol)
    solver.max_iter = 20000
    devnull = os.open(os.devnull, os.O_WRONLY)
    saved = os.dup(1)
    seconds, maps = 0.0, []
    for w in loads:
        os.dup2(devnull, 1)
        start = time.perf_counter()
        err = solver.solve(w * model.E_star * slope)
        seconds += time.perf_counter() - start
        os.dup2(saved, 1)
        if not err <= tol:
            raise SystemExit(f"Tamaas did not converge at W/W0 = {w}: error {err} > {tol}")
        maps.append((np.asarray(model.traction) > 0).astype(np.uint8).reshape(n, n))
    np.stack(maps).tofile(out)
    print(json.dumps({"seconds": seconds}))


def make_surface(wearcoef, outdir, n):
    path = os.path.join(outdir, f"surface_{n}.npy")
    subprocess.run([wearcoef, "surface", "--n", str(n), "--lambda-l-px", str(max(n // 4, 16)),
                    "--lambda-s-px", "8", "--hurst", "0.8", "--seed", "1", "-o", path],
                   check=True)
    return path


def alternate(old, new, outdir, rounds, sizes):
    """Two wearcoef binaries against one Tamaas run per size, in turn (module docs)."""
    import statistics
    import tamaas

    os.makedirs(outdir, exist_ok=True)
    loads = ",".join(repr(float(w)) for w in LOADS)
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    print(f"Tamaas {tamaas.__version__} (1 thread) against two wearcoef binaries in turn, "
          f"{rounds} rounds each; 30 loads, tol {TOL:g}\n")
    print("| N | old: least / median ratio | new: least / median ratio | new / old (medians) "
          "| new / old (least) | same iterations and pixel counts |")
    print("|---|---|---|---|---|---|")
    for n in sizes:
        path = make_surface(new, outdir, n)
        rt, _ = run_child([sys.executable, __file__, "--tamaas-child", path, repr(TOL)])
        assert all(r["converged"] for r in rt), "Tamaas did not converge"
        tt = sum(r["seconds"] for r in rt)
        times = {old: [], new: []}
        shape = {}
        for _ in range(rounds):
            for b in (old, new):
                rows, _ = run_child([b, "solve", "--surface", path, "--loads", loads,
                                     "--tol", repr(TOL), "--json"], env)
                assert all(r["converged"] for r in rows), f"{b} did not converge"
                times[b].append(sum(r["seconds"] for r in rows))
                shape[b] = [(r["iterations"], r["n_contact_px"]) for r in rows]
        lo = {b: min(t) / tt for b, t in times.items()}
        med = {b: statistics.median(t) / tt for b, t in times.items()}
        print(f"| {n} | {lo[old]:.4f} / {med[old]:.4f} | {lo[new]:.4f} / {med[new]:.4f} | "
              f"{med[new] / med[old]:.3f} | {lo[new] / lo[old]:.3f} | "
              f"{'yes' if shape[old] == shape[new] else 'NO'} |")
        sys.stdout.flush()


def main():
    if sys.argv[1] == "--tamaas-maps":
        tamaas_maps(sys.argv[2], float(sys.argv[3]),
                    [float(w) for w in sys.argv[4].split(",")], sys.argv[5])
        return
    if sys.argv[1] == "--tamaas-child":
        tamaas_child(sys.argv[2], float(sys.argv[3]))
        return
    if sys.argv[1] == "--alternate":
        alternate(sys.argv[2], sys.argv[3], sys.argv[4], int(sys.argv[5]),
                  [int(s) for s in sys.argv[6:]] or [256, 512, 1024])
        return
    wearcoef, outdir = sys.argv[1], sys.argv[2]
    sizes = [int(s) for s in sys.argv[3:]] or [256, 512, 1024]
    os.makedirs(outdir, exist_ok=True)
    loads = ",".join(repr(float(w)) for w in LOADS)

    def surface(n):
        path = os.path.join(outdir, f"surface_{n}.npy")
        subprocess.run([wearcoef, "surface", "--n", str(n), "--lambda-l-px", str(max(n // 4, 16)),
                        "--lambda-s-px", "8", "--hurst", "0.8", "--seed", "1", "-o", path],
                       check=True)
        return path

    def ours(path, threads):
        env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
        return run_child([wearcoef, "solve", "--surface", path, "--loads", loads,
                          "--tol", repr(TOL), "--json"], env)

    def theirs(path):
        return run_child([sys.executable, __file__, "--tamaas-child", path, repr(TOL)])

    import tamaas
    print(f"Tamaas {tamaas.__version__} (1 thread, FFTW) vs wearcoef; 30 loads W/W0 in "
          f"[0.001, 0.06], tol {TOL:g}\n")
    print("| N | ratio 1T | ratio 2T | iterations/load ours | iterations/load Tamaas | "
          "ms/iteration ours 1T | ms/iteration Tamaas | memory ours (N² doubles) | "
          "memory Tamaas (N² doubles) | max rel. diff. area | loads with equal pixel counts |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for n in sizes:
        path = surface(n)
        half = surface(n // 2)
        r1, rss1 = ours(path, 1)
        r2, _ = ours(path, 2)
        rt, rsst = theirs(path)
        _, rss1_half = ours(half, 1)
        _, rsst_half = theirs(half)
        # Our peak memory is the least of three runs at N and at N/2: at 256² the
        # difference is about 2.7 MB between processes of 12–14 MB whose peaks vary by
        # ±0.3 MB from run to run (allocator and thread start-up), which alone moved the
        # figure between 6.2 and 7.2. Tamaas's sweeps are too long to repeat.
        rss1 = min([rss1] + [ours(path, 1)[1] for _ in range(2)])
        rss1_half = min([rss1_half] + [ours(half, 1)[1] for _ in range(2)])
        assert all(r["converged"] for r in r1 + r2), "wearcoef did not converge"
        assert all(r["converged"] for r in rt), "Tamaas did not converge"
        t1 = sum(r["seconds"] for r in r1)
        t2 = sum(r["seconds"] for r in r2)
        tt = sum(r["seconds"] for r in rt)
        it1 = sum(r["iterations"] for r in r1)
        itt = sum(r["iterations"] for r in rt)
        diff = max(abs(a["n_contact_px"] - b["n_contact_px"]) / b["n_contact_px"] for a, b in zip(r1, rt))
        equal = sum(a["n_contact_px"] == b["n_contact_px"] for a, b in zip(r1, rt))
        mem = lambda big, small: (big - small) / (8 * (n * n - (n // 2) ** 2))
        print(f"| {n} | {t1 / tt:.3f} | {t2 / tt:.3f} | {it1 / len(r1):.1f} | {itt / len(rt):.1f} | "
              f"{t1 / it1 * 1e3:.2f} | {tt / itt * 1e3:.2f} | {mem(rss1, rss1_half):.1f} | "
              f"{mem(rsst, rsst_half):.1f} | {diff:.2e} | {equal}/{len(r1)} |")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
