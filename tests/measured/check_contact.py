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
from ContactMechanics.Factory import make_plastic_system
from SurfaceTopography import PlasticTopography, Topography

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


def wear(path, out, loads, *extra):
    """`wearcoef wear` on `path` at the loads `loads` (W/W0) with the pressure maps, as every
    check here runs it: the loads table and the pressures (loads, rows = y, cols = x), Pa."""
    run = subprocess.run(
        [BIN, "wear", "--input", path, "--form", "none", "--e-star", "100GPa",
         "--loads", ",".join(map(str, loads)), "--a-star", "1um2", "--tolerance", "1e-10",
         "--pressure-maps", *extra, "-o", out], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return (pd.read_parquet(os.path.join(out, "loads.parquet")),
            np.load(os.path.join(out, "pressure.npy")))


def main():
    print(f"ContactMechanics {cm.__version__}")
    h = surface()
    path = os.path.join(WORK, "map.x3p")
    Topography(h, (NX * DX, NY * DX), unit="m", periodic=False).to_x3p(path)
    out = os.path.join(WORK, "out")
    loads, ours = wear(path, out, LOADS)
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


def plastic():
    """`wear --hardness 4GPa` (0.2 E*·rms slope) against ContactMechanics' plastic system
    (`make_plastic_system` with a `PlasticTopography`; `make_system` ignores the hardness)
    on the free-boundary half-space: the same contact and saturated sets, pressures within
    1e-5 relative L2, and no pressure above the hardness."""
    h = surface()
    path = os.path.join(WORK, "map.x3p")
    out = os.path.join(WORK, "plastic")
    hardness = 4e9
    loads, ours = wear(path, out, [0.02, 0.05], "--hardness", "4GPa")
    for i, force in enumerate(loads["force_n"]):
        sub = FreeFFTElasticHalfSpace((NX, NY), E_STAR, physical_sizes=(NX * DX, NY * DX))
        system = make_plastic_system(
            surface=PlasticTopography(Topography(h, (NX * DX, NY * DX)), hardness),
            substrate=sub)
        res = system.minimize_proxy(external_force=force, pentol=1e-12, maxiter=20000)
        assert res.success, f"ContactMechanics (plastic) did not converge at load {i}"
        theirs = (res.jac / sub.area_per_pt).T
        mine = ours[i]
        assert mine.max() <= hardness, f"pressure {mine.max()} above the hardness"
        at_h = lambda p: p >= hardness * (1 - 1e-9)  # noqa: E731
        contact, saturated = int(((mine > 0) ^ (theirs > 0)).sum()), int((at_h(mine) ^ at_h(theirs)).sum())
        assert saturated == 0 and contact == 0, f"{contact} contact, {saturated} saturated nodes differ"
        assert at_h(mine).sum() == loads["n_saturated_px"][i]
        l2 = np.sqrt(np.sum((mine - theirs) ** 2) / np.sum(theirs**2))
        assert l2 <= 1e-5, f"plastic pressures differ by {l2:.2e}"
        print(f"hardness 4 GPa, W/W0 = {loads['w_over_w0'][i]}: {int((mine > 0).sum())} nodes in "
              f"contact, {int(at_h(mine).sum())} at the hardness, as ContactMechanics; "
              f"pressure relative L2 {l2:.2e}")


def rectangular():
    """A real map with rectangular pixels, solved as measured: SurfaceTopography's
    x3p-2.x3p (pixels of 0.128 × 0.315 µm), not resampled, against ContactMechanics'
    free-boundary half-space on the same heights at the same forces: contact areas within
    1e-3, pressures within 1e-5 relative L2. Its 256 × 256 corner, written back as X3P with
    the file's pixels, keeps ContactMechanics' share of `make test` near a minute (the whole
    650 × 650 map takes it 13 minutes; docs/VALIDATION.md gives that run's numbers)."""
    from SurfaceTopography import read_topography
    whole = read_topography(os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "instrument", "x3p-2.x3p"))
    (nx, ny), (sx, sy) = whole.nb_grid_pts, whole.physical_sizes
    corner = whole.heights()[:256, :256]
    path = os.path.join(WORK, "x3p-2-corner.x3p")
    Topography(corner, (sx * 256 / nx, sy * 256 / ny), unit=whole.unit,
               periodic=False).to_x3p(path)
    out = os.path.join(WORK, "rectangular")
    loads = [0.05, 0.2, 0.5]
    table, ours = wear(path, out, loads)
    t = read_topography(path)
    (nx, ny), (sx, sy) = t.nb_grid_pts, t.physical_sizes
    dx, dy = sx / nx, sy / ny
    assert abs(dy / dx - 2.466) < 0.01, f"pixels {dx} × {dy} m: not the rectangular ones"
    sub = FreeFFTElasticHalfSpace((nx, ny), E_STAR, physical_sizes=(sx, sy))
    system = make_system(surface=Topography(t.heights(), (sx, sy)), substrate=sub)
    for i, force in enumerate(table["force_n"]):
        # pentol is absolute, in the heights' unit (m): 1e-16 m is 1e-9 of the rms height.
        res = system.minimize_proxy(external_force=force, pentol=1e-16, maxiter=20000)
        assert res.success, f"ContactMechanics did not converge at load {i}"
        theirs = (res.jac / sub.area_per_pt).T  # [y, x]
        mine = ours[i]
        area_theirs = (theirs > 0).sum() * dx * dy * 1e12
        area_mine = table["real_contact_area_um2"][i]
        rel = abs(area_mine / area_theirs - 1)
        differ = int(((mine > 0) ^ (theirs > 0)).sum())
        l2 = np.sqrt(np.sum((mine - theirs) ** 2) / np.sum(theirs**2))
        print(f"x3p-2.x3p's corner (pixels {dx * 1e6:.3f} × {dy * 1e6:.3f} µm), W/W0 = {loads[i]}: "
              f"{force:.4g} N, contact area {area_mine:.5g} µm² against {area_theirs:.5g} "
              f"(relative {rel:.1e}), {differ} nodes differ, pressure relative L2 {l2:.1e}")
        assert rel <= 1e-3, f"contact areas differ by {rel:.2e}"
        assert l2 <= 1e-5, f"pressures differ by {l2:.2e} (relative L2)"
        assert abs(mine.sum() * dx * dy / force - 1) < 1e-9


main()
plastic()
rectangular()
