"""Cross-check `asperity surface stats` against SurfaceTopography on its own public test files
with missing points (formats asperity does not read, e.g. FRT and Zygo OPD).

SurfaceTopography reads the file and writes its heights (NaN where undefined) as an asperity
.npy + .npy.json sidecar; asperity then computes the statistics of that file, and both sets of
numbers are printed side by side with their relative differences. Nothing here is committed
data: the input files come from the SurfaceTopography repository (test/file_format_examples/).

Usage: /tmp/st-venv/bin/python benches/peers/missing_points_public_files.py \
           target/release/asperity FILE [FILE ...]
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import SurfaceTopography
from SurfaceTopography import Topography, read_topography

exe = sys.argv[1]
rows = []
with tempfile.TemporaryDirectory() as tmp:
    for path in sys.argv[2:]:
        t0 = read_topography(path).to_unit("m")
        h = np.ma.filled(t0.heights(), np.nan).astype(float)
        nx, ny = h.shape
        sx, sy = t0.physical_sizes
        # asperity stores the spacing (sx / nx); its grid is nx * (sx / nx) long, which can
        # differ from sx in the last bit. SurfaceTopography's masked slope statistics depend on
        # that bit (see BENCHMARKS.md), so both codes are given the same grid.
        t = Topography(t0.heights(), (nx * (sx / nx), ny * (sy / ny)), periodic=t0.is_periodic, unit="m")
        npy = os.path.join(tmp, os.path.basename(path) + ".npy")
        np.save(npy, h)
        with open(npy + ".json", "w") as f:
            json.dump({"unit": "m", "dx_m": sx / nx, "dy_m": sy / ny, "periodic": bool(t.is_periodic)}, f)
        ours = json.loads(subprocess.run([exe, "surface", "stats", "--json", npy], check=True,
                                         capture_output=True, text=True).stdout)
        filled = json.loads(subprocess.run([exe, "surface", "stats", "--json", "--fill", "harmonic", npy],
                                           check=True, capture_output=True, text=True).stdout)
        ti = t.interpolate_undefined_data()
        peer = {
            "missing_points": int(np.ma.count_masked(t.heights())),
            "rq_m": float(t.rms_height_from_area()),
            "rms_gradient": float(t.rms_gradient()),
            "rms_slope": float(t.rms_slope_from_profile()),
            "filled_rms_gradient": float(ti.rms_gradient()),
        }
        mine = {
            "missing_points": ours["missing_points"],
            "rq_m": ours["rq_m"],
            "rms_gradient": ours["rms_gradient"],
            "rms_slope": ours["rms_slope"],
            "filled_rms_gradient": filled["rms_gradient"],
        }
        rel = {k: abs(mine[k] - peer[k]) / abs(peer[k]) for k in mine if k != "missing_points"}
        peer["rms_gradient_as_read"] = float(t0.rms_gradient())
        rows.append({"file": os.path.basename(path), "grid": [nx, ny], "surface_topography": peer,
                     "asperity": mine, "relative_difference": rel})
print(json.dumps({"SurfaceTopography": SurfaceTopography.__version__, "files": rows}, indent=1))
