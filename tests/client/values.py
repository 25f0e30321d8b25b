"""Value digests of a wearcoef data directory, to show that a change of code moves no number.

    python values.py digest DATA PROFILE > digest.json
    python values.py compare EXPECTED.json ACTUAL.json

`digest` records, for every stored output of the numerical stages (surface, contact,
clusters, statistics, analytic: `<stage>/<key>/<file>`) and every table of the profile's
figure gallery (`gallery/<file>`), a SHA-256 of its values: per column for Parquet (the
column's values as Python objects, so file metadata and column order do not count), of
dtype, shape and bytes for .npy. `compare` fails when an entry of EXPECTED is missing from
ACTUAL or differs (a column of EXPECTED missing or different); ACTUAL may hold more (new
stages, new columns). Exit status 0 when everything matches, 1 otherwise.
"""

import hashlib
import json
import os
import sys

import numpy as np
import pyarrow.parquet as pq

NUMERICAL_STAGES = ["surface", "contact", "clusters", "statistics", "analytic"]


def sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def parquet_digest(path):
    table = pq.read_table(path)
    return {name: sha(repr(table.column(name).to_pylist()).encode())
            for name in table.column_names}


def npy_digest(path):
    a = np.load(path)
    return sha(f"{a.dtype.str}{a.shape}".encode() + np.ascontiguousarray(a).tobytes())


def file_digest(path):
    if path.endswith(".parquet"):
        return parquet_digest(path)
    if path.endswith(".npy"):
        return npy_digest(path)
    return None


def digest(data, profile):
    out = {}
    cache = os.path.join(data, "cache")
    for stage in NUMERICAL_STAGES:
        root = os.path.join(cache, stage)
        if not os.path.isdir(root):
            continue
        for key in sorted(os.listdir(root)):
            entry = os.path.join(root, key)
            if key.startswith(".") or not os.path.isfile(os.path.join(entry, "manifest.json")):
                continue
            for name in sorted(os.listdir(entry)):
                d = file_digest(os.path.join(entry, name))
                if d is not None:
                    out[f"{stage}/{key}/{name}"] = d
    gallery = os.path.join(os.path.dirname(os.path.abspath(data)), "figures", profile)
    if os.path.isdir(gallery):
        for name in sorted(os.listdir(gallery)):
            if name.endswith(".parquet"):
                out[f"gallery/{name}"] = parquet_digest(os.path.join(gallery, name))
    return out


def compare(expected, actual):
    problems = []
    for entry, want in expected.items():
        got = actual.get(entry)
        if got is None:
            problems.append(f"{entry}: missing")
        elif isinstance(want, dict):
            for column, value in want.items():
                if column not in got:
                    problems.append(f"{entry}: column {column} missing")
                elif got[column] != value:
                    problems.append(f"{entry}: column {column} differs")
        elif got != want:
            problems.append(f"{entry}: values differ")
    return problems


def main(argv):
    if len(argv) == 4 and argv[1] == "digest":
        json.dump(digest(argv[2], argv[3]), sys.stdout, indent=0, sort_keys=True)
        return 0
    if len(argv) == 4 and argv[1] == "compare":
        with open(argv[2]) as f:
            expected = json.load(f)
        with open(argv[3]) as f:
            actual = json.load(f)
        problems = compare(expected, actual)
        for p in problems:
            print(p)
        print(f"{len(expected)} expected entries, {len(problems)} problem(s)")
        return 1 if problems else 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
