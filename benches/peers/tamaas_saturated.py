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

Conventions as benches/peers/tamaas_compare.py: model E = E* with nu = 0, periodic kernel
2/(E*|q|). Output: per pressure the mean pressure, contact and plastic (p >= pmax) area ratios,
iterations, wall and CPU time (s). The tamaas 2.9 wheel solves on one thread.
Units: SI throughout.
"""
import json
import sys

import numpy as np
import tamaas as tm

from tamaas_compare import solve_counting


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
    pmax = case["hardness_pa"]
    solver = tm.KatoSaturated(model, h, case["tolerance"], pmax)
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
            wall, cpu, its = solve_counting(solver, p)
            best = min(best, wall)
            best_cpu = min(best_cpu, cpu)
            iterations = its
        trac = np.array(model.traction)
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
