"""`wearcoef wear` on a non-periodic, rectangular map against ContactMechanics' free-boundary
half-space (FreeFFTElasticHalfSpace, zero-padded to 2nx × 2ny) on the same heights and
forces: contact sets and pressures at several loads. Usage: python check_contact.py BIN WORKDIR"""
import json
import os
import subprocess
import sys

import numpy as np
import pandas as pd
import ContactMechanics as cm
from ContactMechanics import FreeFFTElasticHalfSpace, make_system
from SurfaceTopography import Topography

BIN, WORK = sys.argv[1], sys.argv[2]
os.makedirs(WORK, exist_ok=True)
NX, NY, DX = 150, 110, 0.5e-6  # points along x and y, pixel size (m)
E_STAR = 100e9  # Pa
LOADS = [0.01, 0.03, 0.1]  # W/W0


def surface():
    """A self-affine map (H = 0.8, λ from 40 to 2 µm) of rms slope 0.2, in metres, [x, y]."""
    rng = np.random.default_rng(3)
    qx = np.fft.fftfreq(NX, DX)[:, None]
    qy = np.fft.fftfreq(NY, DX)[None, :]
    q = np.hypot(qx, qy)
    amp = np.where((q >= 1 / 40e-6) & (q <= 1 / 2e-6), np.maximum(q, 1e-30) ** -1.8, 0)
    h = np.fft.ifft2(amp * np.exp(2j * np.pi * rng.random((NX, NY)))).real
    return h * 0.2 / np.sqrt(np.mean(np.diff(h, axis=0) ** 2) / DX**2 * 2)


def main():
    print(f"ContactMechanics {cm.__version__}")
    h = surface()
    path = os.path.join(WORK, "map.x3p")
    Topography(h, (NX * DX, NY * DX), unit="m", periodic=False).to_x3p(path)
    out = os.path.join(WORK, "out")
    run = subprocess.run(
        [BIN, "wear", "--input", path, "--form", "none", "--e-star", "100GPa",
         "--loads", ",".join(map(str, LOADS)), "--a-star", "1um2", "--tolerance", "1e-10",
         "--pressure-maps", "-o", out], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    loads = pd.read_parquet(os.path.join(out, "loads.parquet"))
    ours = np.load(os.path.join(out, "pressure.npy"))  # (loads, rows = y, cols = x), Pa
    sub = FreeFFTElasticHalfSpace((NX, NY), E_STAR, physical_sizes=(NX * DX, NY * DX))
    system = make_system(surface=Topography(h, (NX * DX, NY * DX)), substrate=sub)
    for i, force in enumerate(loads["force_n"]):
        res = system.minimize_proxy(external_force=force, pentol=1e-12, maxiter=20000)
        assert res.success, f"ContactMechanics did not converge at load {i}"
        theirs = (res.jac / sub.area_per_pt).T  # [y, x]
        mine = ours[i]
        a, b = mine > 0, theirs > 0
        differ = int((a ^ b).sum())
        l2 = np.sqrt(np.sum((mine - theirs) ** 2) / np.sum(theirs**2))
        print(f"W/W0 = {LOADS[i]}: {force:.4g} N, {a.sum()} nodes in contact against "
              f"{b.sum()}, {differ} differ; pressure relative L2 {l2:.2e}")
        assert differ <= max(2, 0.002 * b.sum()), f"contact sets differ at {differ} nodes"
        assert l2 <= 1e-5, f"pressures differ by {l2:.2e} (relative L2)"
        assert abs(mine.sum() * DX * DX / force - 1) < 1e-9


main()
