"""Writes measured_1.x3p and measured_2.x3p, the topography files of pipeline.yaml's
`measured_example` study, as SurfaceTopography (PyPI) writes X3P: two 192 × 144 maps in µm
(pixel 0.5 µm) of a self-affine surface (H = 0.8, wavelengths 32 µm to 4 µm, so
λ_s = 8 pixels and λ_l/λ_s = 8; rms slope 0.2), each tilted as a sample sits in an
instrument and with 10 missing points. The files in the repository were written by this
script with SurfaceTopography 1.27.1:

    python examples/data/make_measured.py examples/data
"""
import sys

import numpy as np
from SurfaceTopography import Topography


def write(path, seed):
    nx, ny, dx = 192, 144, 0.5  # points along x and y; pixel size in µm
    rng = np.random.default_rng(seed)
    q = np.hypot(np.fft.fftfreq(nx, dx)[:, None], np.fft.fftfreq(ny, dx)[None, :])
    amplitude = np.where((q >= 1 / 32) & (q <= 1 / 4), np.maximum(q, 1e-30) ** -1.8, 0)
    h = np.fft.ifft2(amplitude * np.exp(2j * np.pi * rng.random((nx, ny)))).real
    h *= 0.2 / np.sqrt(2 * np.mean((np.diff(h, axis=0) / dx) ** 2))
    x, y = np.meshgrid(np.arange(nx) * dx, np.arange(ny) * dx, indexing="ij")
    h += 0.01 * x - 0.004 * y
    missing = np.zeros(h.shape, dtype=bool)
    missing.flat[rng.choice(h.size, 10, replace=False)] = True
    Topography(np.ma.masked_array(h, missing), (nx * dx, ny * dx), unit="µm",
               periodic=False).to_x3p(path)


if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    for seed in (1, 2):
        write(f"{out}/measured_{seed}.x3p", seed)
