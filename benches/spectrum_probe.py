"""Which modes limit the preconditioned iteration on a fixed contact set: a Lanczos probe.

Usage (numpy and scipy, e.g. the interpreter `bash benches/venv.sh numpy scipy` prints):

    wearcoef surface --n 2048 --lambda-l-px 1024 --lambda-s-px 8 --hurst 0.8 --seed 3128 -o h.npy
    wearcoef solve --surface h.npy --loads 0.0522,0.06 --tol 1e-8 --contact-out c.npy
    python benches/spectrum_probe.py h.npy c.npy [--preconditioner M|E] [--rhs heights|random]

Takes the last load's contact set F from CONTACT (a (loads, n, n) or (n, n) 0/1 array) and
solves the linear problem of the solver's last phase on that fixed F (A = P K P, P: restrict
to F and centre; right-hand side P h, or a random field with `--rhs random`) by conjugate
gradients preconditioned with M = P K⁻¹ P (`M`) or with the solver's free-set extension
M_E = P Eᵀ K⁻¹ E P (`E`, γ = 0.5, a Gaussian of σ = 32 nodes on the fine grid, D ≥ 0.05, as
`solver_replica.py --extend 32`) to a relative residual of 1e-8; `--edge-scale s` uses
S M S instead, S scaling F's edge nodes (nodes of F with a neighbour off F) by s;
`--ring-blocks B` deflates the preconditioner (balancing form, A Z exact) by the
ring-minus-core pattern (1 on each cluster's edge nodes, minus the edge-to-interior count
ratio on its interior) cut into B × B blocks. From the conjugate gradient's
coefficients it builds the Lanczos matrix of the preconditioned operator and prints one JSON
line with the iterations and its Ritz values (the extremes, and how many lie above 2 and
10), then one per extreme Ritz vector (a pressure field on F) describing it: the fraction of
its energy on F's edge nodes (nodes of F with a neighbour off F) against their share of F,
the fraction that is constant per cluster (8-neighbour clusters, not periodic), and how
that per-cluster part spreads over wavelengths (in grid nodes), and how the vector's energy
density (its square) does, the energy share of the clusters whose edge mean exceeds their
interior mean and the vector's correlation with the ring-minus-core pattern (how coherent
an edge-against-core loading is across clusters), its participation ratio (Σv²)² / (|F| Σv⁴) (near 1 when spread
evenly over F, small when localised) and the share of its energy in the most loaded block of
256² nodes (n a multiple of 256).

`--block-deflate B` deflates the preconditioner (balancing form, A Z exact, one convolution
per block) by the indicators of F on blocks of B × B nodes, each centred on F (one dropped:
they sum to 0), the coarse space of benches/deflation_probe.py, there tried with M alone:
how much of what remains with the extension a coarse space of the blocks' loads takes away.
The coarse vectors and their A Z are kept in single precision. `--model-cell C` replaces
A Z by a model that needs no fine convolution per block: the deflection under the block's
load averaged over cells of C × C nodes (P K Π P, Π the cell average), its output
interpolated bilinearly between the cells' centres (`--model-output bilinear`, the
default; `cells`: the cells' staircase; `fine`: K Π on the fine grid), plus the local
field K (1_F − Π 1_F) of F inside the cells scaled by the block's value (left out with
`--no-local`); E = Zᵀ W from the same model. The solver's own form of it is
`Extension::coarse_block` (crates/core/src/contact/solver/deflation.rs).

`--cells C` smooths the extension on cells of C × C nodes as the solver does (default 1:
on the fine grid), and `--near SIGMA,WEIGHT` adds the solver's near term (a second
Gaussian of SIGMA nodes and weight WEIGHT; the solver's is 6,0.3 with `--cells 8`).

`--ritz-deflate K1,K2,…` then asks how far a recycled coarse space could go: the K largest
Ritz vectors of this solve (right eigenvectors of the preconditioned operator, as far as
the Lanczos matrix has found them) deflate the preconditioner (balancing form, A Z exact),
and the same fixed-F problem with another right-hand side (a random field) is solved
without and with each deflation; one JSON line per K gives the iterations. Since the Ritz
vectors come from the same operator, this bounds from above what vectors recycled from the
previous load of a sweep (another contact set) could give.
"""
import argparse
import json

import numpy as np
import scipy.fft as sf
from scipy import ndimage

from solver_replica import Operator, extended_preconditioner, free_set_operators


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("surface")
    ap.add_argument("contact")
    ap.add_argument("--preconditioner", choices=["M", "E"], default="E")
    ap.add_argument("--rhs", choices=["heights", "random"], default="heights")
    ap.add_argument("--max-iterations", type=int, default=300)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--edge-scale", type=float, default=1.0)
    ap.add_argument("--ring-blocks", type=int, default=0)
    ap.add_argument("--block-deflate", type=int, default=0)
    ap.add_argument("--model-cell", type=int, default=0)
    ap.add_argument("--model-output", choices=["cells", "bilinear", "fine"], default="bilinear")
    ap.add_argument("--no-local", action="store_true")
    ap.add_argument("--ritz-deflate", default="")
    ap.add_argument("--cells", type=int, default=1)
    ap.add_argument("--near", default="")
    args = ap.parse_args()
    h = np.load(args.surface)
    contact = np.load(args.contact)
    F = (contact[-1] if contact.ndim == 3 else contact).astype(bool)
    n = h.shape[0]
    op = Operator(n, args.workers)

    P, A, plain = free_set_operators(op, F)
    terms = [(32.0, 0.5, 0.05, args.cells)]
    if args.near:
        sigma, weight = (float(v) for v in args.near.split(","))
        terms.append((sigma, weight, 0.05, args.cells))
    extended = extended_preconditioner(op, F, P, terms)

    edge = F & ~ndimage.binary_erosion(F, structure=np.ones((3, 3)))
    scale = np.where(edge, args.edge_scale, 1.0)

    def M(x):
        # S M S with S = diag(scale): 1 inside F, --edge-scale on its edge nodes.
        return P(scale * unscaled(P(scale * x)))

    def unscaled(x):
        return plain(x) if args.preconditioner == "M" else extended(P(x))

    # The ring-minus-core pattern: 1 on each cluster's edge nodes, −(edge/interior count) on
    # its interior (0 on clusters without interior), so each cluster's sum is 0.
    labels, clusters = ndimage.label(F, structure=np.ones((3, 3)))
    ids = np.arange(1, clusters + 1)
    interior = F & ~edge
    n_edge = ndimage.sum(edge, labels, ids)
    n_interior = ndimage.sum(interior, labels, ids)
    ring = np.zeros((n, n))
    ring[edge] = 1.0
    ring[interior] = -(n_edge / np.maximum(n_interior, 1))[labels[interior] - 1]
    ring[np.isin(labels, ids[n_interior < 1])] = 0.0
    if args.ring_blocks > 0:
        M = deflate(M, A, P, block_space(ring, n, args.ring_blocks, P))
    if args.block_deflate > 0:
        # The centred indicators sum to P 1_F = 0: one of them is dropped.
        blocks = block_space(F.astype(np.float64), n, n // args.block_deflate, P)[:-1]
        model = A
        if args.model_cell > 0:
            model = cell_model(op, P, args.model_cell, args.model_output)
            if not args.no_local:
                model = local_model(op, P, F, model, args.model_cell, args.block_deflate)
        M = deflate(M, model, P, blocks, np.float32)

    b = P(h) if args.rhs == "heights" else P(np.random.default_rng(1).standard_normal((n, n)))
    alphas, betas, zs, rzs = conjugate_gradients(A, M, b, args.max_iterations)
    k = len(alphas)
    T = np.zeros((k, k))
    for j in range(k):
        T[j, j] = 1 / alphas[j] + (betas[j - 1] / alphas[j - 1] if j > 0 else 0.0)
        if j + 1 < k:
            T[j, j + 1] = T[j + 1, j] = np.sqrt(betas[j]) / alphas[j]
    ritz, vectors = np.linalg.eigh(T)

    def ritz_vector(column):
        # Right eigenvector of M A: Σ_j s_j z_j / sqrt(r_j·z_j).
        v = sum(vectors[j, column] * zs[j].astype(np.float64) / np.sqrt(rzs[j]) for j in range(k))
        return np.where(F, v, 0.0)

    if args.ritz_deflate:
        other = P(np.random.default_rng(2).standard_normal((n, n)))
        base = len(conjugate_gradients(A, M, other, args.max_iterations)[0])
        for count in (int(c) for c in args.ritz_deflate.split(",")):
            space = [P(ritz_vector(k - 1 - j)) for j in range(count)]
            deflated = deflate(M, A, P, space)
            iterations = len(conjugate_gradients(A, deflated, other, args.max_iterations)[0])
            print(json.dumps({
                "n": n, "preconditioner": args.preconditioner, "ritz_vectors": count,
                "ritz_values": ritz[k - count:].tolist(), "iterations_random_rhs": iterations,
                "undeflated": base,
            }))
    print(json.dumps({
        "n": n, "preconditioner": args.preconditioner, "contact_fraction": float(F.mean()),
        "iterations": k, "ritz_min": ritz[:3].tolist(), "ritz_max": ritz[-3:].tolist(),
        "ritz_above_2": int(np.sum(ritz > 2)), "ritz_above_10": int(np.sum(ritz > 10)),
    }))
    wavelength = np.where(op.q > 0, n / np.where(op.q > 0, op.q, 1.0), np.inf)
    weights = np.full(op.q.shape, 2.0)
    weights[:, 0] = 1.0
    for name, column in (("largest", -1), ("smallest", 0)):
        v = ritz_vector(column)
        energy = np.sum(v**2)
        per_cluster = np.zeros_like(v)
        per_cluster[F] = ndimage.mean(v, labels, index=np.arange(1, clusters + 1))[labels[F] - 1]
        def by_wavelength(field):
            power = weights * np.abs(sf.rfft2(field - field.mean())) ** 2
            bands, low = {}, 0
            for high in (4, 16, 64, 256, 1024, np.inf):
                inside = (wavelength >= low) & (wavelength < high)
                bands[f"{low:g}-{high:g}"] = round(float(power[inside].sum() / power.sum()), 3)
                low = high
            return bands
        print(json.dumps({
            "ritz_vector": name, "energy_on_edge_nodes": round(float(np.sum(v[edge] ** 2) / energy), 3),
            "edge_nodes_share_of_F": round(float(edge.sum() / F.sum()), 3),
            "constant_per_cluster": round(float(np.sum(per_cluster**2) / energy), 3),
            "per_cluster_part_by_wavelength_nodes": by_wavelength(per_cluster),
            "energy_density_by_wavelength_nodes": by_wavelength(v**2),
            "edge_above_core_energy_share": round(edge_above_core(v, labels, ids, edge,
                                                                   interior, n_interior), 3),
            "correlation_with_ring_pattern": round(float(
                np.sum(v * ring) / np.sqrt(energy * np.sum(ring**2))), 3),
            "participation_ratio": round(float(energy**2 / (F.sum() * np.sum(v**4))), 4),
            "largest_256_block_energy_share": round(float(
                (v**2).reshape(n // 256, 256, n // 256, 256).sum(axis=(1, 3)).max() / energy), 3),
        }))


def conjugate_gradients(A, M, b, max_iterations):
    """Preconditioned conjugate gradients on A x = b from 0 until r·z falls by 1e-16 (a
    relative residual of about 1e-8); returns the coefficients α, β and, per iteration, z
    (f32) and r·z, from which the Lanczos matrix and Ritz vectors follow."""
    r = b.copy()
    z = M(r)
    d = z.copy()
    rz = np.sum(r * z)
    rz0 = rz
    alphas, betas, zs, rzs = [], [], [], []
    while len(alphas) < max_iterations and rz > 1e-16 * rz0:
        zs.append(z.astype(np.float32))
        rzs.append(rz)
        Ad = A(d)
        alpha = rz / np.sum(d * Ad)
        r -= alpha * Ad
        z = M(r)
        rz_new = np.sum(r * z)
        alphas.append(alpha)
        betas.append(rz_new / rz)
        rz = rz_new
        d = z + betas[-1] * d
    return alphas, betas, zs, rzs


def edge_above_core(v, labels, ids, edge, interior, n_interior):
    """Energy share of v, over the clusters with an interior, of those whose mean over their
    edge nodes exceeds the mean over their interior."""
    energy = ndimage.sum(v**2, labels, ids)
    edge_mean = ndimage.sum(np.where(edge, v, 0.0), labels, ids) / np.maximum(
        ndimage.sum(edge, labels, ids), 1)
    core_mean = ndimage.sum(np.where(interior, v, 0.0), labels, ids) / np.maximum(n_interior, 1)
    keep = n_interior >= 1
    return float(np.sum(energy[keep] * (edge_mean > core_mean)[keep]) / np.sum(energy[keep]))


def block_space(field, n, blocks, P):
    """`field` (the ring pattern, or F's indicator) cut into blocks × blocks equal blocks,
    each centred on F (the empty ones dropped)."""
    side = n // blocks
    space = []
    for i in range(blocks):
        for j in range(blocks):
            z = np.zeros((n, n))
            cut = (slice(i * side, (i + 1) * side), slice(j * side, (j + 1) * side))
            z[cut] = field[cut]
            z = P(z)
            if np.any(z):
                space.append(z)
    return space


def cell_model(op, P, cell, output):
    """x ↦ P K Π P x, Π the average over cells of cell × cell nodes: the deflection under the
    cell-averaged load, on the fine grid (`fine`), averaged over the cells again (`cells`:
    P Π K Π P, the cells' staircase), or interpolated bilinearly between the cells' centres
    from those averages (`bilinear`: what the coarse grid alone can give)."""
    n, m = op.n, op.n // cell

    def average(x):
        means = x.reshape(m, cell, m, cell).mean(axis=(1, 3))
        return np.repeat(np.repeat(means, cell, axis=0), cell, axis=1)

    if output == "bilinear":
        xi = (np.arange(n) + 0.5) / cell - 0.5
        i0 = np.floor(xi).astype(int)
        w = xi - i0
        i0, i1 = i0 % m, (i0 + 1) % m

        def interpolate(x):
            means = x.reshape(m, cell, m, cell).mean(axis=(1, 3))
            rows = (1 - w)[:, None] * means[i0] + w[:, None] * means[i1]
            return (1 - w)[None, :] * rows[:, i0] + w[None, :] * rows[:, i1]

        return lambda x: P(interpolate(op.conv(average(P(x)), op.k_hat)))
    if output == "fine":
        return lambda x: P(op.conv(average(P(x)), op.k_hat))
    return lambda x: P(average(op.conv(average(P(x)), op.k_hat)))


def local_model(op, P, F, model, cell, block):
    """W x = P (model x + Y ⊙ L): the cell model plus the local field L = K (1_F − Π 1_F) of
    F's structure inside the cells, scaled by Y, the block means of x over F (for x a
    block-constant field on F, K x up to the blocks' edges)."""
    n, m, b = op.n, op.n // cell, op.n // block
    Ff = F.astype(np.float64)
    means = Ff.reshape(m, cell, m, cell).mean(axis=(1, 3))
    L = op.conv(Ff - np.repeat(np.repeat(means, cell, axis=0), cell, axis=1), op.k_hat)
    counts = Ff.reshape(b, block, b, block).sum(axis=(1, 3))

    def W(x):
        sums = np.where(F, x, 0.0).reshape(b, block, b, block).sum(axis=(1, 3))
        Y = np.where(counts > 0, sums / np.maximum(counts, 1), 0.0)
        return P(model(x) + np.repeat(np.repeat(Y, block, axis=0), block, axis=1) * L)

    return W


def deflate(M, A, P, space, dtype=np.float64):
    """The balancing form (I − Q A) M (I − A Q) + Q, Q = Z (Zᵀ A Z)⁻¹ Zᵀ, of M on the
    coarse space Z (A Z exact, one convolution per vector; both kept as `dtype`)."""
    AZ = [A(z).astype(dtype) for z in space]
    E = np.array([[np.sum(a * z, dtype=np.float64) for z in space] for a in AZ])
    space = [z.astype(dtype) for z in space]
    E_inv = np.linalg.inv(0.5 * (E + E.T))

    def combine(fields, c):
        return sum(ci * f for ci, f in zip(c, fields))

    def deflated(x):
        y = E_inv @ np.array([np.sum(z * x) for z in space])
        s = M(x - combine(AZ, y))
        v = E_inv @ np.array([np.sum(a * s) for a in AZ])
        return P(s - combine(space, v) + combine(space, y))

    return deflated


if __name__ == "__main__":
    main()
