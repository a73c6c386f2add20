"""Reference values for topographies with missing points, from SurfaceTopography (the peer).

Writes three small test files of our own into surfaces/ (deterministic, no randomness) and
prints, for each, the statistics SurfaceTopography computes on it, as JSON. tests/surface_missing.rs
asserts `asperity surface stats` against these numbers to 1e-9; the numbers are pasted there with
this command:

    benches/peers/setup_surfacetopography.sh /tmp/st-venv
    /tmp/st-venv/bin/python benches/peers/missing_points_reference.py surfaces

Files (heights in m unless the header says otherwise):
- missing-points.x3p: ISO 25178-72 container, 40 x 32 points, uint16 heights (CZ Increment
  1 nm, Offset -2 um) with a validity mask bindata/valid.bin (one bit per point, least
  significant bit first, 1 = valid): an elliptic hole, a notch at the border, single points.
- missing-points-matrix.csv: asperity height matrix (nm), 36 x 28, non-periodic, `nan` = missing.
- missing-points-periodic.csv: asperity height matrix (um), 24 x 20, periodic, `nan` = missing.
- missing-points-profile.csv: uniform profile `x_um,height_nm`, 200 points, `nan` = missing.

SurfaceTopography reads the x3p itself (its own reader, validity mask included); the text files
are parsed here exactly as asperity parses them (decimal text to float64, then times the unit)
and handed to its Topography / UniformLineScan constructors with physical size n * spacing.
"""
import hashlib
import json
import math
import os
import sys
import zipfile

import numpy as np
import SurfaceTopography
from SurfaceTopography import Topography, UniformLineScan, read_topography

out = sys.argv[1] if len(sys.argv) > 1 else "surfaces"


def field(nx, ny, a, b):
    """A smooth, non-periodic test field (dimensionless, order 1)."""
    i = np.arange(nx).reshape(-1, 1)
    j = np.arange(ny).reshape(1, -1)
    return (np.sin(a * i + 0.3) * np.cos(b * j - 0.2) + 0.35 * np.sin(0.9 * i + 1.3 * j)
            + 0.02 * i - 0.015 * j + 0.1 * ((i * 7 + j * 3) % 5))


def mask(nx, ny, cx, cy, rx, ry):
    """True where the point is missing: an ellipse, a notch at x = 0, three single points."""
    i = np.arange(nx).reshape(-1, 1)
    j = np.arange(ny).reshape(1, -1)
    m = ((i - cx) / rx) ** 2 + ((j - cy) / ry) ** 2 <= 1.0
    m = m | ((i <= 1) & (j >= ny // 2) & (j < ny // 2 + 4))
    for p in [(nx - 1, 0), (3, ny - 2), (nx // 2, 1)]:
        m[p] = True
    return m


def write_x3p(path):
    nx, ny = 40, 32
    # Raw values stay below 2^15: SurfaceTopography 1.27 reads larger uint16 values as negative.
    raw = np.round(8000 + 1500 * field(nx, ny, 0.31, 0.23)).astype("<u2")
    assert raw.min() > 0 and raw.max() < 2**15
    missing = mask(nx, ny, 24, 14, 4.5, 3.2)
    raw[missing] = 0  # arbitrary: the validity mask says these are missing
    data = raw.T.tobytes()  # x fastest
    valid = np.packbits(~missing.T.reshape(-1), bitorder="little").tobytes()
    xml = f"""<?xml version="1.0" encoding="UTF-8" standalone="no" ?>
<p:ISO5436_2 xmlns:p="http://www.opengps.eu/2008/ISO5436_2">
  <Record1>
    <Revision>ISO5436 - 2000</Revision>
    <FeatureType>SUR</FeatureType>
    <Axes>
      <CX><AxisType>I</AxisType><DataType>D</DataType><Increment>2.5e-07</Increment><Offset>0</Offset></CX>
      <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>3e-07</Increment><Offset>0</Offset></CY>
      <CZ><AxisType>A</AxisType><DataType>I</DataType><Increment>1e-09</Increment><Offset>-2e-06</Offset></CZ>
    </Axes>
  </Record1>
  <Record2>
    <Date>2024-01-01T00:00:00Z</Date>
    <Instrument><Manufacturer>asperity test</Manufacturer><Model>synthetic</Model><Serial>not available</Serial><Version>1</Version></Instrument>
    <CalibrationDate>2024-01-01T00:00:00Z</CalibrationDate>
    <ProbingSystem><Type>Software</Type><Identification>missing_points_reference.py</Identification></ProbingSystem>
    <Comment>synthetic map with missing points for tests</Comment>
  </Record2>
  <Record3>
    <MatrixDimension><SizeX>{nx}</SizeX><SizeY>{ny}</SizeY><SizeZ>1</SizeZ></MatrixDimension>
    <DataLink>
      <PointDataLink>bindata/data.bin</PointDataLink>
      <MD5ChecksumPointData>{hashlib.md5(data).hexdigest().upper()}</MD5ChecksumPointData>
      <ValidPointsLink>bindata/valid.bin</ValidPointsLink>
      <MD5ChecksumValidPoints>{hashlib.md5(valid).hexdigest().upper()}</MD5ChecksumValidPoints>
    </DataLink>
  </Record3>
  <Record4><ChecksumFile>md5checksum.hex</ChecksumFile></Record4>
</p:ISO5436_2>
"""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("main.xml", xml)
        z.writestr("bindata/data.bin", data)
        z.writestr("bindata/valid.bin", valid)
        z.writestr("md5checksum.hex", hashlib.md5(xml.encode()).hexdigest() + " *main.xml\n")
    return int(missing.sum())


def write_matrix(path, nx, ny, unit, dx, dy, periodic, scale, a, b, hole):
    h = scale * field(nx, ny, a, b)
    missing = mask(nx, ny, *hole)
    with open(path, "w") as f:
        f.write("# asperity height matrix with missing points (nan), for tests\n")
        f.write(f"# unit: {unit}, dx_m: {dx!r}, dy_m: {dy!r}, periodic: {str(periodic).lower()}\n")
        f.write(f"# rows: y (j = 0..{ny - 1}), columns: x (i = 0..{nx - 1})\n")
        for j in range(ny):
            f.write(",".join("nan" if missing[i, j] else f"{h[i, j]:.6f}" for i in range(nx)) + "\n")


def read_matrix(path):
    """Parse as asperity does: decimal text to float64, times the unit."""
    unit = dx = dy = None
    periodic = False
    rows = []
    factors = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "nm": 1e-9}
    for line in open(path):
        line = line.strip()
        if line.startswith("#"):
            for part in line[1:].split(","):
                if ":" in part:
                    k, v = (t.strip() for t in part.split(":", 1))
                    if k == "unit":
                        unit = factors[v]
                    elif k == "dx_m":
                        dx = float(v)
                    elif k == "dy_m":
                        dy = float(v)
                    elif k == "periodic":
                        periodic = v == "true"
            continue
        if line:
            rows.append([float(t) for t in line.split(",")])
    h = np.array(rows).T * unit  # rows are y
    nx, ny = h.shape
    return Topography(h, (nx * dx, ny * dy), periodic=periodic, unit="m")


def write_profile(path):
    n = 200
    x = np.arange(n)
    z = 40.0 * np.sin(0.11 * x) + 15.0 * np.cos(0.37 * x + 0.5) + 0.2 * x
    missing = np.zeros(n, bool)
    missing[[0, 57, 58, 59, 120, 199]] = True
    missing[150:156] = True
    with open(path, "w") as f:
        f.write("# uniform profile with missing points (nan), for tests\n")
        f.write("x_um,height_nm\n")
        for k in range(n):
            f.write(f"{k * 0.5:.1f}," + ("nan" if missing[k] else f"{z[k]:.4f}") + "\n")


def read_profile(path):
    xs, zs = [], []
    for line in open(path):
        line = line.strip()
        if not line or line.startswith("#") or line.startswith("x_"):
            continue
        a, b = line.split(",")
        xs.append(float(a) * 1e-6)
        zs.append(float(b) * 1e-9)
    n = len(xs)
    d = (xs[-1] - xs[0]) / (n - 1)
    return UniformLineScan(np.array(zs), n * d, periodic=False, unit="m")


def stats(t):
    r = {"missing_points": int(np.ma.count_masked(t.heights()))}
    filled = t.interpolate_undefined_data()
    if t.dim == 2:
        r["rq_m"] = float(t.rms_height_from_area())
        r["rms_gradient"] = float(t.rms_gradient())
        r["rms_slope"] = float(t.rms_slope_from_profile())
        r["filled_rq_m"] = float(filled.rms_height_from_area())
        r["filled_rms_gradient"] = float(filled.rms_gradient())
        r["filled_rms_slope"] = float(filled.rms_slope_from_profile())
    else:
        r["rq_m"] = float(t.rms_height_from_profile())
        r["rms_slope"] = float(t.rms_slope_from_profile())
        r["filled_rq_m"] = float(filled.rms_height_from_profile())
        r["filled_rms_slope"] = float(filled.rms_slope_from_profile())
    return r


os.makedirs(out, exist_ok=True)
p_x3p = os.path.join(out, "missing-points.x3p")
p_mat = os.path.join(out, "missing-points-matrix.csv")
p_per = os.path.join(out, "missing-points-periodic.csv")
p_pro = os.path.join(out, "missing-points-profile.csv")
write_x3p(p_x3p)
write_matrix(p_mat, 36, 28, "nm", 5e-07, 7.5e-07, False, 120.0, 0.27, 0.19, (12, 18, 3.5, 4.5))
write_matrix(p_per, 24, 20, "um", 1e-06, 1e-06, True, 0.8, 2 * math.pi / 24 * 2, 2 * math.pi / 20,
             (5, 6, 2.2, 2.8))
write_profile(p_pro)

result = {
    "SurfaceTopography": SurfaceTopography.__version__,
    "numpy": np.__version__,
    "missing-points.x3p": stats(read_topography(p_x3p)),
    "missing-points-matrix.csv": stats(read_matrix(p_mat)),
    "missing-points-periodic.csv": stats(read_matrix(p_per)),
    "missing-points-profile.csv": stats(read_profile(p_pro)),
}
print(json.dumps(result, indent=1))
