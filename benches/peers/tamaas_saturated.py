#!/usr/bin/env python3
"""Run tamaas 2.9's pressure-saturated solver (KatoSaturated) on a surface exported by asperity.

The peer of asperity's hardness-limited normal contact (`NormalProblem::hardness_pa`): the
contact pressure bounded by pmax = H, load-controlled. Called by tests/plastic_contact.rs and by
`cargo bench --bench normal -- --plastic` (benches/normal.rs) with the venv made by
benches/peers/setup.sh; can also be run by hand:

    /tmp/asperity-peers-venv/bin/python benches/peers/tamaas_saturated.py CASE.json OUT.json

CASE.json:
    surface_npy     path of the heights (m), float64 array of shape (nx, ny), periodic
    lx_m, ly_m      patch size (m)
    e_star_pa       composite modulus E* (Pa)
    hardness_pa     saturation pressure H (tamaas' pmax) (Pa)
    tolerance       tamaas' solver tolerance
    pressures_pa    imposed mean pressures (Pa)
    repeats         timed cold solves per pressure (the fastest wall and CPU times are reported)
    write_fields    optional: also write each pressure field as <OUT>.<k>.npy (for the test)

Conventions as benches/peers/tamaas_compare.py (model E = E* with nu = 0, periodic kernel
2/(E*|q|)), but solved in reduced units: lengths (patch and heights) over lx, pressures over E*,
so the model has E = 1 and the patch [1, ly/lx]. The elastic problem is invariant under that
scaling (p = E* u'/x'), and KatoSaturated needs it: on the SI problem (E = 1e11, a 1 mm patch) it
does not converge (its error stays at 3.04 for thousands of iterations and it ends in full
contact), while the reduced problem converges in a few thousand iterations. Output (SI): per
pressure the mean pressure, contact and plastic (p >= pmax) area ratios, iterations, wall and
CPU time (s). The tamaas 2.9 wheel solves on one thread.
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
    """solver.solve(p), timed; returns (wall s, CPU s, iterations or None).

    tamaas prints its iterations to stderr at log level `info` (file descriptor 2, captured
    here). KatoSaturated's solve runs its loop and then a short second one (each under its own
    "Iter" header): the iterations are the sum of the last iteration number of each.
    """
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
        blocks = []
        for line in log:
            if line.strip().startswith("Iter"):
                blocks.append(0)
            m = ITERATION_LINE.match(line)
            if m and blocks:
                blocks[-1] = int(m.group(1))
    return wall, cpu, (sum(blocks) if blocks else None)


def main(case_path, out_path):
    with open(case_path) as f:
        case = json.load(f)
    lx = case["lx_m"]
    e_star = case["e_star_pa"]
    h = np.load(case["surface_npy"]) / lx
    nx, ny = h.shape
    tm.set_log_level(tm.LogLevel.info)
    model = tm.ModelFactory.createModel(
        tm.model_type.basic_2d, [1.0, case["ly_m"] / lx], [nx, ny]
    )
    model.E = 1.0
    model.nu = 0.0
    assert abs(model.E_star - 1.0) < 1e-12
    pmax = case["hardness_pa"]
    solver = tm.KatoSaturated(model, h, case["tolerance"], pmax / e_star)
    solver.dump_freq = 10**9
    # tamaas stops silently after max_iter (default 1000) iterations: lifted to compare
    # converged solves.
    solver.max_iter = 1_000_000
    results = []
    for k, p in enumerate(case["pressures_pa"]):
        best = best_cpu = float("inf")
        iterations = None
        for _ in range(case["repeats"]):
            model.traction[...] = 0.0
            model.displacement[...] = 0.0
            wall, cpu, its = solve_counting(solver, p / e_star)
            best = min(best, wall)
            best_cpu = min(best_cpu, cpu)
            iterations = its
        trac = np.array(model.traction) * e_star
        entry = {
            "pressure_pa": p,
            "mean_pressure_pa": float(trac.mean()),
            "contact_area_ratio": float((trac > 0).mean()),
            "plastic_area_ratio": float((trac >= pmax).mean()),
            "max_pressure_pa": float(trac.max()),
            "iterations": iterations,
            "time_s": best,
            "cpu_s": best_cpu,
        }
        if case.get("write_fields"):
            path = f"{out_path}.{k}.npy"
            np.save(path, trac)
            entry["pressure_npy"] = path
        results.append(entry)
    info = {"tamaas_version": tm.__version__, "solver": "KatoSaturated", "results": results}
    with open(out_path, "w") as f:
        json.dump(info, f, indent=1)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: tamaas_saturated.py CASE.json OUT.json")
    main(sys.argv[1], sys.argv[2])
