#!/usr/bin/env python3
"""Run tamaas 2.9 (PolonskyKeerRey, pressure-controlled) on a surface exported by asperity.

Called by `cargo bench --bench normal` (benches/normal.rs) with the venv made by
benches/peers/setup.sh; can also be run by hand:

    /tmp/asperity-peers-venv/bin/python benches/peers/tamaas_compare.py CASE.json OUT.json

CASE.json (written by the Rust benchmark):
    surface_npy     path of the heights (m), float64 array of shape (nx, ny), periodic
    lx_m, ly_m      patch size (m)
    e_star_pa       composite modulus E* (Pa)
    tolerance       solver tolerance (the same number asperity uses)
    pressures_pa    imposed mean pressures (Pa)
    repeats         timed cold solves per pressure (the fastest wall and CPU times are reported)

Conventions (checked on a Westergaard wave): tamaas' model modulus E with nu = 0 makes its
hertz modulus E* = E/(1-nu^2) equal to E; its periodic kernel is 2/(E*|q|) like ours; the
solved displacement satisfies u - h = gap >= 0 (0 in contact), so tamaas' mean displacement
minus the mean height equals asperity's mean gap. Units: SI throughout.

Iterations: tamaas prints its last iteration (number, cost, error) to stderr at log level
`info` when `dump_freq` exceeds the iteration count; the script captures stderr (file
descriptor 2) around each solve and reads the number.

Threads: set OMP_NUM_THREADS before calling. The solver of the tamaas 2.9 wheel runs on one
thread whatever OMP_NUM_THREADS says (its CPU time equals its wall time; BENCHMARKS.md).
"""
import json
import os
import re
import sys
import tempfile
import time

import numpy as np
import tamaas as tm

ITERATION_LINE = re.compile(r"^\s*(\d+)\s+\S+\s+\S+\s*$")


def solve_counting(solver, p):
    """solver.solve(p), timed; returns (wall s, CPU s, iterations or None)."""
    with tempfile.TemporaryFile(mode="w+") as log:
        saved = os.dup(2)
        sys.stderr.flush()
        os.dup2(log.fileno(), 2)
        try:
            c0 = time.process_time()
            t0 = time.perf_counter()
            solver.solve(p)
            wall = time.perf_counter() - t0
            cpu = time.process_time() - c0
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
        log.seek(0)
        iterations = None
        for line in log:
            m = ITERATION_LINE.match(line)
            if m:
                iterations = int(m.group(1))
    return wall, cpu, iterations


def main(case_path, out_path):
    with open(case_path) as f:
        case = json.load(f)
    h = np.load(case["surface_npy"])
    nx, ny = h.shape
    tm.set_log_level(tm.LogLevel.info)
    model = tm.ModelFactory.createModel(
        tm.model_type.basic_2d, [case["lx_m"], case["ly_m"]], [nx, ny]
    )
    model.E = case["e_star_pa"]
    model.nu = 0.0
    assert abs(model.E_star / case["e_star_pa"] - 1.0) < 1e-12
    solver = tm.PolonskyKeerRey(model, h, case["tolerance"])
    solver.dump_freq = 10**9
    # tamaas stops silently after max_iter (default 1000) iterations: near full contact on
    # 2048² its Polonsky–Keer–Rey needs more, so the cap is lifted to compare converged solves.
    solver.max_iter = 100_000
    results = []
    for p in case["pressures_pa"]:
        best = best_cpu = float("inf")
        iterations = None
        for _ in range(case["repeats"]):
            model.traction[...] = 0.0
            model.displacement[...] = 0.0
            wall, cpu, its = solve_counting(solver, p)
            best = min(best, wall)
            best_cpu = min(best_cpu, cpu)
            iterations = its
        trac = np.array(model.traction)
        disp = np.array(model.displacement)
        results.append(
            {
                "pressure_pa": p,
                "mean_pressure_pa": float(trac.mean()),
                "contact_area_ratio": float((trac > 0).mean()),
                "mean_displacement_m": float(disp.mean()),
                "mean_gap_m": float((disp - h).mean()),
                "iterations": iterations,
                "time_s": best,
                "cpu_s": best_cpu,
            }
        )
    info = {"tamaas_version": tm.__version__, "results": results}
    with open(out_path, "w") as f:
        json.dump(info, f, indent=1)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: tamaas_compare.py CASE.json OUT.json")
    main(sys.argv[1], sys.argv[2])
