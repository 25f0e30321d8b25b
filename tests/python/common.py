"""What the Python package's checks share: the binary run with its exit code checked, and
two tables compared column by column, floats by their bits (NaN = NaN)."""

import subprocess

import numpy as np


def run(binary, *args):
    """`binary args…`, which must exit 0; its completed process (stdout as text)."""
    out = subprocess.run([binary, *args], capture_output=True, text=True)
    assert out.returncode == 0, f"{args}: exit {out.returncode}: {out.stderr}"
    return out


def same_frame(mine, theirs, what):
    """Equal columns, row counts and values, floats compared by their bits."""
    assert list(mine.columns) == list(theirs.columns), f"{what}: columns {list(mine.columns)} against {list(theirs.columns)}"
    assert len(mine) == len(theirs), f"{what}: {len(mine)} rows against {len(theirs)}"
    for c in mine.columns:
        a, b = mine[c].to_numpy(), theirs[c].to_numpy()
        if a.dtype.kind == "f" or b.dtype.kind == "f":
            a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
            assert np.array_equal(a.view(np.uint64), b.view(np.uint64)), f"{what}.{c}: values differ"
        else:
            assert np.array_equal(a, b), f"{what}.{c}: values differ"
