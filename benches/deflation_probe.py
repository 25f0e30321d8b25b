"""Where the preconditioned iteration's count grows with the box: a probe on a fixed contact set.

`make bench-deflation-probe` (arguments: the wearcoef binary, a work directory, then box sizes
L/λ_l). For each box it makes the paper spectrum's surface (λ_l = 1024 Δl, λ_s = 8 Δl, H = 0.8,
seed 3128, n = 1024·L/λ_l) and its contact set F at W/W0 = 0.02 with `wearcoef surface` and
`wearcoef solve` (a 2-load sweep, tol 1e-8), then solves the linear problem the solver's last
phase solves, on that fixed F: minimise ½⟨p, K p⟩ − ⟨p, h⟩ over p supported on F with a fixed
mean, by conjugate gradients to a relative residual of 1e-8, with

- M = P K⁻¹ P, the solver's preconditioner (P: restrict to F, centre);
- the same M deflated by block indicators on F (blocks of 256² nodes, the balancing
  Neumann–Neumann form M_D = (I − Q A) M (I − A Q) + Q, Q = Z E⁺ Zᵀ, E = Zᵀ A Z, with A Z
  computed exactly, one convolution per block);
- an orthogonal two-level split, (I − Π) M (I − Π) + Z E⁺ Zᵀ (Π: block means on F), which
  needs no A Z in its application;
- an additive two-level preconditioner, M + P Z E⁺ Zᵀ (the coarse correction added to M's
  action, as in additive Schwarz), which needs only E, not A Z, in its application.

It prints the iteration counts; it is a probe of where the count grows, not a solver (A Z costs
one convolution per block).
"""
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from solver_replica import Operator, coarse_space, deflated, free_set_operators


def contact_set(wearcoef, work, boxes):
    n = 1024 * boxes
    surface = work / f"surface_{n}.npy"
    contact = work / f"contact_{n}.npy"
    if not contact.exists():
        subprocess.run([wearcoef, "surface", "--n", str(n), "--lambda-l-px", "1024",
                        "--lambda-s-px", "8", "--hurst", "0.8", "--seed", "3128",
                        "-o", str(surface)], check=True)
        subprocess.run([wearcoef, "solve", "--surface", str(surface), "--loads", "0.005,0.02",
                        "--tol", "1e-8", "--contact-out", str(contact), "--json"], check=True,
                       stdout=subprocess.DEVNULL)
    return np.load(surface), np.load(contact)[-1].astype(bool)


def probe(h, F):
    n = h.shape[0]
    op = Operator(n)
    P, A, M = free_set_operators(op, F)

    b = P(h - op.conv(np.where(F, 1.0, 0.0), op.k_hat))

    def pcg(precondition, tol=1e-8, maxit=2000):
        x = np.zeros_like(b)
        r = b.copy()
        z = precondition(r)
        d = z.copy()
        rz = np.vdot(r, z)
        for it in range(1, maxit + 1):
            ad = A(d)
            a = rz / np.vdot(d, ad)
            x += a * d
            r -= a * ad
            if np.linalg.norm(r) < tol * np.linalg.norm(b):
                return it
            z = precondition(r)
            rz_new = np.vdot(r, z)
            d = z + (rz_new / rz) * d
            rz = rz_new
        return maxit

    coarse = coarse_space(op, F)
    idx, Z, _, E_inv = coarse
    counts = Z.sum(axis=1)
    pos = np.argmax(Z, axis=0)

    def block_means(r):
        return op.full(idx, ((Z @ r.ravel()[idx]) / counts)[pos])

    def orthogonal(r):
        s = M(r - block_means(r))
        y = E_inv @ (Z @ r.ravel()[idx])
        return P(s - block_means(s) + op.full(idx, Z.T @ y))

    def additive(r):
        y = E_inv @ (Z @ r.ravel()[idx])
        return M(r) + P(op.full(idx, Z.T @ y))

    return {
        "n": n,
        "contact_fraction": len(idx) / n / n,
        "blocks": len(counts),
        "preconditioned": pcg(M),
        "deflated": pcg(lambda r: deflated(op, M, P, coarse, r)),
        "two_level_orthogonal": pcg(orthogonal),
        "two_level_additive": pcg(additive),
    }


def main():
    wearcoef, work = sys.argv[1], Path(sys.argv[2])
    work.mkdir(parents=True, exist_ok=True)
    rows = []
    for boxes in [int(b) for b in sys.argv[3:]]:
        start = time.time()
        h, F = contact_set(wearcoef, work, boxes)
        row = {"l_over_lambda_l": boxes, **probe(h, F), "seconds": round(time.time() - start, 1)}
        print(json.dumps(row), flush=True)
        rows.append(row)
    print("| L/λ_l | n | contact fraction | blocks of 256² | M = P K⁻¹ P | deflated "
          "| orthogonal two-level | additive two-level |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['l_over_lambda_l']} | {r['n']} | {r['contact_fraction']:.4f} | {r['blocks']} "
              f"| {r['preconditioned']} | {r['deflated']} | {r['two_level_orthogonal']} "
              f"| {r['two_level_additive']} |")


if __name__ == "__main__":
    main()
