"""Time SurfaceTopography on the same statistics as `asperity surface stats` (peer benchmark).

Usage: surface_stats.py HEIGHTS.npy   (spacing and periodicity from HEIGHTS.npy.json, asperity's
sidecar). Prints one JSON object: the values and the wall time of the statistics (rms height,
rms gradient, rms slope along x, autocorrelation, radially averaged PSD), best of REPEATS runs.
"""
import json
import sys
import time

import numpy as np
from SurfaceTopography import Topography

REPEATS = 3

path = sys.argv[1]
meta = json.load(open(path + ".json"))
h = np.load(path)
nx, ny = h.shape
t = Topography(h, (nx * meta["dx_m"], ny * meta["dy_m"]), periodic=meta["periodic"], unit="m")


def run():
    rq = t.rms_height_from_area()
    grad = t.rms_gradient()
    slope = t.rms_slope_from_profile()
    t.autocorrelation_from_area()
    t.power_spectrum_from_area()
    return rq, grad, slope


best = float("inf")
for _ in range(REPEATS):
    t0 = time.perf_counter()
    rq, grad, slope = run()
    best = min(best, time.perf_counter() - t0)
import SurfaceTopography

print(json.dumps({
    "version": SurfaceTopography.__version__,
    "stats_time_s": best,
    "rq_m": float(rq),
    "rms_gradient": float(grad),
    "rms_slope": float(slope),
}))
