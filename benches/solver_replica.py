"""A numpy replica of the contact solver's preconditioned iteration, to try changes to it.

Usage (with numpy and scipy, e.g. the interpreter `bash benches/venv.sh numpy scipy` prints):

    python benches/solver_replica.py N SURFACE.npy LOADS [--deflate] [--start increment]
        [--trace] [--tol 1e-10]

Solves the warm-started sweep over LOADS (W/W0, comma separated) on the heights in SURFACE
(n × n, a periodic box of side 1, E* = 1) and prints one JSON line per load (iterations,
contact fraction). The iteration is the solver's (crates/core/src/contact/solver): the free
set F (contact set and interpenetrating nodes), z = P K⁻¹ P g on F, the conjugate direction
kept unless more than 3 % of the contact set changed or it descends less than half as
steeply as z, exact line search, projection on p ≥ 0 and rescaling to the load. It differs in
bookkeeping only: u = K p is recomputed by FFT at every iteration instead of updated. On the
paper spectrum's surfaces (seed 3128, λ_l = 1024 Δl, λ_s = 8 Δl) at W/W0 = 0.0152, 0.0174,
0.02 it takes 46 / 32 / 32 iterations at 1024² where `wearcoef solve` takes 45 / 32 / 32,
and 60 / 42 / 42 at 2048² against 59 / 41 / 43.

Options:
- `--deflate`: the preconditioner deflated by indicators of 256² blocks on F (balancing
  Neumann–Neumann form, A Z recomputed by one convolution per block whenever F changes);
- `--refresh F`: with `--deflate`, rebuild the coarse space only when more than a fraction
  F of the free set changed since it was built, and in between use it restricted to the
  current free set (A Z stale on the changed nodes); 0 (the default) rebuilds at every change;
- `--start increment`: the warm start adds the load increment as K⁻¹ 1_S on the previous
  contact set S (clipped at 0) instead of scaling the previous pressure;
- `--f32-preconditioner`: z = P K⁻¹ P g computed by a single-precision FFT (the rest in
  double precision);
- `--extend SIGMA` (with `--gamma`, `--dmin`): the preconditioner's free-set extension of
  the solver (`P Eᵀ K⁻¹ E P`, `E = 1_F + γ (1 − 1_F) D⁻¹ S 1_F`, `D = max(S 1_F, dmin)`), with
  `S` a Gaussian of standard deviation SIGMA nodes on the fine grid instead of the solver's
  8² cells; 0 (the default) is `P K⁻¹ P`;
- `--long SIGMA_L` (with `--long-weight`, `--dmin-long`, `--long-settled`): with `--extend`,
  a second extension term of standard deviation SIGMA_L nodes and its own density,
  `E = 1_F + (1 − 1_F) (γ D⁻¹ S + γ_L D_L⁻¹ S_L) 1_F`, so that the weight reaches γ + γ_L for
  the longest modes; `--long-settled` uses it only after an iteration that did not restart
  (the conjugate gradient restarted when it is switched on or off);
- `--settled-fraction X`: with `--long`, use the second term only after an iteration in
  which at most a fraction X of the contact set left or entered it (the solver's near
  term: `--extend 32 --cell 8 --long 6 --long-weight 0.3 --long-cell 8 --settled-fraction
  0.002` is contact stage version 9's preconditioner);
- `--unsettled-weight W`: with `--settled-fraction`, the second term with weight W (instead of
  none) while the contact set has not settled;
- `--first-damping D`: the first step of every load shortened to D times the
  line search's;
- `--load-offset`: after an iteration that changed more than 6 nodes of the contact set,
  the load is restored by a uniform offset, `p ← max(p + c, 0)` on F with `c ≤ 0` (the
  nearest point of `{p ≥ 0, mean p = p̄}`), instead of rescaling (contact stage version 10:
  version 9's options above and `--load-offset`);
- `--cell C`, `--long-cell C`: the smoothing of the first or second term on cells of C × C
  nodes, as the solver does it (1, the default: a Gaussian on the fine grid);
- `--first-on-contact K`: the first K iterations of a warm-started load act on the contact
  set alone (no interpenetrating nodes in F);
- `--restart F`: the restart threshold (fraction of the contact set changed; 0.03);
- `--trace`: per iteration of the last load, the error and the nodes that left and entered
  the contact set.
"""
import argparse
import json

import numpy as np
import scipy.fft as sf

BLOCK = 256
RESTART_FRACTION = 0.03
DESCENT_FRACTION = 0.5


class Operator:
    """The elastic operator of a periodic box of side 1 and E* = 1 on an n × n grid, by FFT:
    û = 2 p̂ / (E* 2π|q|) for q in cycles per box side (K), and its inverse (K⁻¹); both 0 at
    q = 0."""

    def __init__(self, n, workers=2):
        self.n, self.workers = n, workers
        qx = np.fft.fftfreq(n, 1.0 / n)[:, None]
        qy = np.fft.rfftfreq(n, 1.0 / n)[None, :]
        self.q = np.sqrt(qx**2 + qy**2)
        self.k_hat = np.where(self.q > 0, 1.0 / (np.pi * np.where(self.q > 0, self.q, 1.0)), 0.0)
        self.k_inv_hat = np.pi * self.q

    def conv(self, x, multiplier):
        return sf.irfft2(sf.rfft2(x, workers=self.workers) * multiplier, s=(self.n, self.n),
                         workers=self.workers)

    def full(self, idx, values):
        """A field that is `values` at the flat indices `idx` and 0 elsewhere."""
        out = np.zeros(self.n * self.n)
        out[idx] = values
        return out.reshape(self.n, self.n)


def centring(F):
    """P of the free set F: restrict a field to F and centre it there."""

    def P(x):
        y = np.where(F, x, 0.0)
        y[F] -= y[F].mean()
        return y

    return P


def free_set_operators(op, F):
    """(P, A, M) on the free set F: the centring P, A = P K P and M = P K⁻¹ P."""
    P = centring(F)
    return P, (lambda x: P(op.conv(x, op.k_hat))), (lambda x: P(op.conv(P(x), op.k_inv_hat)))


def extended_preconditioner(op, F, P, terms):
    """The free-set extension of M: r ↦ P Eᵀ K⁻¹ E r for r on F (centred),
    E = 1_F + (1 − 1_F) Σ_j γ_j D_j⁻¹ S_j 1_F, one term per (σ_j, γ_j, D_min,j[, c_j]) of
    `terms`: S_j a Gaussian of standard deviation σ_j nodes, on the fine grid, or with a
    cell size c_j > 1 as the solver does it, S_j = U G_j Uᵀ / c_j² (Uᵀ: sums over cells of
    c_j × c_j nodes, U: the cell's value on its nodes, G_j the Gaussian on the cells);
    D_j = max(S_j 1_F, D_min,j)."""
    n = op.n
    parts = []
    for term in terms:
        sigma, weight, floor = term[:3]
        cell = int(term[3]) if len(term) > 3 else 1
        if cell <= 1:
            s_hat = np.exp(-2 * (np.pi * sigma * op.q / n) ** 2)

            def S(x, s_hat=s_hat):
                return op.conv(x, s_hat)
        else:
            m = n // cell
            qx = np.fft.fftfreq(m, 1.0 / m)[:, None]
            qy = np.fft.rfftfreq(m, 1.0 / m)[None, :]
            g_hat = np.exp(-2 * (np.pi * (sigma / cell) * np.sqrt(qx**2 + qy**2) / m) ** 2)

            def S(x, g_hat=g_hat, m=m, cell=cell):
                sums = x.reshape(m, cell, m, cell).sum(axis=(1, 3))
                smoothed = sf.irfft2(sf.rfft2(sums) * g_hat, s=(m, m))
                return np.repeat(np.repeat(smoothed, cell, axis=0), cell, axis=1) / cell**2
        parts.append((S, weight, np.maximum(S(F.astype(float)), floor)))

    def M(r):
        r_F = np.where(F, r, 0.0)
        off = 0.0
        for S, weight, density in parts:
            off = off + weight * S(r_F) / density
        y = op.conv(np.where(F, r, off), op.k_inv_hat)
        y_off = np.where(F, 0.0, y)
        back = 0.0
        for S, weight, density in parts:
            back = back + weight * S(y_off / density)
        return P(y + back)

    return M


def offset_to_load(x, F, load):
    """max(x + c, 0) on F (0 elsewhere) with the c for which it sums to `load`, from the
    values on F sorted in decreasing order (the largest k with x_(k) + c_k > 0)."""
    values = x[F]
    ordered = np.sort(values)[::-1]
    c_k = (load - np.cumsum(ordered)) / np.arange(1, len(ordered) + 1)
    c = c_k[np.nonzero(ordered + c_k > 0)[0].max()]
    out = np.zeros_like(x)
    out[F] = np.maximum(values + c, 0.0)
    return out


def coarse_space(op, F, block=BLOCK):
    """Deflation space of the free set F: indicators of the block × block blocks on F (Z, one
    row per block that F touches), A Z for A = P K P (P: restrict to F, centre; one
    convolution per block), and the pseudo-inverse of E = Zᵀ A Z on the mean-zero space
    Σ_I c_I y_I = 0. Returns (idx, Z, AZ, E_inv): idx the flat indices of F."""
    n = op.n
    idx = np.flatnonzero(F)
    blocks = ((np.arange(n) // block)[:, None] * (n // block)
              + (np.arange(n) // block)[None, :]).ravel()
    _, pos = np.unique(blocks[idx], return_inverse=True)
    Z = np.zeros((pos.max() + 1, len(idx)))
    Z[pos, np.arange(len(idx))] = 1.0
    AZ = np.array([op.conv(op.full(idx, z), op.k_hat).ravel()[idx] for z in Z])
    return restricted(idx, Z, AZ, np.ones(len(idx), dtype=bool))


def restricted(idx, Z, AZ, keep):
    """(idx, Z, AZ, E_inv) of a coarse space restricted to the nodes `keep` of idx (A Z
    centred on them, E = Zᵀ A Z inverted on the mean-zero space)."""
    idx, Z, AZ = idx[keep], Z[:, keep], AZ[:, keep]
    AZ = AZ - AZ.mean(axis=1, keepdims=True)
    counts = Z.sum(axis=1)
    Z, AZ, counts = Z[counts > 0], AZ[counts > 0], counts[counts > 0]
    E = Z @ AZ.T
    u = counts / np.linalg.norm(counts)
    proj = np.eye(len(counts)) - np.outer(u, u)
    E_inv = proj @ np.linalg.pinv(proj @ (0.5 * (E + E.T)) @ proj, rcond=1e-10,
                                  hermitian=True) @ proj
    return idx, Z, AZ, E_inv


def deflated(op, M, P, coarse, r):
    """The balancing Neumann–Neumann preconditioner (I − Q A) M (I − A Q) + Q applied to r,
    Q = Z E⁺ Zᵀ, with M and the centring P on the free set."""
    idx, Z, AZ, E_inv = coarse
    y = E_inv @ (Z @ r.ravel()[idx])
    s = M(P(r - op.full(idx, AZ.T @ y)))
    v = E_inv @ (AZ @ s.ravel()[idx])
    return P(s - op.full(idx, Z.T @ v) + op.full(idx, Z.T @ y))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("n", type=int)
    ap.add_argument("surface")
    ap.add_argument("loads")
    ap.add_argument("--deflate", action="store_true")
    ap.add_argument("--start", choices=["scaled", "increment"], default="scaled")
    ap.add_argument("--trace", action="store_true")
    ap.add_argument("--f32-preconditioner", action="store_true")
    ap.add_argument("--refresh", type=float, default=0.0)
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--extend", type=float, default=0.0)
    ap.add_argument("--gamma", type=float, default=0.5)
    ap.add_argument("--dmin", type=float, default=0.05)
    ap.add_argument("--restart", type=float, default=RESTART_FRACTION)
    ap.add_argument("--long", type=float, default=0.0)
    ap.add_argument("--long-weight", type=float, default=0.5)
    ap.add_argument("--dmin-long", type=float, default=0.05)
    ap.add_argument("--long-settled", action="store_true")
    ap.add_argument("--first-on-contact", type=int, default=0)
    ap.add_argument("--settled-fraction", type=float, default=-1.0)
    ap.add_argument("--cell", type=int, default=1)
    ap.add_argument("--long-cell", type=int, default=1)
    ap.add_argument("--unsettled-weight", type=float, default=0.0)
    ap.add_argument("--first-damping", type=float, default=1.0)
    ap.add_argument("--load-offset", action="store_true")
    args = ap.parse_args()
    n = args.n
    h = np.load(args.surface)
    h_std = h.std()
    op = Operator(n, args.workers)
    conv, k_hat, k_inv_hat = op.conv, op.k_hat, op.k_inv_hat
    # Spectral rms slope, as the solver's load scale W0 = E* · rms slope · L².
    h_hat = sf.rfft2(h, workers=args.workers)
    weights = np.full(h_hat.shape, 2.0)
    weights[:, 0] = 1.0
    weights[:, -1] = 1.0
    slope = np.sqrt(np.sum(weights * np.abs(h_hat) ** 2 * (2 * np.pi * op.q) ** 2) / n**4)

    def solve(p, target, trace):
        if p.sum() > 0 and args.start == "increment":
            contact = p > 0
            inc = np.where(contact, np.maximum(conv(contact.astype(float), k_inv_hat), 0.0), 0.0)
            p = p + (target - p.mean()) * n * n / inc.sum() * inc
        elif p.sum() > 0:
            p = p * (target / p.mean())
        else:
            p = np.full((n, n), target)
        u = conv(p, k_hat)
        t = np.zeros((n, n))
        gz_old = 0.0
        restart = True
        coarse_key, coarse = None, None
        long_before = False
        changed = None
        for it in range(20000):
            w = u - h
            S = p > 0
            level = w[S].mean()
            error = np.sum(p * (w - w.min())) / (p.sum() * h_std)
            if error <= args.tol:
                return p, it
            g = w - level
            F = S | (w < level)
            if it < args.first_on_contact and p.sum() > 0:
                F = S

            P = centring(F)
            r = P(g)
            switched = False
            if args.deflate:
                if coarse_key is None or np.sum(coarse_key != F) > args.refresh * F.sum():
                    coarse_key, coarse = F.copy(), coarse_space(op, F)
                    refreshes[0] += 1
                # The space built on an earlier F, restricted to the current one (A Z stale
                # on the nodes that changed); itself when F has not changed.
                keep = F.ravel()[coarse[0]]
                current = coarse if keep.all() else restricted(*coarse[:3], keep)
                z = deflated(op, lambda x: P(conv(x, k_inv_hat)), P, current, r)
            elif args.f32_preconditioner:
                r32 = r.astype(np.float32)
                z = P(sf.irfft2(sf.rfft2(r32, workers=args.workers) * k_inv_hat.astype(np.float32),
                                s=(n, n), workers=args.workers).astype(np.float64))
            elif args.extend > 0:
                use_long = args.long > 0 and not (args.long_settled and restart)
                if args.settled_fraction >= 0:
                    use_long = (args.long > 0 and changed is not None
                                and changed <= args.settled_fraction * S.sum())
                switched, long_before = use_long != long_before, use_long
                terms = [(args.extend, args.gamma, args.dmin, args.cell)]
                if use_long:
                    terms.append((args.long, args.long_weight, args.dmin_long, args.long_cell))
                elif args.unsettled_weight > 0:
                    terms.append((args.long, args.unsettled_weight, args.dmin_long,
                                  args.long_cell))
                z = extended_preconditioner(op, F, P, terms)(r)
            else:
                z = P(conv(r, k_inv_hat))
            gz = np.sum(r * z)
            beta = 0.0 if (restart or gz_old <= 0) else gz / gz_old
            if args.extend > 0 and args.long > 0 and switched:
                beta = 0.0
            t_old = np.where(F, t - t[F].mean(), 0.0)
            if np.sum(r * (z + beta * t_old)) < DESCENT_FRACTION * gz:
                beta = 0.0
            t = z + beta * t_old
            gz_old = gz
            kt = conv(t, k_hat)
            tau = np.sum(g * t) / np.sum(t * kt)
            if it == 0 and p.sum() > 0:
                tau *= args.first_damping
            p_new = np.maximum(p - tau * t, 0.0)
            left = int(np.sum(S & (p_new <= 0)))
            entered = int(np.sum(~S & (p_new > 0)))
            restart = left + entered > args.restart * S.sum()
            changed = left + entered
            if trace:
                print(f"  iteration {it:3d}: error {error:.2e}, interpenetrating "
                      f"{int(F.sum() - S.sum())}, left {left}, entered {entered}, "
                      f"restart {restart}, beta {beta:.3f}", flush=True)
            if args.load_offset and changed > 6:
                p = offset_to_load(p - tau * t, F, target * n * n)
            else:
                p = p_new * (target / p_new.mean())
            u = conv(p, k_hat)
        raise RuntimeError("no convergence in 20000 iterations")

    refreshes = [0]
    loads = [float(x) for x in args.loads.split(",")]
    p = np.zeros((n, n))
    for i, load in enumerate(loads):
        p, iterations = solve(p, load * slope, args.trace and i == len(loads) - 1)
        print(json.dumps({"w_over_w0": load, "iterations": iterations,
                          "contact_fraction": float((p > 0).mean()),
                          "coarse_refreshes": refreshes[0]}), flush=True)


if __name__ == "__main__":
    main()
