"""Time numpy.fft.rfft2 + irfft2 (float64) on the sizes of benches/fft.rs.

Prints one JSON object: {"numpy": version, "seconds": {N: median seconds per pair}}.
"""
import json
import sys
import timeit

import numpy as np

sizes = [int(s) for s in sys.argv[1:]] or [512, 1024, 2048, 4096]
rng = np.random.default_rng(0)
result = {}
for n in sizes:
    a = rng.standard_normal((n, n))
    pair = lambda: np.fft.irfft2(np.fft.rfft2(a), s=a.shape)
    pair()
    number = max(1, int(0.2 / max(timeit.timeit(pair, number=1), 1e-6)))
    runs = timeit.repeat(pair, number=number, repeat=15)
    result[n] = float(np.median(runs) / number)
print(json.dumps({"numpy": np.__version__, "seconds": result}))
