"""Every reader of `wearcoef topography` against SurfaceTopography (PyPI) on files that
SurfaceTopography writes: the same heights (metres), missing points, pixel sizes and units;
the rms slope after the plane is removed; and each corrupt file refused with exit 2 naming
the file. Usage: python check_readers.py WEARCOEF_BIN WORKDIR"""
import json
import os
import subprocess
import sys
import zipfile

import numpy as np
import SurfaceTopography as st
from SurfaceTopography import Topography, read_topography
from SurfaceTopography.Support.UnitConversion import get_unit_conversion_factor

BIN, WORK = sys.argv[1], sys.argv[2]
os.makedirs(WORK, exist_ok=True)
NX, NY, DX, DY = 60, 45, 0.5, 0.4  # points along x and y, pixel sizes in µm


def surface(missing):
    """Heights in µm indexed [x, y] as SurfaceTopography holds them: a random field with a
    tilt, and `missing` masked points."""
    rng = np.random.default_rng(7)
    x, y = np.meshgrid(np.arange(NX) * DX, np.arange(NY) * DY, indexing="ij")
    h = 0.2 * rng.standard_normal((NX, NY)) + 0.03 * x - 0.02 * y + 1.5
    mask = np.zeros_like(h, dtype=bool)
    mask.flat[rng.choice(NX * NY, missing, replace=False)] = True
    return np.ma.masked_array(h, mask) if missing else h


def ours(path, *extra):
    out = os.path.join(WORK, "ours.npy")
    run = subprocess.run(
        [BIN, "topography", "--input", path, "--form", "none", "--fill", "keep",
         "-o", out, "--json", *extra],
        capture_output=True, text=True)
    assert run.returncode == 0, f"{path}: exit {run.returncode}: {run.stderr}"
    return np.load(out), json.loads(run.stdout)


def compare(path, *extra, rtol=1e-12, rows_first=False, **theirs_given):
    """Our map against SurfaceTopography's reading of the same file. `rows_first`: a .npy,
    whose first axis SurfaceTopography takes as x and we take as y (rows, numpy's image
    layout `h[y, x]`, docs/CONVENTIONS.md)."""
    t = read_topography(path, **theirs_given)
    to_m = get_unit_conversion_factor(t.unit, "m")
    theirs = np.ma.filled(np.ma.asarray(t.heights(), dtype=float), np.nan) * to_m
    pixel = np.array(t.physical_sizes) / np.array(t.nb_grid_pts) * to_m
    if not rows_first:
        theirs = theirs.T
    else:
        pixel = pixel[::-1]
    mine, report = ours(path, *extra)
    assert mine.shape == theirs.shape, f"{path}: shape {mine.shape} against {theirs.shape}"
    assert np.array_equal(np.isnan(mine), np.isnan(theirs)), f"{path}: missing points differ"
    ok = ~np.isnan(theirs)
    scale = np.abs(theirs[ok]).max()
    err = np.abs(mine[ok] - theirs[ok]).max() / scale
    assert err <= rtol, f"{path}: heights differ by {err:.3g} of the largest"
    got = np.array([report["pixel_size_x_m"], report["pixel_size_y_m"]])
    assert np.allclose(got, pixel, rtol=1e-12, atol=0), f"{path}: pixel {got} against {pixel}"
    assert report["missing_points"] == int((~ok).sum()), f"{path}: missing count"
    print(f"{os.path.basename(path)}: {mine.shape[0]} × {mine.shape[1]}, "
          f"{report['missing_points']} missing, heights within {err:.1e}, "
          f"pixel {got[0]:.3e} × {got[1]:.3e} m: as SurfaceTopography reads it")


def main():
    print(f"SurfaceTopography {st.__version__}")
    holed = Topography(surface(7), (NX * DX, NY * DY), unit="µm", periodic=False)
    whole = Topography(surface(0), (NX * DX, NY * DY), unit="µm", periodic=False)
    for dtype, rtol in [("D", 1e-12), ("F", 1e-12), ("L", 1e-12), ("I", 1e-12)]:
        path = os.path.join(WORK, f"map_{dtype}.x3p")
        holed.to_x3p(path, dtype=dtype)
        compare(path, rtol=rtol)
    path = os.path.join(WORK, "map.nc")
    holed.to_netcdf(path)
    compare(path)
    path = os.path.join(WORK, "map.txt")
    holed.to_matrix(path)
    compare(path)
    path = os.path.join(WORK, "map.npy")
    np.save(path, np.ma.filled(holed.heights(), np.nan).T)
    compare(path, "--height-unit", "um", "--pixel-size", str(DX), "--pixel-size-y", str(DY),
            rows_first=True, physical_sizes=(NY * DY, NX * DX), unit="µm")

    # x-y-z lists, written by numpy: in Gwyddion's layout (units in a comment header), the
    # points shuffled; and bare, the unit given.
    h = np.ma.filled(holed.heights(), np.nan)
    x, y = np.meshgrid(np.arange(NX) * DX, np.arange(NY) * DY, indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), h.ravel()])
    np.random.default_rng(3).shuffle(points)
    path = os.path.join(WORK, "map.xyz")
    with open(path, "w") as f:
        f.write("# Channel: Height\n# Lateral units: µm\n# Value units: µm\n")
        np.savetxt(f, points)
    compare(path)
    path = os.path.join(WORK, "bare.xyz")
    np.savetxt(path, points)
    compare(path, "--height-unit", "um", unit="um")

    # The rms slope after the plane is removed, against SurfaceTopography's (upwind
    # differences on the (nx − 1) × (ny − 1) pairs where ours averages every pair: they
    # differ by O(1/n), 1 % here).
    path = os.path.join(WORK, "whole.x3p")
    whole.to_x3p(path)
    theirs = read_topography(path).detrend("height").rms_gradient()
    run = subprocess.run([BIN, "topography", "--input", path, "--json"],
                         capture_output=True, text=True, check=True)
    mine = json.loads(run.stdout)["rms_slope"]
    assert abs(mine / theirs - 1) < 0.01, f"rms slope {mine} against {theirs}"
    print(f"rms slope after the plane: {mine:.5f} against SurfaceTopography's {theirs:.5f}")

    # Corrupt files: exit 2, the file named, what is wrong said.
    good = os.path.join(WORK, "map_D.x3p")
    cases = {}
    raw = open(good, "rb").read()
    cases["truncated.x3p"] = raw[: len(raw) * 2 // 3]
    with zipfile.ZipFile(good) as z:
        members = {n: z.read(n) for n in z.namelist()}
    data = bytearray(members["bindata/data.bin"])
    data[100] ^= 0xFF
    tampered = os.path.join(WORK, "tampered.x3p")
    with zipfile.ZipFile(tampered, "w") as z:
        for n, b in members.items():
            z.writestr(n, bytes(data) if n == "bindata/data.bin" else b)
    short = os.path.join(WORK, "short.x3p")
    with zipfile.ZipFile(short, "w") as z:
        for n, b in members.items():
            if n == "main.xml":
                b = b.replace(b"<MD5ChecksumPointData>", b"<Unused>").replace(
                    b"</MD5ChecksumPointData>", b"</Unused>")
            z.writestr(n, b[:-8] if n == "bindata/data.bin" else b)
    nc = open(os.path.join(WORK, "map.nc"), "rb").read()
    cases["truncated.nc"] = nc[: len(nc) // 2]
    cases["notes.sur"] = b"not a map"
    for name, blob in cases.items():
        with open(os.path.join(WORK, name), "wb") as f:
            f.write(blob)
    unitless = os.path.join(WORK, "map.npy")
    expectations = [
        (os.path.join(WORK, "truncated.x3p"), ["--"], "zip"),
        (tampered, [], "MD5"),
        (short, [], "truncated or mismatched"),
        (os.path.join(WORK, "truncated.nc"), [], "truncated"),
        (os.path.join(WORK, "notes.sur"), [], "not read"),
        (unitless, [], "no height unit"),
    ]
    for path, _, said in expectations:
        run = subprocess.run([BIN, "topography", "--input", path],
                             capture_output=True, text=True)
        assert run.returncode == 2, f"{path}: exit {run.returncode}, not 2: {run.stderr}"
        assert path in run.stderr and said in run.stderr, f"{path}: {run.stderr!r}"
        print(f"{os.path.basename(path)}: exit 2: {run.stderr.strip().splitlines()[-1][:150]}")


main()


def psd_against_surface_topography():
    """Our radially averaged PSD (radial Hann window, ⟨w²⟩ = 1) against SurfaceTopography's
    power_spectrum_from_area on the same prepared heights, in our bins (its `collocation`
    takes bin edges): every bin within 1e-12. The bin that holds the Nyquist radius
    π min(1/Δx, 1/Δy) is left out: we stop at that radius, SurfaceTopography counts the
    wavevectors past it up to the bin's edge."""
    path = os.path.join(WORK, "whole.x3p")
    prep, table = os.path.join(WORK, "prep.npy"), os.path.join(WORK, "psd.parquet")
    run = subprocess.run([BIN, "topography", "--input", path, "-o", prep, "--psd", table,
                          "--json"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    import pandas as pd
    ours = pd.read_parquet(table)
    h = np.load(prep).T  # [x, y] for SurfaceTopography
    t = Topography(h, (NX * DX * 1e-6, NY * DY * 1e-6), unit="m", periodic=False)
    edges = np.unique(np.concatenate([ours["q_low_per_m"], ours["q_high_per_m"]]))
    q, c = t.power_spectrum_from_area(collocation=edges, reliable=False)
    nyquist = np.pi / max(DX, DY) * 1e6
    ours = ours[ours["q_high_per_m"] <= nyquist]
    worst, matched = 0.0, 0
    for qi, ci in zip(np.ma.filled(q, np.nan), np.ma.filled(c, np.nan)):
        if np.isnan(ci) or qi > ours["q_high_per_m"].max():
            continue
        mine = ours[(ours["q_low_per_m"] <= qi) & (qi < ours["q_high_per_m"])]
        assert len(mine) == 1, f"no bin of ours holds SurfaceTopography's q = {qi}"
        worst = max(worst, abs(mine["c_m4"].iloc[0] / ci - 1))
        matched += 1
    assert matched == len(ours), f"{matched} of our {len(ours)} bins matched"
    assert worst < 1e-12, f"PSD bins differ by {worst:.2e}"
    print(f"PSD: {len(ours)} bins as SurfaceTopography's within {worst:.1e}")


def write_sdf(path, h_um, binary, data_type):
    """An ISO 25178-71 SDF file of the heights h_um ([x, y], µm, NaN missing), written here
    from the standard (SurfaceTopography reads SDF but writes none): text with `BAD`, or
    binary little-endian with NaN (DataType 7) or int16 and its reserved minimum (5)."""
    import struct
    z = h_um.T * 1e-6  # [y, x] in metres: profiles along y, points along x
    zscale = 1e-9 if data_type == 5 else 1.0
    raw = z / zscale
    if data_type == 5:
        raw = np.where(np.isnan(raw), -(2**15), np.round(raw)).astype("<i2")
    fields = dict(NumPoints=NX, NumProfiles=NY, Xscale=DX * 1e-6, Yscale=DY * 1e-6,
                  Zscale=zscale, Zresolution=-1.0, Compression=0, DataType=data_type,
                  CheckType=0)
    with open(path, "wb") as f:
        if binary:
            f.write(b"bISO-1.0" + b"wearcoef  " + b"281120261200" * 2)
            f.write(struct.pack("<HHddddBBB", NX, NY, fields["Xscale"], fields["Yscale"],
                                zscale, -1.0, 0, data_type, 0))
            f.write(raw.astype("<f8" if data_type == 7 else "<i2").tobytes())
        else:
            head = "aISO-1.0\nManufacID = wearcoef\nCreateDate = 281120261200\n"
            head += "".join(f"{k} = {v!r}\n" for k, v in fields.items()) + "*\n"
            rows = "\n".join(" ".join("BAD" if np.isnan(v) else repr(float(v)) for v in r)
                             for r in raw)
            f.write((head + rows + "\n*\n").encode())
    return raw


def sdf_and_gsf():
    """SDF (text, binary float64, binary int16) against SurfaceTopography's reader; GSF
    written by gsffile (PyPI) against gsffile's own reader."""
    holed = np.ma.filled(surface(7), np.nan)  # µm, [x, y]
    for name, binary, data_type, rtol in [("text.sdf", False, 7, 1e-15),
                                          ("float.sdf", True, 7, 0),
                                          ("int16.sdf", True, 5, 0)]:
        path = os.path.join(WORK, name)
        write_sdf(path, holed, binary, data_type)
        compare(path, rtol=max(rtol, 1e-15))
    import gsffile
    path = os.path.join(WORK, "map.gsf")
    data = (np.ma.filled(surface(7), np.nan).T * 1e-6).astype(np.float32)
    gsffile.write_gsf(path, data, {"XReal": NX * DX * 1e-6, "YReal": NY * DY * 1e-6,
                                   "XYUnits": "m", "ZUnits": "m"})
    theirs, meta = gsffile.read_gsf(path)
    mine, report = ours(path)
    assert np.array_equal(np.isnan(mine), np.isnan(theirs)), "GSF: missing points differ"
    ok = ~np.isnan(theirs)
    assert np.array_equal(mine[ok], theirs[ok].astype(float)), "GSF: heights differ"
    pixel = [meta["XReal"] / NX, meta["YReal"] / NY]
    assert np.allclose([report["pixel_size_x_m"], report["pixel_size_y_m"]], pixel, rtol=1e-12)
    print(f"map.gsf: {mine.shape[0]} × {mine.shape[1]}, {int((~ok).sum())} missing, "
          f"heights and pixel sizes as gsffile reads them")
    for name, cut, said in [("float.sdf", 100, "truncated"), ("text.sdf", 300, "truncated"),
                            ("map.gsf", 8, "truncated")]:
        blob = open(os.path.join(WORK, name), "rb").read()
        bad = os.path.join(WORK, "cut_" + name)
        with open(bad, "wb") as f:
            f.write(blob[:-cut])
        run = subprocess.run([BIN, "topography", "--input", bad], capture_output=True, text=True)
        assert run.returncode == 2 and bad in run.stderr and said in run.stderr, run.stderr
        print(f"cut_{name}: exit 2: {run.stderr.strip()[:140]}")


psd_against_surface_topography()
sdf_and_gsf()


INSTRUMENT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "instrument")


def x3p_in_numpy(path):
    """An X3P archive read in numpy, independently of both readers: main.xml at the root or
    in the archive's one folder, heights `raw · Increment + Offset` of CZ (as
    SurfaceTopography scales them), [y, x] (rows along y); the pixel size in metres."""
    import xml.etree.ElementTree as ET
    with zipfile.ZipFile(path) as z:
        main = [n for n in z.namelist()
                if n.split("/")[-1] == "main.xml" and not n.startswith("__MACOSX")]
        assert len(main) == 1, f"{path}: main.xml members {main}"
        folder = main[0][: -len("main.xml")]
        root = ET.fromstring(z.read(main[0]))

        def get(*names):
            node = root
            for name in names:
                node = next(c for c in node if c.tag.split("}")[-1] == name)
            return node.text

        dtype = {"I": "<u2", "L": "<u4", "F": "<f4", "D": "<f8"}[get("Record1", "Axes", "CZ", "DataType")]
        nx, ny = int(get("Record3", "MatrixDimension", "SizeX")), int(get("Record3", "MatrixDimension", "SizeY"))
        inc = float(get("Record1", "Axes", "CZ", "Increment") or 1)
        off = float(get("Record1", "Axes", "CZ", "Offset") or 0)
        raw = np.frombuffer(z.read(folder + get("Record3", "DataLink", "PointDataLink")), dtype, nx * ny)
        pixel = (float(get("Record1", "Axes", "CX", "Increment")), float(get("Record1", "Axes", "CY", "Increment")))
    return raw.astype(float).reshape(ny, nx) * inc + off, pixel


def instruments():
    """Files nobody on this project wrote (instrument/SOURCES.md): every map read as
    SurfaceTopography reads it; where SurfaceTopography refuses a valid file, as numpy reads
    it; and every file that is not a map refused with exit 2, saying what it is."""
    at = lambda name: os.path.join(INSTRUMENT, name)  # noqa: E731
    for name in ["x3p-2.x3p", "sdf-1.sdf", "nc-1.nc", "matrix-3.txt", "matrix-4.txt",
                 "matrix-6.txt", "txt_example.txt", "gwyddion-export-english.txt",
                 "gwyddion-export-german.txt"]:
        compare(at(name))
    for name in ["xyz-1.txt", "xyz-2.txt", "xyz-1-different-order.txt"]:
        compare(at(name), "--height-unit", "um", unit="um")
    # Files that state no units, given them (the pixel size in the heights' unit).
    compare(at("matrix-5.txt"), "--height-unit", "nm", "--pixel-size", "2000",
            physical_sizes=(10 * 2000, 10 * 2000), unit="nm")
    compare(at("example-2d.npy"), "--height-unit", "um", "--pixel-size", "1",
            rows_first=True, physical_sizes=(2, 2), unit="µm")
    # X3P archives SurfaceTopography refuses (an en dash in Revision; main.xml in a folder,
    # as x3ptools writes it): read, and equal to numpy's reading of the same members.
    for name in ["pyramid.x3p", "testing.x3p", "csafe-logo.x3p", "sample-land.x3p"]:
        try:
            read_topography(at(name))
            refused = None
        except Exception as e:  # noqa: BLE001
            refused = type(e).__name__
        assert refused, f"{name}: SurfaceTopography now reads it; compare with it instead"
        theirs, pixel = x3p_in_numpy(at(name))
        mine, report = ours(at(name))
        assert mine.shape == theirs.shape, f"{name}: shape {mine.shape} against {theirs.shape}"
        assert np.array_equal(np.isnan(mine), np.isnan(theirs)), f"{name}: missing points"
        ok = ~np.isnan(theirs)
        assert np.array_equal(mine[ok], theirs[ok]), f"{name}: heights differ"
        got = (report["pixel_size_x_m"], report["pixel_size_y_m"])
        assert np.allclose(got, pixel, rtol=1e-12), f"{name}: pixel {got} against {pixel}"
        print(f"{name}: {mine.shape[0]} × {mine.shape[1]}, as numpy reads it "
              f"(SurfaceTopography refuses it: {refused})")
    # What their spectra resolve, said honestly: the confocal map's straightest power law is
    # steeper than any self-affine surface's (H > 1), so nothing is fitted and no pixel warning
    # is given; the AFM map is self-affine down to its pixel (H resolved, λ_s not), which is
    # warned of.
    for name, hurst, lambda_s, warned in [("x3p-2.x3p", False, False, False),
                                         ("matrix-3.txt", True, False, True)]:
        run = subprocess.run([BIN, "topography", "--input", at(name), "--json"],
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        fit = json.loads(run.stdout)["psd_fit"]
        assert (fit["hurst"] is not None, fit["lambda_s_m"] is not None) == (hurst, lambda_s), fit
        assert fit["not_resolved"], fit
        assert ("down to the pixel" in run.stderr) == warned, run.stderr
        assert "measure at a finer pixel" not in run.stderr, run.stderr
        print(f"{name}: PSD run H = {fit['run_hurst']:.2f}; not resolved: {fit['not_resolved'][0][:60]}…")
    refusals = [
        ("csv-1.csv", "a line scan (x, z): 8 points"),
        ("csv-2.csv", "a line scan (an increasing first column"),
        ("csv-3.csv", "a line scan (x, z): 8 points"),
        ("dektak-1.csv", "a line scan (x, z): 9600 points"),
        ("single_column.txt", "one column of 9 heights"),
        ("xy-1.txt", "a line scan (x, z): 132 points"),
        ("nonuniform.asc", "a line scan (x, z): 134 points"),
        ("nonsense_txt_file.txt", "no heights"),
        ("metropro-1.head.dat", "Zygo MetroPro (.dat): not read here; SurfaceTopography reads it"),
        ("wrongnpyfile.npy", "corrupted by a text conversion"),
    ]
    for name, said in refusals:
        path = at(name)
        run = subprocess.run([BIN, "topography", "--input", path], capture_output=True, text=True)
        assert run.returncode == 2, f"{name}: exit {run.returncode}, not 2: {run.stderr}"
        assert path in run.stderr and said in run.stderr, f"{name}: {run.stderr!r}"
        print(f"{name}: exit 2: {run.stderr.strip().splitlines()[-1][len(path) + 9:][:110]}")


instruments()
