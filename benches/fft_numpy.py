"""Time the 2-D real FFT pair (forward r2c + inverse c2r, float64) of numpy and of FFTW
(pyFFTW, plans made with FFTW_MEASURE, 1 and 2 threads), and FFTW's float32 pair (1 thread),
on the sizes of benches/fft.rs.

Each timing is the median over 15 repeats of a loop long enough to last about 0.2 s. The
FFTW plans work on preallocated aligned arrays and are executed without copies, as the
Rust bench reuses its plans and buffers.

Prints one JSON object: {"numpy": version, "pyfftw": version,
"seconds": {"numpy": {N: s}, "fftw1": {N: s}, "fftw2": {N: s}, "fftw1_f32": {N: s}}}.
"""
import json
import sys
import timeit

import numpy as np

sizes = [int(s) for s in sys.argv[1:]] or [512, 1024, 2048, 4096]
rng = np.random.default_rng(0)


def median_seconds(pair):
    pair()
    number = max(1, int(0.2 / max(timeit.timeit(pair, number=1), 1e-6)))
    runs = timeit.repeat(pair, number=number, repeat=15)
    return float(np.median(runs) / number)


result = {"numpy": {}, "fftw1": {}, "fftw2": {}, "fftw1_f32": {}}
versions = {"numpy": np.__version__}
try:
    import pyfftw

    versions["pyfftw"] = pyfftw.__version__
except ImportError:
    pyfftw = None

for n in sizes:
    a = rng.standard_normal((n, n))
    result["numpy"][n] = median_seconds(
        lambda: np.fft.irfft2(np.fft.rfft2(a), s=a.shape)
    )
    if pyfftw is None:
        continue
    for threads, real_type, complex_type, name in (
        (1, "float64", "complex128", "fftw1"),
        (2, "float64", "complex128", "fftw2"),
        (1, "float32", "complex64", "fftw1_f32"),
    ):
        real = pyfftw.empty_aligned((n, n), dtype=real_type)
        spec = pyfftw.empty_aligned((n, n // 2 + 1), dtype=complex_type)
        out = pyfftw.empty_aligned((n, n), dtype=real_type)
        forward = pyfftw.FFTW(
            real, spec, axes=(0, 1), direction="FFTW_FORWARD",
            flags=("FFTW_MEASURE",), threads=threads,
        )
        inverse = pyfftw.FFTW(
            spec, out, axes=(0, 1), direction="FFTW_BACKWARD",
            flags=("FFTW_MEASURE", "FFTW_DESTROY_INPUT"), threads=threads,
        )
        real[:] = a  # planning with FFTW_MEASURE overwrites the arrays

        def pair():
            forward.execute()
            inverse.execute()

        result[name][n] = median_seconds(pair)
        # Same result as numpy (FFTW's inverse is unnormalised, like ours).
        forward.execute()
        inverse.execute()
        tolerance = 1e-4 if real_type == "float32" else 1e-8
        assert np.allclose(out / (n * n), a, atol=tolerance), "FFTW pair does not round-trip"

print(json.dumps({**versions, "seconds": result}))
